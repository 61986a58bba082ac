"""Closed-state outline design inside the rigid family: the paper's "circling the square".

For ``--rigid`` with rhombus holes, no deployed target and closed-state targets that are each a square or
a circle, both closed states are linear in the rigid family's seeds ``S`` (``family.py``): closed state 1 is
the grid ``c₁ = Z S``, closed state 2 the member at ψ = π/2, ``c₂ = J Y S`` at one node per grid vertex.
So every equality family holds by construction, and

* a **square** outline is a set of linear equalities on ``S`` (each boundary vertex on its side of the
  axis-aligned square of the target's side, centred on the origin): the seeds are restricted to that
  affine subspace, ``S = S₀ + N u``, and the square holds to rounding — exact, not fitted;
* a **circle** outline is size-free: the residuals are ``|c_i − o| − R`` over the state's boundary
  vertices with the centre ``o`` and radius ``R`` unknowns — the geometric least-squares circle of the
  outline. Without a square to fix the scale they are taken relative to R, ``R₀ (|c_i − o| / R − 1)``
  (``R₀``, the start's radius, sets the units), or shrinking the pattern would fit any circle.

What is left — ``u``, ``o``, ``R`` — is minimised by Levenberg–Marquardt with a dense normal matrix on
circle fit + w·E_reg + ρ|min(0, g − m)|² (the deployed tiles at ψ = π/4, the closed-state grids'
orientation), with the same step limiting on the inequalities as the other solvers. A square that cannot
be made exact (rank-deficient rows, e.g. a square in both states) is left to the full solver.
"""

from __future__ import annotations

import numpy as np

from ...core.lm import Damping, Stopping, levenberg_marquardt
from ...core.stencils import Stencils
from ...targets.curve import Target
from ..closed_families import ClosedGrid
from .family import RigidFamily

PSI_DEPLOYED = (
    np.pi / 4
)  # deployment angle of the written pattern (any member angle in (0, π/2) works)
STAGES = ((1e2, 1e-9, 200), (1e4, 1e-12, 100))  # (penalty, stall tolerance, iteration cap)
REG_WEIGHT = (
    1e-6  # the circle residuals are ~1e-2 of a tile: a regulariser at 1e-3 would outweigh them
)
SQUARE_TOL = 1e-12  # relative residual of the square rows that counts as feasible


def square_affine(
    E: list[np.ndarray], e: list[np.ndarray], n: int
) -> tuple[np.ndarray, np.ndarray] | None:
    """``(base, N)`` with every solution of the stacked square rows ``E x = e`` written
    ``base + N u`` (N an orthonormal null-space basis); the whole space when there are no rows,
    None when the rows are inconsistent (no exact square in this family)."""
    if not E:
        return np.zeros(n), np.eye(n)
    A, b = np.vstack(E), np.concatenate(e)
    U, sv, Vt = np.linalg.svd(A, full_matrices=True)
    rank = int((sv > 1e-10 * sv[0]).sum())
    base = Vt[:rank].T @ ((U[:, :rank].T @ b) / sv[:rank])
    if np.abs(A @ base - b).max() > SQUARE_TOL * max(1.0, np.abs(b).max()):
        return None
    return base, Vt[rank:].T


def outline_kind(spec) -> str | None:
    """ "square" or "circle" for closed-state targets this solver handles exactly, else None."""
    if isinstance(spec, Target) and spec.name in ("square", "circle"):
        return spec.name
    return None


def applies(req) -> bool:
    """``req`` (a ``solve.DesignRequest``) is a rigid rhombus design of square/circle closed-state outlines only."""
    return (
        req.rigid
        and req.holes == "rhombus"
        and not req.symmetry
        and req.target is None
        and bool(req.contracted)
        and all(outline_kind(v) for v in req.contracted.values())
    )


