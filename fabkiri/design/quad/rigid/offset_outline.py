"""Square/circle closed-state outlines in the parallelogram-hole rigid family (``offsets.py``).

The same problem as ``outline.py`` (an exact square, a size-free least-squares circle) with one more unknown
per hole, its offset: the additive-kirigami demo's freedom, which the rhombus family lacks (a 5x5 square to
circle ends at 3.7 % circle RMS there whatever the start, with no inequality active).

State 1's outline does not depend on the offsets (the boundary rows of ``A(t)`` involve boundary nodes
only), so a square there is the same linear equality on the seeds as in the rhombus family and is made
exact the same way: ``S = S₀ + N u``. State 2 is ``J W Z(t) S``, nonlinear in the offsets only through the
sparse solve for ``Z(t)``. The unknowns ``(u, t, o, R)`` are found by the outline solver's Levenberg–Marquardt
on circle fit + w·E_reg + ρ|min(0, g − m)|², with two inequality rows per hole keeping |t| < 1
(the hole's merge corners strictly inside its slit; ``T_SOFT``, ``T_HARD``).
"""

from __future__ import annotations

from types import SimpleNamespace
from typing import TYPE_CHECKING

import numpy as np

from ..closed_families import ClosedGrid
from .outline import (
    PSI_DEPLOYED,
    REG_WEIGHT,
    active_rows,
    lm_stages,
    outline_kind,
    outline_space,
    square_affine,
)

if TYPE_CHECKING:
    from .offsets import OffsetFamily

# |t| above T_SOFT is penalised like any inequality inside its margin; T_HARD is never crossed (step
# limiting). A hard wall alone at the soft bound left LM halving every step that touched it: 5x5 ended at
# 3.3 % circle RMS with offsets stuck on it
T_SOFT, T_HARD = 0.9, 0.98
# (penalty, stall tolerance, iteration cap). The first stage's cap trades time for fit (square->circle,
# vertices only, 7x7 at 60/120/200 iterations: 0.96/0.78/0.59 %, the time growing with the cap)
STAGES = ((1e2, 1e-5, 120), (1e4, 1e-6, 10))
# Above this many tiles the rhombus members take it: an iteration grows costly and the offsets
# gain little there (square->circle 17x17: 0.239 % against the rhombus family's 0.25 %;
# 13x13: 0.41 % against 0.43 %), while at 9x9 they take 0.95 % to 0.53 % and at 5x5 3.7 % to 0.23 %.
OFFSET_MAX_TILES = 11 * 11
MID_WEIGHT = 1.0  # 5x5: vertex RMS 1.61 %, Hausdorff 1.06 %; at 0.5: 1.28 % but Hausdorff 2.03 % (the outline's
# edges cut inside the circle); without midpoints 0.21 % but Hausdorff 8.7 % (vertices bunched, long chords)


def covers(req) -> bool:
    """A rigid parallelogram-hole design of square/circle closed-state outlines only."""
    # a square only in state 1: there it is linear in the seeds (state 2's outline moves with the offsets)
    return (
        req.rigid
        and req.holes == "parallelogram"
        and not req.symmetry
        and req.target is None
        and bool(req.contracted)
        and all(outline_kind(v) for v in req.contracted.values())
        and all(outline_kind(v) != "square" or s == 1 for s, v in req.contracted.items())
    )


def applies(req) -> bool:
    """``covers(req)`` at a size where the offsets are worth their cost (``OFFSET_MAX_TILES``)."""
    return covers(req) and req.rows * req.cols <= OFFSET_MAX_TILES


def preferred_holes(rows: int, cols: int, rigid: bool, symmetry, target, contracted: dict) -> str:
    """The hole shape when the user gives none: parallelogram where this solver applies, else rhombus."""
    r = SimpleNamespace(
        rows=rows,
        cols=cols,
        rigid=rigid,
        symmetry=symmetry,
        target=target,
        contracted=contracted,
        holes="parallelogram",
    )  # the request's fields that ``applies`` reads
    return "parallelogram" if applies(r) else "rhombus"


def _reps(st, state: int) -> tuple[np.ndarray, ClosedGrid]:
    """One node at every grid vertex of the closed state, and the grid."""
    g = ClosedGrid.build(st, state, 0)
    rep = np.empty(g.n_vertices, dtype=np.int64)
    rep[g.vertex.ravel()] = st.tiles.ravel()
    return rep, g


