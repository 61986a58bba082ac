"""Inverse design inside the closed-form rigid-deployable family (``family.py``).

For ``--rigid`` with rhombus holes every equality family (edge pairs of both
closed states, hinge sums) holds identically on the family ``x(S, ψ)``, so the
problem left is small and unconstrained but for the inequalities:

    min_p  |s(x)|² + w E_reg(x) + ρ |min(0, g(x) - m)|²,   x = x(p), p = (S, ψ),

with 2(M+N+2)+1 unknowns instead of 2V. It is solved by Levenberg-Marquardt
with dense reduced normal matrices (see ``_Merit``: the tile-shape rows live on
the closed-state-1 grid, the rest on the deployed nodes), with the same step
limiting on the inequalities as the full solver. Small lattices form the dense
reduced Jacobian directly (``TileShapeRows``: per tile corner, then pair
differences; inequality rows only where active), large ones by sparse blocks. When the fit
comes out nearly exact, minimum-norm Gauss-Newton steps on the fit rows make
it exact ("hard" shape matching). The caller (``solve.py``) checks every family
on the result and falls back to the full solver when a check fails.
"""

from __future__ import annotations

import copy
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy import sparse

from ...core.stencils import Family, StackedJacobian, Stencils
from ..constraints import exact_fits
from ..objective import tile_corners
from .contact import ClosedContact
from .family import EXACT_GRID, RigidFamily
from .merit import KeptGridBlock, _Evaluation, reduced_normal
from .mirror import Mirror, MirroredMerit, symmetric_member
from .steps import MAX_STALL, exact_fit, fit_miss, levenberg_marquardt, stage, stiffer_alone
from .tiles import TILE_SHAPE, TileShapeRows, grid_families

# (penalty weight, stall tolerance, iteration cap) per stage, softest first as in the full solver: a stiff
# inequality wall from the start leaves LM crawling along it (16x16 rigid circle: 300 iterations to a
# 1.3 mm fit at 1e4 alone, 74 to an exact fit from 1e2). Near an exact fit the tiny regulariser is
# minimised along the curved fit manifold, where LM crawls too: a stage stops after 3 steps in a row that
# each gain less than its stall tolerance, and the hard-fit projection finishes.
STAGES = ((1e2, 1e-3, 200), (1e4, 1e-6, 40))
# The first stage can run from two starts that differ only in LM's damping: Marquardt (diag JᵀJ) and
# Levenberg (identity) scaling reach different local minima, and neither is always better (rigid 16x16:
# heart 13.3 mm vs 0.43 mm, circle exact vs 0.04 mm). The second runs only when the first misses the
# target by more than ``miss_tol`` of its size; the better merit is kept.
SCALINGS = ("marquardt", "levenberg")
# the stiffer stage is there to remove inequality violations: when the first stage ends with none (g >= 0,
# rows inside their margin allowed) its steps crawl along the fit manifold lowering the regulariser a little,
# so it gets this many (64x64 rigid circle: 40 steps -> 10, about half the time, fit 0.2005 -> 0.1962 mm,
# regulariser +1.6 %)
POLISH_STEPS = 10
# A level started from its coarse level's design (coarse to fine) can try the stiffer weight alone first
# (``steps.stiffer_alone``): that design ends at the weight's margins, and where the fine design is close, the soft
# stage's detour (corners into their margins for the fit, pushed out again) costs iterations and fit (64x64 rigid
# circle: 31 iterations to 0.214 % of the size, against 14 to 0.197 %). docs/speed.md, "Ninth wave".
MEMBER_STAGE = (STAGES[-1][0], STAGES[0][1], 25, MAX_STALL)
# ... and above 96x96 tiles, where the stage keeps its regulariser block (``routes.keeps_block``): one step fewer
# at its end, two small gains in a row (128x128 rigid circle: 31 iterations of the two stages to 0.22062 % of the
# size; this stage alone 13 to 0.22039 %, 14 with three to 0.22064 %). docs/speed.md, "Session 55 (big55)".
MEMBER_STAGE_KEPT = (STAGES[-1][0], STAGES[0][1], 25, 2)