class _Maps:
    """Dense linear maps from ``vec S = (Sx, Sy)`` to the node array ``[deployed nodes; grids of the
    target states]`` that the families of ``solve.DesignProblem`` evaluate."""

    def __init__(self, fam: RigidFamily, st: Stencils, states: list[int]):
        M, N = st.rows, st.cols
        G = (M + 1) * (N + 1)
        nf = fam.n_seeds
        c, s = np.cos(PSI_DEPLOYED), np.sin(PSI_DEPLOYED)
        # node x = c Zn Sx − s Y Sy, y = c Zn Sy + s Y Sx (RigidFamily.nodes), rows interleaved x, y
        blocks = [
            np.stack([np.hstack([c * fam.Zn, -s * fam.Y]), np.hstack([s * fam.Y, c * fam.Zn])], 1)
        ]
        self.grid = {}
        for state in states:
            if state == 1:
                Zx, Zy = (
                    np.hstack([fam.Z, np.zeros_like(fam.Z)]),
                    np.hstack([np.zeros_like(fam.Z), fam.Z]),
                )
            else:  # closed state 2 = the member at ψ = π/2: x = −Y Sy, y = Y Sx at one node per grid vertex
                vid = ClosedGrid.build(st, 2, 0).vertex.ravel()
                rep = np.empty(G, dtype=np.int64)
                rep[vid] = st.tiles.ravel()
                Yr = fam.Y[rep]
                Zx, Zy = np.hstack([np.zeros_like(Yr), -Yr]), np.hstack([Yr, np.zeros_like(Yr)])
            self.grid[state] = (Zx, Zy)
            blocks.append(np.stack([Zx, Zy], 1))
        self.A = np.concatenate(blocks).reshape(-1, 2 * nf)  # (2 nv, 2 nf)
        self.nf = nf


def _square_rows(maps: _Maps, st: Stencils, state: int, half: float):
    """``E vec S = e``: every boundary vertex of the state's grid on its side of the square."""
    M, N = st.rows, st.cols
    gi, gj = np.divmod(np.arange((M + 1) * (N + 1)), N + 1)
    Zx, Zy = maps.grid[state]
    rows, rhs = [], []
    for on_side, coord, value in [
        (gi == 0, Zy, -half),
        (gi == M, Zy, half),
        (gj == 0, Zx, -half),
        (gj == N, Zx, half),
    ]:
        rows.append(coord[on_side])
        rhs.append(np.full(int(on_side.sum()), value))
    return np.vstack(rows), np.concatenate(rhs)


def _circle_residuals(maps: _Maps, st: Stencils, state: int):
    """Boundary vertices of the state's grid: ``(B, 2, 2 nf)`` maps from ``vec S``."""
    g = ClosedGrid.build(st, state, 0)
    Zx, Zy = maps.grid[state]
    return np.stack([Zx[g.boundary], Zy[g.boundary]], 1)


def _square_state_rows(
    prob, maps: _Maps, st: Stencils, states: list, kinds: dict
) -> tuple[list[np.ndarray], list[np.ndarray]]:
    """The square rows ``E vec S = e`` of every square target state (the side half-length in tile units)."""
    E, e = [], []
    for s in states:
        if kinds[s] == "square":
            lo, hi = prob.curves_mm[s].bbox
            half = 0.5 * float((hi - lo).max()) / prob.L0
            Es, es = _square_rows(maps, st, s, half)
            E.append(Es)
            e.append(es)
    return E, e


def solve_outline(prob, log, iters: dict):
    """Design in the rigid family for square/circle closed-state targets; ``(X, mode, fitted)`` or None
    when a square cannot be exact. ``fitted`` maps each circle state to its (centre, radius) in
    normalised units."""
    req, st = prob.req, prob.st
    fam: RigidFamily = prob.rigid_family
    states = sorted(prob.grids)
    maps = _Maps(fam, st, states)
    # the start: the member nearest the initial guess (standard pattern), its seeds
    S0, _ = fam.fit(prob.X0[: prob.n], PSI_DEPLOYED)
    s0 = np.concatenate([S0[:, 0], S0[:, 1]])
    kinds = {s: outline_kind(req.contracted[s]) for s in states}
    space = outline_space(
        square_affine(*_square_state_rows(prob, maps, st, states, kinds), 2 * maps.nf),
        states,
        kinds,
        log,
        "outline: the square rows are inconsistent; leaving the design to the full solver",
    )
    if space is None:
        return None
    base, Nsp, circles, relative = space
    op = _CircleOutline(prob, maps, st, base, Nsp, circles, relative)
    p = op.start(Nsp.T @ (s0 - base))
    p = lm_stages(op.evaluate, op.ineq_viol, op.nodes, p, STAGES, "outline", iters, log)
    X = op.nodes(p)
    fitted = {}
    off = op.k
    for s in circles:
        fitted[s] = (p[off : off + 2].copy(), float(p[off + 2]))
        off += 3
    return X, "least-squares" if circles else "hard", fitted