def closed_grid(fam: OffsetFamily, st, y: np.ndarray, state: int) -> np.ndarray:
    """Grid vertices of a closed state: the mean of the nodes at each (merge corners of a hole differ by
    its offset; boundary vertices are exact)."""
    g = ClosedGrid.build(st, state, 0)
    pos = y if state == 1 else fam.at(y, np.pi / 2)
    acc = np.zeros((g.n_vertices, 2))
    cnt = np.zeros(g.n_vertices)
    np.add.at(acc, g.vertex.ravel(), pos[st.tiles.ravel()])
    np.add.at(cnt, g.vertex.ravel(), 1.0)
    return acc / cnt[:, None]


def _start_seeds(prob, fam: OffsetFamily, t0: np.ndarray):
    """The rhombus member nearest the initial guess (least squares over the deployed nodes), centred:
    ``(vec S, Z0, rep1, g1)`` with ``Z0`` the state-1 map of the zero offsets ``t0``."""
    st, nf, n = prob.st, fam.n_seeds, prob.n
    _, Z0, _ = fam.state1(np.zeros((nf, 2)), t0, jac=True)
    c, s_ = np.cos(PSI_DEPLOYED), np.sin(PSI_DEPLOYED)
    WZ = fam.W @ Z0
    Kx = np.block([[c * Z0, -s_ * WZ], [s_ * WZ, c * Z0]])
    sol = np.linalg.lstsq(Kx, np.concatenate([prob.X0[:n, 0], prob.X0[:n, 1]]), rcond=None)[0]
    rep1, g1 = _reps(st, 1)
    # centred on the origin like the square rows (a translation of state 1 is a member's rigid motion; the
    # orthogonal projection onto the square rows is not, and would fold tiles when far off)
    y0 = Z0 @ np.stack([sol[:nf], sol[nf:]], -1)
    lo, hi = y0[rep1[g1.boundary]].min(0), y0[rep1[g1.boundary]].max(0)
    return sol - np.repeat(0.5 * (lo + hi), nf), Z0, rep1, g1  # vec S = (Sx, Sy)


def _square_rows(
    prob, nf: int, Z0: np.ndarray, rep1: np.ndarray, g1, states: list, kinds: dict, log
) -> tuple[list[np.ndarray], list[np.ndarray]] | None:
    """The linear rows ``E vec S = e`` of a square state-1 outline, or None for a square in state 2."""
    st = prob.st
    E, e = [], []
    for s in states:
        if kinds[s] == "square":
            if s != 1:
                log(
                    "offset outline: a square in state 2 is not linear in the seeds; rhombus holes take it"
                )
                return None
            lo, hi = prob.curves_mm[s].bbox
            half = 0.5 * float((hi - lo).max()) / prob.L0
            gi, gj = np.divmod(np.arange(g1.n_vertices), st.cols + 1)
            zr = np.zeros_like(Z0)
            for on, xy, val in [
                (gi == 0, 1, -half),
                (gi == st.rows, 1, half),
                (gj == 0, 0, -half),
                (gj == st.cols, 0, half),
            ]:
                Zs = Z0[rep1[on]]
                E.append(
                    np.hstack([Zs, zr[rep1[on]]]) if xy == 0 else np.hstack([zr[rep1[on]], Zs])
                )
                e.append(np.full(int(on.sum()), val))
    return E, e


def solve_offset_outline(prob, log, iters: dict, t_start=None):
    """``(X, mode, fitted)`` like ``outline.solve_outline`` (X: deployed nodes at ψ = π/4, then each target
    state's grid), or None when a square cannot be exact."""
    # loaded here: the offsets' family is this solver's alone, and it applies to few requests (``applies``)
    from .offsets import OffsetFamily

    req, st = prob.req, prob.st
    fam = OffsetFamily.build(st, prob.std.topology.spanning_tree(0))
    states = sorted(prob.grids)
    kinds = {s: outline_kind(req.contracted[s]) for s in states}
    t0 = np.zeros(fam.n_holes)
    s0, Z0, rep1, g1 = _start_seeds(prob, fam, t0)
    rows = _square_rows(prob, fam.n_seeds, Z0, rep1, g1, states, kinds, log)
    if rows is None:
        return None
    space = outline_space(
        square_affine(*rows, 2 * fam.n_seeds),
        states,
        kinds,
        log,
        "offset outline: the square rows are inconsistent",
    )
    if space is None:
        return None
    base, Nsp, circles, relative = space
    op = _OffsetOutline(prob, fam, base, Nsp, circles, relative, rep1)
    # circle start from the start member's algebraic circle
    if t_start is not None:
        t0 = np.asarray(t_start, dtype=float)
    p = op.start(Nsp.T @ (s0 - base), t0)
    log(f"offset outline start: violation {op.viol(op.nodes(p)):.2e}")
    p = lm_stages(op.evaluate, op.viol, op.nodes, p, STAGES, "offset_outline", iters, log)
    y = op.member(p, False)
    X = op.deployed(y)
    for s_, g in prob.grids.items():
        X[g.offset : g.offset + g.n_vertices] = closed_grid(fam, st, y, s_)
    # the stored circle is the outline's own: the geometric least-squares circle of its vertices (the
    # solver's circle also saw the edge midpoints)
    fitted = {s: _lsq_circle(op.states_of(y)[s][op.bnodes[s]]) for s in circles}
    prob.offsets = p[op.k : op.k + op.K].copy()
    log(
        f"offsets: |t| max {np.abs(prob.offsets).max():.3f}, mean {np.abs(prob.offsets).mean():.3f}"
    )
    return X, "least-squares" if circles else "hard", fitted