class _Merit:
    """Stacked residuals of the reduced problem and their Jacobians.

    Rows come in two blocks: on the deployed nodes ``x(p)`` (fit, non-overlap; Jacobian ∂x/∂p = ``D``)
    and on the closed-state-1 grid ``c = Z S`` (the ``TILE_SHAPE`` families; ∂c/∂p = ``C``, constant).
    The grid block is the large one (the regulariser); its normal matrix, by coordinate blocks of ``Z``,
    costs about a third of ``Dᵀ JᵀJ D`` on the nodes (G ≈ V/2 grid vertices, no ψ column). With ``contact``
    the closed states' contact rows follow (``contact.py``, on ``Z S`` and ``Y S``; dense, few active).
    """

    _kept: KeptGridBlock | None = None  # a stage's kept regulariser block (``steps.stage``)

    def __init__(
        self,
        fam: RigidFamily,
        families: list[Family],
        margin: dict,
        reg_weight: float,
        rho: float = STAGES[0][0],
        scaling: str = "marquardt",
        grid_families: Sequence[Family] = (),
        contact: ClosedContact | None = None,
    ):
        self.fam = fam
        self.contact = contact
        self.nf = fam.n_seeds
        on_grid = {f.name for f in grid_families}
        self.fits = [f for f in families if f.kind == "fit"]
        self.regs = [f for f in families if f.kind == "reg" and f.name not in on_grid]
        self.ineqs = [f for f in families if f.kind == "ineq" and f.name not in on_grid]
        self.grid_regs = [f for f in grid_families if f.kind == "reg"]
        self.grid_ineqs = [f for f in grid_families if f.kind == "ineq"]
        self.margin = margin
        self.w = float(np.sqrt(reg_weight))
        self.sq = float(np.sqrt(rho))
        self.scaling = scaling
        G, nf = fam.Z.shape
        # the dense path needs the grid families to be exactly the regulariser and tile convexity
        self._tiles = None
        # a symmetric solve's dense path: Jacobians over q's columns (``mirror_dense.halved``)
        self._half: Any = None
        names = [f.name for f in self.grid_regs] + [f.name for f in self.grid_ineqs]
        if names == list(TILE_SHAPE):
            reg, conv = self.grid_regs[0], self.grid_ineqs[0]
            rows = reg.meta["rows"]
            if (2 * len(rows.first) + len(conv.meta["quads"]) * 4) * (2 * nf + 1) <= DENSE_JD:
                self._tiles = TileShapeRows(fam, conv.meta["quads"], rows, self.margin[conv.name])
        # block path: ∂c/∂p, dense only while small (column slicing of Jc costs more there)
        self._C = None
        if self._tiles is None and 2 * G * (2 * nf + 1) <= DENSE_JD:
            C = np.zeros((G, 2, 2 * nf + 1))
            C[:, 0, :nf] = fam.Z
            C[:, 1, nf : 2 * nf] = fam.Z
            self._C = C.reshape(2 * G, 2 * nf + 1)

    def staged(self, rho: float, scaling: str) -> _Merit:
        """The same rows with another penalty weight and LM scaling (sharing every precomputed array)."""
        new = copy.copy(self)
        new.sq, new.scaling = float(np.sqrt(rho)), scaling
        return new

    def with_contact(self, contact: ClosedContact) -> _Merit:
        """The same rows and the closed states' contact rows."""
        new = copy.copy(self)
        new.contact = contact
        return new

    def unpack(self, p: np.ndarray) -> tuple[np.ndarray, float]:
        nf = self.nf
        return np.stack([p[:nf], p[nf : 2 * nf]], -1), float(p[-1])

    def state(self, p: np.ndarray):
        """``(X, c, w)``: deployed nodes, closed-state-1 grid and (with contact rows) closed state 2 turned
        back a quarter, ``Y S``, of member ``p``."""
        S, psi = self.unpack(p)
        c = self.fam.grid(S)
        return self.fam.nodes(S, psi, c), c, self._state_2(S)

    def _state_2(self, S: np.ndarray) -> np.ndarray | None:
        return None if self.contact is None else self.fam.Y @ S

    def contact_rows(self, Xc, hard: bool) -> tuple[np.ndarray, np.ndarray]:
        """The active contact rows and their dense ``∂r/∂p`` (none without contact rows)."""
        if self.contact is None:
            return np.zeros(0), np.zeros((0, 2 * self.nf + 1))
        return self.contact.active(Xc[1:], 0.5 if hard else 1.0, 1.0 if hard else self.sq)

    def ineq_values(self, Xc) -> dict:
        """Every inequality family's values ``g``, node families on ``X``, grid families on ``c``."""
        X, c, w = Xc
        return {
            **{f.name: f.residual(X) for f in self.ineqs},
            **{f.name: f.residual(c) for f in self.grid_ineqs},
            **(self.contact.values((c, w)) if self.contact and self.contact.barrier else {}),
        }

    def ineq_violation(self, Xc, values: dict | None = None) -> float:
        vals = (self.ineq_values(Xc) if values is None else values).values()
        return max(0.0, -min((float(v.min(initial=np.inf)) for v in vals), default=0.0))

    def rows(self, Xc, hard: bool = False, values: dict | None = None, jacobians: bool = True):
        """Residuals and Jacobians of the merit (or of the hard-fit rows): ``(r, Jx, Jc)``.

        ``r`` stacks the node rows (``Jx``, CSR over the nodes) and then the grid rows (``Jc``, over the grid, a
        ``StackedJacobian``: the grid block takes its coordinate columns, not the CSR).
        The contact rows are ``contact_rows``' (``_Evaluation`` appends them).
        ``values``: the inequality values of ``Xc`` when already known (``ineq_values``). Without
        ``jacobians`` only ``r`` (``Jx``, ``Jc`` None): a trial step needs no Jacobian unless it is accepted.
        """
        X, c, _ = Xc
        values = self.ineq_values(Xc) if values is None else values
        blocks: list[tuple[np.ndarray, StackedJacobian | None]] = []
        for arr, fits, regs, ineqs in (
            (X, self.fits, self.regs, self.ineqs),
            (c, [], self.grid_regs, self.grid_ineqs),
        ):
            rs, Js = [], []
            for f in fits:
                if hard and f.meta.get("soft"):  # the exact fit leaves the soft outline rows out
                    continue
                r, J = f(arr) if jacobians else (f.residual(arr), None)
                rs.append(r)
                Js.append(J)
            kept = self._kept if arr is c else None  # a stage's kept grid block (``steps.stage``)
            if not hard:
                for f in regs:  # a stencil's rows kept unassembled (``StackedJacobian``)
                    if not jacobians:
                        r, J = f.residual(arr), None
                    else:
                        r, J = f.block(arr, self.w) if kept is None else kept.block(f, arr, self.w)
                    rs.append(self.w * r)
                    Js.append(J)
            for f in ineqs:
                m = self.margin[f.name] * (0.5 if hard else 1.0)
                v = values[f.name] - m
                act = np.flatnonzero(v < 0)
                if len(act):  # the Jacobian only for active rows
                    s = 1.0 if hard else self.sq
                    rs.append(s * v[act])
                    Js.append(s * f.rows_jacobian(arr, act, len(v)) if jacobians else None)
            n = 2 * len(arr)
            r = np.concatenate(rs) if rs else np.zeros(0)
            if not jacobians:
                blocks.append((r, None))
                continue
            blocks.append((r, StackedJacobian(Js, n)))
        (rx, Jx), (rc, Jc) = blocks
        return np.concatenate([rx, rc]), None if Jx is None else Jx.csr(), Jc

    def evaluate(self, p: np.ndarray, hard: bool = False) -> _Evaluation:
        """Member ``p``: its nodes, grid, inequality violation and (merit or hard-fit) rows."""
        if self._tiles is not None:
            return self._evaluate_dense(p, hard)
        Xc = self.state(p)
        values = self.ineq_values(Xc)
        return _Evaluation(self, p, Xc, self.ineq_violation(Xc, values), hard, values=values)

    def _node_rows(self, X: np.ndarray, hard: bool, s: float, ineq: list) -> tuple[list, list]:
        """The node blocks of the dense path: ``(rows, pend)``; ``pend`` holds each block's ``(scale, () -> stencil
        Jacobian, rows or None)`` in row order, the gradients formed only when asked. ``ineq``: the inequality
        families' values on ``X``."""
        rs: list[np.ndarray] = []
        pend: list[tuple[float, Any, np.ndarray | None]] = []
        for f in self.fits:
            if not (hard and f.meta.get("soft")):
                r, J = f.fn(X)
                rs.append(r)
                pend.append((1.0, lambda J=J: J, None))
        if not hard:
            for f in self.regs:
                r, J = f.fn(X)
                rs.append(self.w * r)
                pend.append((self.w, lambda J=J: J, None))
        for f, r in zip(self.ineqs, ineq):
            v = r - self.margin[f.name] * (0.5 if hard else 1.0)
            act = np.flatnonzero(v < 0)
            if len(act):  # rarely
                rs.append(s * v[act])
                # the gradients only when asked, and of the active rows only where the family can
                pend.append((s, lambda f=f, m=v < 0: f.stencil_where(X, m), act))
        return rs, pend

    def _evaluate_dense(self, p: np.ndarray, hard: bool) -> _Evaluation:
        """The inequality values of member ``p`` now, its rows when ``r`` is first asked for, their dense reduced
        Jacobian (node rows through ``∂x/∂p`` at the nodes they touch, tile-shape rows from ``TileShapeRows``,
        inequality rows only where active) when a step asks: LM refuses a trial step that adds a violation on
        the values alone (``lm._limited``: most step-limit halvings), and most other trials end at ``r``."""
        S, psi = self.unpack(p)
        c = self.fam.grid(S)
        X, w = self.fam.nodes(S, psi, c), self._state_2(S)
        t = self._tiles
        assert t is not None, "evaluate takes the dense path only with the tile-shape rows"
        tc = tile_corners(c, t.quads)
        s = 1.0 if hard else self.sq
        ineq = [f.residual(X) for f in self.ineqs]
        g = tc.cross.reshape(-1)
        gmin = min([float(v.min(initial=np.inf)) for v in ineq] + [float(g.min(initial=np.inf))])
        if self.contact is not None and self.contact.barrier:
            gmin = min(
                [gmin]
                + [float(g.min(initial=np.inf)) for g in self.contact.values((c, w)).values()]
            )
        got: dict = {}

        def rows() -> np.ndarray:
            """The rows (once): the regulariser's last, its normal-matrix block formed from the buffer."""
            if not got:
                rs, pend = self._node_rows(X, hard, s, ineq)
                v = g - t.margin * (0.5 if hard else 1.0)
                flat = np.flatnonzero(v < 0)
                if len(flat):
                    rs.append(s * v[flat])
                rk, Jk = self.contact_rows((X, c, w), hard)
                rs.append(rk)
                rr = None if hard else self.w * t.rows.residual(tc)
                r = np.concatenate(rs if rr is None else [*rs, rr])
                got.update(r=r, pend=pend, flat=flat, Jk=Jk, rr=rr)
            return got["r"]

        def dense():
            """``(J, reg)``: the Jacobian of the rows before the regulariser's, and ``(tc, JᵀJ, Jᵀr)`` of those."""
            rows()
            flat, Jk, rr = got["flat"], got["Jk"], got["rr"]
            Js = [sc * self._node_jacobian(stencil(), S, psi, r) for sc, stencil, r in got["pend"]]
            if len(flat):
                Js.append(s * t.convexity_jacobian(tc, flat))
            Js.append(Jk if self._half is None else self._half.through(Jk))
            J = np.zeros((sum(len(b) for b in Js), len(p) if self._half is None else self._half.nq))
            o = 0
            for Jb in Js:
                J[o : o + len(Jb), : Jb.shape[1]] = Jb  # grid blocks have no ψ column
                o += len(Jb)
            return J, None if rr is None else (tc, *t.regularizer_normal(tc, rr, self.w))

        return _Evaluation(self, p, (X, c, w), max(0.0, -gmin), hard, rows=rows, dense=dense)

    def _node_jacobian(
        self, J, S: np.ndarray, psi: float, rows: np.ndarray | None = None
    ) -> np.ndarray:
        """``∂r/∂p`` (dense) of node rows from their stencil Jacobian ``(nodes, grads)`` (what the fit and
        inequality families return), through ``∂x/∂p`` at those nodes only."""
        nodes, grads = J
        if rows is not None:
            nodes, grads = nodes[rows], grads[rows]
        m, k = nodes.shape
        at = (self.fam if self._half is None else self._half).jacobian_at
        D = at(S, psi, nodes.reshape(-1)).reshape(m, k, 2, -1)
        return np.einsum("mkd,mkdp->mp", grads, D)

    def _touched(self, Jx, p: np.ndarray) -> tuple[sparse.csr_matrix, np.ndarray]:
        """``Jx`` on the columns of the nodes its rows touch and ``∂x/∂p`` at those nodes only: the node rows
        (fit, active inequalities) see a few boundary nodes, and the full ``(2V, P)`` matrix would not fit
        in memory at 128x128."""
        nodes = np.unique(Jx.indices // 2)
        cols = np.stack([2 * nodes, 2 * nodes + 1], 1).reshape(-1)
        D = self.fam.jacobian_at(*self.unpack(p), nodes).reshape(2 * len(nodes), -1)
        return Jx[:, cols], D

    def reduced_jacobian(self, Jx, Jc, p: np.ndarray) -> np.ndarray:
        """Dense ∂r/∂p of the stacked rows."""
        Js, D = self._touched(Jx, p)
        return np.vstack([Js @ D, self._grid_to_p(Jc)])

    def dense_jd(self) -> float:
        """``DENSE_JD`` as it is now (``mirror_normal.half_normal`` forms its blocks by it too)."""
        return DENSE_JD

    def normal(self, r: np.ndarray, Jx, Jc, p: np.ndarray):
        """Reduced Gauss-Newton matrix and gradient: ``Dᵀ JxᵀJx D + Cᵀ JcᵀJc C`` and ``Dᵀ Jxᵀ rx + Cᵀ Jcᵀ rc``."""
        nx = Jx.shape[0]
        Hx, gx = reduced_normal(*self._touched(Jx, p), r[:nx], DENSE_JD)
        Hc, gc = (
            self._grid_normal(Jc, r[nx:]) if self._kept is None else self._kept.normal(Jc, r[nx:])
        )
        return Hx + Hc, gx + gc

    def _grid_to_p(self, Jc) -> np.ndarray:
        """``Jc C`` (dense): the grid rows' Jacobian with respect to ``p``."""
        if self._C is not None:
            return Jc @ self._C
        Z = self.fam.Z
        return np.hstack([J @ Z for J in Jc.columns()] + [np.zeros((Jc.shape[0], 1))])

    def _grid_normal(self, Jc, rc: np.ndarray):
        """``Cᵀ JcᵀJc C`` and ``Cᵀ Jcᵀ rc``. C = ∂c/∂p is block-diagonal (Z for x, Z for y, nothing for ψ):
        above the dense threshold the matrix is assembled as ``Zᵀ (Jaᵀ Jb) Z``, a in {x, y}, a third of the
        work of the product through a dense C (and no 2G × P matrix in memory), and
        through the family's sparse factor ``Z = E Z[core]`` (``core.py``): the dense products run
        over the core's vertices (about a quarter of them) instead of all G grid vertices."""
        nf = self.nf
        P = 2 * nf + 1
        if Jc.shape[0] * P <= DENSE_JD:
            JC = self._grid_to_p(Jc)
            return JC.T @ JC, JC.T @ rc
        core = self.fam.core
        # the transposes as CSR (a CSC @ CSR product converts its right factor every time)
        (Ja, Jb), (AT, BT) = Jc.columns(), Jc.transposes()
        H = np.zeros((P, P))
        H[:nf, :nf] = core.quadratic(AT @ Ja)
        H[nf : 2 * nf, nf : 2 * nf] = core.quadratic(BT @ Jb)
        H[:nf, nf : 2 * nf] = core.quadratic(AT @ Jb)
        H[nf : 2 * nf, :nf] = H[:nf, nf : 2 * nf].T
        g = [core.ZcT @ (core.ET @ (JT @ rc)) for JT in (AT, BT)]
        return H, np.concatenate([*g, [0.0]])


# below this many entries in the reduced Jacobian J D it is formed densely (measured, 1 thread: faster than
# the sparse JᵀJ up to 32x32, slower at 64x64 with 1.7e7 entries)
DENSE_JD = 4e6


@dataclass(frozen=True)
class ReducedSearch:
    """How :func:`solve_reduced` weighs and searches: the regulariser's weight in the merit, ``fit_tol`` of a
    hard fit (absolute), ``mean_edge(X)`` the unit of its 1 % "nearly exact" threshold, the log, the LM
    iteration cap, the fit miss that ends the scalings early, the LM scalings to start with and the
    ``(penalty weight, stall tolerance, iteration cap, small gains in a row)`` of the stiffer stage tried alone
    first from a coarse design's member (``MEMBER_STAGE``; None: the stages only); ``keep_block``: ``steps.stage``'s."""

    reg_weight: float
    fit_tol: float
    mean_edge: Callable[[np.ndarray], float]
    log: Callable[[str], None]
    max_iter: int = 200
    miss_tol: float = 0.0
    scalings: tuple[str, ...] = SCALINGS
    # the stiffer stage's cap after a first stage that ends feasible (a minimax finish step: 0, ``finish_step``)
    polish_steps: int = POLISH_STEPS
    member: tuple[float, float, int, int] | None = None
    keep_block: bool = False


def solve_reduced(
    fam: RigidFamily,
    st: Stencils,
    X0: np.ndarray,
    psi0: float,
    families: list[Family],
    margin: dict,
    how: ReducedSearch,
    S0: np.ndarray | None = None,
    mirror: Mirror | None = None,
):
    """Fit within the rigid family from the member nearest ``X0`` at ``psi0`` (or from seeds ``S0``, a member):
    ``(X, mode, iterations)``, ``mode`` "hard" when the fit rows were driven to ``how.fit_tol`` (absolute,
    normalised units), else "least-squares"; above ``EXACT_GRID`` with ``how.keep_block``, ``X`` by ``exact_nodes``.
    ``mirror``: the symmetric members' map ``p = P q`` and axis rows (``mirror.py``); the solve is over ``q``."""
    if S0 is None:  # the member nearest X0 (a least-squares fit over all nodes)
        S0, _ = fam.fit(X0, psi0)
    p0 = np.concatenate([S0[:, 0], S0[:, 1], [psi0]])
    if mirror is not None:
        p0 = symmetric_member(mirror.P, p0)
    iters: dict = {}
    on_grid = grid_families(fam, st, families)
    judge: Any = _Merit(fam, families, margin, how.reg_weight, STAGES[-1][0], grid_families=on_grid)
    if mirror is not None:
        judge = MirroredMerit(judge, mirror.P, mirror.axis_rows)
    p, X, mode = _search(judge, p0, "", iters, how)
    # the closed states' contact rows only where a result has tiles of a closed state overlapping: on every
    # step they would bar the transient overlaps the fit passes through (32x32 heart: 1.61 % -> 3.55 %)
    touching = judge.with_contact(ClosedContact(fam, st))
    # from an overlapping point they are a penalty only: as a barrier, the step limit (on the largest violation
    # of any row) let the tiles' convexity rows go as far negative as the overlap was deep (64x64 heart)
    pushing = judge.with_contact(ClosedContact(fam, st, barrier=False))

    def rank(p, X, mode) -> tuple:
        """Feasible on its own inequalities, then apart in the closed states, then (overlapping only) the merit."""
        Xc = judge.state(p)
        S, _ = judge.unpack(p if mirror is None else mirror.P @ p)
        xs = (Xc[1], fam.translations(S, Xc[1][fam.node_vertex]))  # Y S, no dense Y
        gap = min(float(g.min(initial=np.inf)) for g in touching.contact.values(xs).values())
        r = np.zeros(0) if gap >= 0.0 else touching.evaluate(p).r
        return (judge.ineq_violation(Xc) > 0, gap < 0.0, float(r @ r)), X, mode, p

    best = rank(p, X, mode)
    # from the overlapping result first, then (if that ends violating an inequality) from the start, where the
    # rows bar the overlap on every step; the original result stays if neither is better (the CLI reports it)
    for tag, merit, start, where in (
        ("contact_", pushing, p, "that result (a penalty)"),
        ("contact_start_", touching, p0, "the start (a barrier)"),
    ):
        if not best[0][1]:
            break
        how.log(f"closed-state tiles overlap: again with the contact rows, from {where}")
        best = min(best, rank(*_search(merit, start, tag, iters, how)), key=lambda b: b[0])
    _, X, mode, p = best
    if how.keep_block and len(fam.Z) > EXACT_GRID:
        X = fam.exact_nodes(*judge.unpack(p))
    return X, mode, iters


def _search(judge, p0, tag: str, iters: dict, how: ReducedSearch):
    """The stages from ``p0`` with each LM scaling in turn (``how.scalings``): ``(p, X, mode)`` of the best."""
    best = None
    stages: tuple[tuple[float, float, int], ...]
    for scaling in how.scalings:
        p, stages = p0, STAGES
        # (with the first scaling only: the circles it is for need no second)
        alone = how.member is not None and not tag and scaling == how.scalings[0]
        first = stiffer_alone(judge, p0, scaling, iters, how) if alone else None
        if first is not None:
            p, X, merit = first
            stages = ()
            hard = exact_fit(merit, p, X, f"{scaling}_member", iters, how)
            if hard is not None:
                return hard
        for n, (rho, stall_tol, cap) in enumerate(stages):
            merit = stage(judge, rho, scaling if n == 0 else "marquardt", how, tag)
            if n and judge.ineq_violation(judge.state(p)) == 0.0:
                cap = min(cap, how.polish_steps)
            p, X, k = levenberg_marquardt(merit, p, min(cap, how.max_iter), stall_tol, how.log)
            iters[f"reduced_{tag}{scaling}_rho_{rho:g}"] = k
            hard = exact_fit(merit, p, X, f"{tag}{scaling}", iters, how)
            if hard is not None:  # an exact fit: nothing left to compare
                return hard
        ev = judge.evaluate(p)
        cost = float(ev.r @ ev.r)
        miss = fit_miss(exact_fits(merit.fits), X)
        viol = ev.gviol
        how.log(
            f"reduced ({scaling} start): merit {cost:.4e}, fit misses by {miss:.3%} of the target size"
            + (f", an inequality violated by {viol:.2e}" if viol > 0 else "")
        )
        # a result that violates an inequality (g < 0: a coarse-to-fine start can leave a reflex corner that
        # the fit holds against any penalty; rigid 32x32 ellipse) ranks below every feasible one, and the other
        # scaling is tried as well
        if best is None or (viol > 0, cost) < best[0]:
            best = ((viol > 0, cost), p, X)
        if miss <= how.miss_tol and not viol > 0:
            break
    assert best is not None, "scalings is not empty"
    return best[1], best[2], "least-squares"