class _CircleOutline:
    """The least-squares problem in ``p = (u, (o, R) per circle)`` with seeds ``S = base + N u`` (the square
    rows' solution space): circle fit + w·E_reg + ρ|min(0, g − m)|², the deployed nodes linear in ``u``."""

    def __init__(
        self,
        prob,
        maps: _Maps,
        st: Stencils,
        base: np.ndarray,
        Nsp: np.ndarray,
        circles: list,
        relative: bool,
    ):
        self.k = Nsp.shape[1]
        self.AN = maps.A @ Nsp
        self.Ab = maps.A @ base
        self.circles, self.relative = circles, relative
        self.Bc = {
            s: np.einsum("bdf,fk->bdk", _circle_residuals(maps, st, s), Nsp) for s in circles
        }
        self.bc = {s: np.einsum("bdf,f->bd", _circle_residuals(maps, st, s), base) for s in circles}
        self.fams_reg = prob.of("reg")
        self.fams_ineq = prob.of("ineq")
        self.margin = prob.margin
        self.w = np.sqrt(REG_WEIGHT)
        self.R0: dict = {}

    def start(self, u0: np.ndarray) -> np.ndarray:
        """Circle unknowns (o_x, o_y, R) per circle state, started from the start's algebraic circle."""
        p0 = [u0]
        for s in self.circles:
            q = self.Bc[s] @ u0 + self.bc[s]
            A = np.c_[2 * q, np.ones(len(q))]
            sol = np.linalg.lstsq(A, (q * q).sum(1), rcond=None)[0]
            self.R0[s] = float(np.sqrt(sol[2] + sol[:2] @ sol[:2]))
            p0.append(np.array([sol[0], sol[1], self.R0[s]]))
        return np.concatenate(p0)

    def nodes(self, p):
        return (self.Ab + self.AN @ p[: self.k]).reshape(-1, 2)

    def ineq_viol(self, X):
        return max(
            0.0, -min((float(f.residual(X).min(initial=0.0)) for f in self.fams_ineq), default=0.0)
        )

    def _circle_rows(self, p, jac, rs, Js):
        k, R0, relative = self.k, self.R0, self.relative
        off = k
        for s in self.circles:
            q = self.Bc[s] @ p[:k] + self.bc[s]
            o, R = p[off : off + 2], p[off + 2]
            d = q - o
            dist = np.sqrt((d * d).sum(1))
            # with a square fixing the scale: the geometric least-squares circle, |c - o| - R; without, the
            # same relative to R (else shrinking the pattern would fit any circle)
            a = R0[s] / R if relative else 1.0
            rs.append(a * (dist - R))
            if jac:
                unit = d / dist[:, None]
                J = np.zeros((len(q), len(p)))
                J[:, :k] = a * np.einsum("bd,bdk->bk", unit, self.Bc[s])
                J[:, off : off + 2] = -a * unit
                J[:, off + 2] = -R0[s] * dist / R**2 if relative else -1.0
                Js.append(J)
            off += 3

    def evaluate(self, p, rho, jac=True):
        """``(X, r, J)``: circle rows, the regulariser and the active inequalities."""
        k, AN, w = self.k, self.AN, self.w
        X = self.nodes(p)
        rs: list = []
        Js: list = []
        self._circle_rows(p, jac, rs, Js)
        for f in self.fams_reg:
            r, Jx = f(X) if jac else (f.residual(X), None)
            rs.append(w * r)
            if jac:
                Js.append(np.hstack([w * (Jx @ AN), np.zeros((len(r), len(p) - k))]))
        active_rows(
            self.fams_ineq,
            self.margin,
            X,
            np.sqrt(rho),
            jac and (lambda Jx: Jx @ AN),
            len(p) - k,
            rs,
            Js,
        )
        r = np.concatenate(rs)
        return X, r, (np.vstack(Js) if jac else None)


def active_rows(
    fams_ineq, margin: dict, X: np.ndarray, sq: float, to_p, pad: int, rs: list, Js: list
) -> None:
    """Append ``sq·(g − m)`` of every inequality row inside its margin to ``rs`` and, unless ``to_p`` is
    False, its Jacobian in the unknowns to ``Js``: ``to_p`` maps the node Jacobian rows to the leading
    unknowns, ``pad`` zero columns follow for the rest."""
    for f in fams_ineq:
        v = f.residual(X) - margin[f.name]
        act = v < 0
        rs.append(sq * v[act])
        if to_p and act.any():
            _, Jx = f(X)
            Js.append(
                np.hstack([sq * to_p(Jx[np.flatnonzero(act)]), np.zeros((int(act.sum()), pad))])
            )