class _OffsetOutline:
    """The least-squares problem in ``p = (u, t, (o, R) per circle)``: seeds ``S = base + N u`` (the square
    rows' solution space), offsets ``t``, and each circle's centre and radius."""

    def __init__(
        self,
        prob,
        fam: OffsetFamily,
        base: np.ndarray,
        Nsp: np.ndarray,
        circles: list,
        relative: bool,
        rep1: np.ndarray,
    ):
        st = prob.st
        self.prob, self.fam, self.base, self.Nsp = prob, fam, base, Nsp
        self.nf, self.K, self.n, self.k = fam.n_seeds, fam.n_holes, prob.n, Nsp.shape[1]
        self.circles, self.relative = circles, relative
        rep2, _ = _reps(st, 2)
        M, N = st.rows, st.cols
        idx = np.arange((M + 1) * (N + 1)).reshape(M + 1, N + 1)
        ring = np.concatenate([idx[0, :-1], idx[:-1, -1], idx[-1, :0:-1], idx[:0:-1, 0]])
        self.bnodes = {s: (rep1 if s == 1 else rep2)[ring] for s in circles}
        # the circle's points: the outline's vertices (in ring order) and, weighted by MID_WEIGHT, its edge
        # midpoints, so that the vertices also spread round the circle
        B = len(ring)
        self.P = np.vstack([np.eye(B), MID_WEIGHT * 0.5 * (np.eye(B) + np.roll(np.eye(B), 1, 1))])
        self.wts = np.r_[np.ones(B), np.full(B, MID_WEIGHT)]
        self.fams_reg, self.fams_ineq, self.margin = prob.of("reg"), prob.of("ineq"), prob.margin
        self.w = np.sqrt(REG_WEIGHT)
        self.R0: dict = {}
        self.npar = 0
        self._member: tuple[bytes, np.ndarray] | None = None

    def seeds(self, p):
        v = self.base + self.Nsp @ p[: self.k]
        return np.stack([v[: self.nf], v[self.nf :]], -1)

    def member(self, p, jac):
        if jac:
            return self.fam.state1(self.seeds(p), p[self.k : self.k + self.K], jac=True)
        # the last one is kept: LM's step limiting (``nodes``) and its trial rows ask for the same member
        key = np.asarray(p, dtype=float).tobytes()
        if self._member is None or self._member[0] != key:
            y = self.fam.state1(self.seeds(p), p[self.k : self.k + self.K])
            y.flags.writeable = False  # shared by the callers
            self._member = (key, y)
        return self._member[1]

    def states_of(self, y):
        return {1: y, 2: self.fam.at(y, np.pi / 2)}

    def deployed(self, y):
        X = np.zeros((self.prob.nv, 2))
        X[: self.n] = self.fam.at(y, PSI_DEPLOYED)
        return X

    def nodes(self, p):
        """What the step limiting checks: the deployed nodes and the offsets."""
        return self.deployed(self.member(p, False)), p[self.k : self.k + self.K]

    def viol(self, Xt):
        X, t = Xt
        g = min((float(f.residual(X).min(initial=0.0)) for f in self.fams_ineq), default=0.0)
        return max(0.0, -g, float(np.abs(t).max(initial=0.0)) - T_HARD)

    def start(self, u0: np.ndarray, t0: np.ndarray) -> np.ndarray:
        """The start ``p``: each circle the algebraic circle of the start member's outline (sets ``R0``)."""
        y0 = self.member(np.r_[u0, t0], False)
        p0 = [u0, t0]
        for s in self.circles:
            q = self.states_of(y0)[s][self.bnodes[s]]
            A = np.c_[2 * q, np.ones(len(q))]
            so = np.linalg.lstsq(A, (q * q).sum(1), rcond=None)[0]
            self.R0[s] = float(np.sqrt(so[2] + so[:2] @ so[:2]))
            p0.append(np.array([so[0], so[1], self.R0[s]]))
        p = np.concatenate(p0)
        self.npar = len(p)
        return p

    def dmember(self, Z, Dt):
        """``∂y/∂(u, t)`` and ``J W ∂y/∂(u, t)``, each ``(V, 2, k + K)``: closed state 1 and closed state 2;
        the deployed nodes at ψ are ``cos ψ`` and ``sin ψ`` times them."""
        V, k, nf = Z.shape[0], self.k, self.nf
        Dy = np.concatenate([Z @ self.Nsp[:nf], Z @ self.Nsp[nf:]], 1).reshape(V, 2, k)
        Dy = np.concatenate([Dy, Dt], 2)
        WD = (self.fam.W @ Dy.reshape(V, -1)).reshape(Dy.shape)
        return Dy, np.stack([-WD[:, 1], WD[:, 0]], 1)

    def _circle_rows(self, p, st_pos, D1, D2, jac, rs, Js):
        """Each circle's weighted point-to-circle distances (relative to the start radius when no square fixes
        the size), appended to ``rs`` and ``Js``."""
        k, K, npar, P, wts = self.k, self.K, self.npar, self.P, self.wts
        off = k + K
        for s in self.circles:
            q = (P @ st_pos[s][self.bnodes[s]]) / wts[:, None]
            o, R = p[off : off + 2], p[off + 2]
            d = q - o
            dist = np.sqrt((d * d).sum(1))
            a = wts * (self.R0[s] / R if self.relative else 1.0)
            rs.append(a * (dist - R))
            if jac:
                unit = d / dist[:, None]
                Dq = np.einsum(
                    "pb,bdk->pdk", P / wts[:, None], (D2 if s == 2 else D1)[self.bnodes[s]]
                )
                J = np.zeros((len(q), npar))
                J[:, : k + K] = a[:, None] * np.einsum("bd,bdk->bk", unit, Dq)
                J[:, off : off + 2] = -a[:, None] * unit
                J[:, off + 2] = -wts * self.R0[s] * dist / R**2 if self.relative else -wts
                Js.append(J)
            off += 3

    def evaluate(self, p, rho, jac=True):
        """``((X, t), r, J)``: circle rows, the regulariser, active inequalities and the offsets' soft bound."""
        k, K, n, npar = self.k, self.K, self.n, self.npar
        if jac:
            y, Z, Dt = self.member(p, True)
        else:
            y = self.member(p, False)
        X = self.deployed(y)
        rs: list = []
        Js: list = []
        D1, D2 = self.dmember(Z, Dt) if jac else (None, None)
        self._circle_rows(p, self.states_of(y), D1, D2, jac, rs, Js)
        Dd = (
            (np.cos(PSI_DEPLOYED) * D1 + np.sin(PSI_DEPLOYED) * D2).reshape(2 * len(y), -1)
            if jac
            else None
        )
        pad = npar - k - K
        w = self.w
        for f in self.fams_reg:
            if jac:
                r, Jx = f(X)
                Js.append(np.hstack([w * (Jx[:, : 2 * n] @ Dd), np.zeros((len(r), pad))]))
            else:
                r = f.residual(X)
            rs.append(w * r)
        sq = np.sqrt(rho)
        active_rows(
            self.fams_ineq,
            self.margin,
            X,
            sq,
            jac and (lambda Jx: Jx[:, : 2 * n] @ Dd),
            pad,
            rs,
            Js,
        )
        t = p[k : k + K]
        v = np.r_[T_SOFT - t, T_SOFT + t]
        act = v < 0
        rs.append(sq * v[act])
        if jac and act.any():
            Jt = np.zeros((2 * K, npar))
            Jt[np.arange(K), k + np.arange(K)] = -1.0
            Jt[K + np.arange(K), k + np.arange(K)] = 1.0
            Js.append(sq * Jt[act])
        return (X, t), np.concatenate(rs), (np.vstack(Js) if jac else None)


def _lsq_circle(q: np.ndarray, iters: int = 50) -> tuple[np.ndarray, float]:
    """Geometric least-squares circle through ``q``: Gauss-Newton on the centre from the algebraic circle
    (for a given centre the best radius is the mean distance)."""
    c = np.linalg.lstsq(np.c_[2 * q, np.ones(len(q))], (q * q).sum(1), rcond=None)[0][:2]
    for _ in range(iters):
        d = q - c
        dist = np.sqrt((d * d).sum(1))
        J = -d / dist[:, None]
        step = np.linalg.lstsq(J - J.mean(0), -(dist - dist.mean()), rcond=None)[0]
        c = c + step
        if np.abs(step).max() <= 1e-14 * dist.mean():
            break
    return c, float(np.sqrt(((q - c) ** 2).sum(1)).mean())