class _OutlinePoint:
    """An iterate ``p`` of an outline problem as the LM core's point (``lm.LMPoint``).

    A trial's rows are evaluated without their Jacobian (about 2 trials in 5 are refused, and the
    Jacobian is 4/5 of an evaluation); the first step from a point evaluates them again with it, and
    those rows then serve. Its violation is ``ineq_viol(nodes(p))`` (what the step limiting checks; the
    start's from the nodes ``evaluate`` returns).
    """

    def __init__(self, op: tuple, rho: float, p: np.ndarray, rows: tuple | None = None):
        self.op, self.rho, self.x, self._rows = op, rho, p, rows
        self._r: np.ndarray | None = None
        self._normal: np.ndarray | None = None
        evaluate, ineq_viol, nodes = op
        self.gviol = ineq_viol(rows[0] if rows is not None else nodes(p))

    def moved(self, p: np.ndarray) -> _OutlinePoint:
        return _OutlinePoint(self.op, self.rho, p)

    @property
    def rows(self) -> tuple:
        """``(X, r, J)`` with the Jacobian."""
        if self._rows is None:
            self._rows = self.op[0](self.x, self.rho)
        return self._rows

    @property
    def r(self) -> np.ndarray:
        if self._rows is not None:
            return self._rows[1]
        if self._r is None:
            self._r = self.op[0](self.x, self.rho, jac=False)[1]
        return self._r

    @property
    def JtJ(self) -> np.ndarray:
        if self._normal is None:
            J = self.rows[2]
            self._normal = J.T @ J
        return self._normal

    def step(self, mu: float) -> np.ndarray:
        """Marquardt scaling: the diagonal of JᵀJ (lifted off zero), over its mean."""
        JtJ = self.JtJ
        D = np.diag(JtJ) + 1e-12 * float(np.diag(JtJ).max())
        return -np.linalg.solve(JtJ + mu * np.diag(D / D.mean()), self.rows[2].T @ self.r)

    def predicted(self, dp: np.ndarray) -> float:
        Jdp = self.rows[2] @ dp
        return -(float(self.r @ Jdp) + 0.5 * float(Jdp @ Jdp))


def _lm(evaluate, ineq_viol, nodes, p, rho, max_iter, stall_tol):
    """Levenberg-Marquardt (Marquardt scaling) with step limiting on the inequalities, on the LM core.

    The damping starts at 1e-3 of JᵀJ's mean diagonal and follows the gain ratio (Nielsen) when a step
    is accepted, but a refused step raises it by a constant 4 (not a growing factor), up to 1e20.
    Returns ``p, iterations``.
    """
    op = (evaluate, ineq_viol, nodes)
    start = _OutlinePoint(op, rho, p, rows=evaluate(p, rho))
    mu0 = 1e-3 * max(float(np.diag(start.JtJ).mean()), 1e-30)
    pt, it = levenberg_marquardt(
        start,
        start.moved,
        Damping(mu0, 1e20, raise_by=4.0, raise_growth=1.0),
        Stopping(max_iter, stall_tol),
    )
    return pt.x, it


def lm_stages(evaluate, ineq_viol, nodes, p, stages, name: str, iters: dict, log) -> np.ndarray:
    """``_lm`` through the penalty ``stages`` (ρ, stall tolerance, cap), each stage's iterations in ``iters``
    as ``{name}_rho_{ρ}``."""
    for rho, stall_tol, cap in stages:
        p, it = _lm(evaluate, ineq_viol, nodes, p, rho, cap, stall_tol)
        iters[f"{name}_rho_{rho:g}"] = it
        log(
            f"{name.replace('_', ' ')} rho={rho:g}: {it} iterations, violation {ineq_viol(nodes(p)):.2e}"
        )
    return p


def outline_space(affine, states: list, kinds: dict, log, inconsistent: str):
    """``(base, N, circle states, relative)``: the square rows' solution space ``S = base + N u``, the states
    fitted to a circle, and whether their fit is relative (no square fixes the scale); None, logging
    ``inconsistent``, when the square rows have no solution (``affine`` None)."""
    if affine is None:
        log(inconsistent)
        return None
    base, Nsp = affine
    return (
        base,
        Nsp,
        [s for s in states if kinds[s] == "circle"],
        not any(kinds[s] == "square" for s in states),
    )
