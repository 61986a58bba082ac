"""The inverse-design solvers.

``--rigid`` designs with rhombus holes (no symmetry, no closed-state targets)
are solved in the closed-form rigid family (``rigid.py``, ``reduced.py``);
``_design`` says when the full solver below is asked as well. The full solver:
sparse Levenberg-Marquardt with penalty continuation and a final Gauss-Newton
projection onto the equality manifold.

Why this design (see ``docs/design-solver.md``): the reconfigurable constraint
set has dependent and redundant rows at every feasible point (rank deficit of
about one row per hole, spec §2.3), which breaks LICQ-based NLP solvers
(IPOPT refuses it, SLSQP fails). Least-squares methods do not need independent
rows. The solver therefore

1. minimises ``ρ|c(x)|² + |s(x)|² + w E_reg(x) + ρ|min(0, g(x) - m)|²`` by
   Levenberg-Marquardt on the stacked residuals, for ρ = 1e2 then 1e4 (warm
   started), where ``c`` are the equality families, ``s`` the signed distances
   of the boundary tips to the target, ``E_reg`` the smoothness regulariser and
   ``g >= 0`` the inequalities with a small margin ``m``; a step that would
   make an inequality more violated is halved (step limiting);
2. projects onto ``c = 0`` (and ``s = 0`` when the least-squares fit came out
   exact, "hard" shape matching) with damped Gauss-Newton steps
   ``(JᵀJ + μI) dx = -Jᵀc``, which converge quadratically whatever the rank of J;
3. if the first schedule leaves the constraint manifold or the projection
   stalls, restarts with stiff penalties (1e4, 1e6) and keeps the best attempt.

Normal equations are factorised with SuperLU (scipy.sparse) in a geometric
nested-dissection order; LU-preconditioned CG reuses a factorisation across
steps. Units are normalised: the initial tile edge is 1.
"""

from __future__ import annotations

import sys
import time
from dataclasses import dataclass, field, replace

import numpy as np
from scipy import sparse
from scipy.sparse.linalg import splu

try:  # single-threaded BLAS: the solver's vector operations are too small to gain from threads, and on a
    # loaded machine OpenBLAS threads contend (measured: a 16k-vector dot took 1.7 ms instead of 7 µs)
    from threadpoolctl import ThreadpoolController
except ImportError:  # pragma: no cover
    ThreadpoolController = None

from ..errors import InputError
from ..pattern import geometry
from ..pattern.conformance import boundary_tip_order
from ..pattern.lattice import standard_pattern
from ..pattern.model import Pattern
from . import constraints as C
from . import offset_outline, outline
from .conformance import deployed as deployed_conformance
from .fabrication import FabricationLimits
from .fabrication import families as fabrication_families
from .initial import coarse_tile_map, initial_guess
from .objective import energy, regularizer, weighted
from .reduced import fit_miss, solve_reduced
from .rigid import RigidFamily, resample_grid
from .targets import Target
from .unfold import convex_member

_BLAS = None  # one controller per process: finding the loaded BLAS libraries costs ~1.3 ms a call


def single_thread_blas():
    """Context manager that limits BLAS to one thread (a no-op without threadpoolctl)."""
    global _BLAS
    if ThreadpoolController is None:  # pragma: no cover
        import contextlib

        return contextlib.nullcontext()
    if _BLAS is None:
        _BLAS = ThreadpoolController()
    return _BLAS.limit(limits=1, user_api="blas")


CONVEX_MARGIN = 0.02  # cross(next - v, prev - v) >= 0.02 l^2: tile angles stay > ~1° from 0 and π
GAP_MARGIN = 0.005  # gap angles at hinges: the penalty acts before the hard limit g >= 0 stops a step
STALL = 1e-6  # a penalty stage ends after 3 accepted steps that each lower the merit by less than this
EARLY_STALL = 1e-3  # ... looser in the first stage: the next one refines from there
# (penalty weight, stall tolerance, iteration cap) per stage; the projection then enforces c = 0 exactly,
# moving x by O(|c|), so the last stage need not converge the penalty problem to high accuracy
PENALTIES = ((1e2, EARLY_STALL, 200), (1e4, STALL, 40))
STIFF_PENALTIES = ((1e4, 1e-4, 300), (1e6, STALL, 60))  # fallback when the first schedule gets stuck
COARSE_PENALTIES = ((1e4, STALL, 40),)  # from a coarse-to-fine start: repair the constraints stiffly, then project
COARSE_MIN = 16  # --init coarse: a level with fewer tiles a side than this starts from rescaled
RESTART_ABOVE = 1e-3  # max equality row after the first schedule that triggers the fallback
# inexact LM: penalty-stage steps solve the normal equations to 1e-5 (the gain ratio judges the step that
# was actually taken); the projection keeps 1e-13 so its Gauss-Newton steps stay quadratically convergent.
# 1e-3 and 1e-4 were faster on the rigid circle but landed in worse local minima on must-show targets
# (heart 16x16 fit 12.8 mm instead of 0.09 mm, blob 8x8 rigid 0.92 mm instead of 0.16 mm); 1e-5 did not.
LM_CG_RTOL = 1e-5
SOLVERS = ("auto", "reduced", "full")
# auto: a least-squares fit from the rigid family also gets the full solver when the pattern is small
# (up to FULL_ALWAYS_TILES) and its outline misses ``second_opinion_above`` (the CLI's --shape-tol), or
# when it misses the target by more than FULL_ABOVE of its size; the lower objective wins. The family's LM
# often stops in a worse local minimum on non-convex or elongated targets (rigid 100 mm, 16x16 rectangle
# 0.088 vs 0.022 mm, 8x8 heart 0.42 vs 0.15 mm), while on the rigid circle both reach the same fit (32x32
# 0.16 vs 0.14 mm, 64x64 0.22 vs 0.21 mm) and the full solver would only cost time (3.9 s and 63 s).
FULL_ALWAYS_TILES = 16 * 16
FULL_ABOVE = 2.5e-3
# ... but not above this many tiles: at 64x64 the full solver takes 1-8 minutes and did not find the better
# design on hard targets (rigid heart from rescaled: 21.6 mm either way; ellipse: 7.4 mm after 7.8 min)
FULL_MAX_TILES = 32 * 32
# from this many tiles a non-rigid rhombus design (no symmetry, no closed-state target) is solved as the rigid
# one, coarse to fine: a rigid member satisfies every non-rigid equality, and there the full solver over all
# nodes was slower and mostly worse (API, rescaled, 100 mm: 32x32 heart 90 s CPU, Hausdorff 7.1 % of the
# target's diagonal; 32x32 ellipse 84 s CPU and unconverged, 11.8 %; rigid family: 9.5 s / 7.5 %, 3.9 s / 1.2 %)
VIA_RIGID_TILES = 32 * 32
# below that, the CLI's last guess for a non-rigid design that missed: answered by the rigid family as well
# (leaf SVG 16x16: conformal unconverged, rescaled overlapping, standard 22.6 % off; the rigid family 1 %)
VIA_RIGID_INIT = "rigid"
# from this many tiles (below VIA_RIGID_TILES) a non-rigid rhombus design tries the rigid family first, from
# each of RIGID_FIRST_INITS, reduced only, and keeps the member with the closest outline if it is within the
# shape tolerance; otherwise the full solver runs as before. Measured (design(), 16x16, 100 mm, CPU s under
# load 9): heart full 4.6 s, Hausdorff 8.3 % -> rigid family 0.8 s, 1.4 %; ellipse 2:1 full 7.6 s, 0.77 % ->
# rigid family from coarse 1.6 s, 0.18 %. A member meeting RIGID_FIRST_GOOD ends the search early.
VIA_RIGID_FIRST_TILES = 16 * 16
RIGID_FIRST_INITS = ("coarse", "rescaled")
RIGID_FIRST_GOOD = 5e-3
# a projection whose max row has not fallen tenfold over its last 5 accepted steps has stopped converging
# quadratically: the rows conflict (the 16x16 heart's half-margin rows: 50 steps from 1e-6 to 3e-8, then the
# equalities-only pass converged in 6); it hands over to the next pass
HARD_STALL_STEPS = 5
HARD_STALL_GAIN = 0.1
MAX_CG = 10  # CG steps on a stale factorisation before a fresh one (64x64, CG to 1e-3: 10 beat 5, 20, 40)


@dataclass
class DesignRequest:
    """What to design. Targets are in mm."""

    rows: int
    cols: int
    target: Target | None = None
    rigid: bool = False
    symmetry: str | None = None  # "x": y -> -y, "y": x -> -x
    holes: str = "rhombus"  # or "parallelogram"
    contracted: dict = field(default_factory=dict)  # state -> Target | ("rect", ratio or None)
    init: str = "rescaled"
    solver: str = "auto"  # "reduced": closed-form rigid family only; "full": all nodes; "auto": see _design
    tol: float = 1e-10
    reg_weight: float = 1e-3
    max_iter: int = 300
    name: str = ""
    outline: bool = True  # also fit the tip polygon's chords and the target's samples (``C.outline_match``)
    fabrication: FabricationLimits | None = None  # mm limits at the target's size (design/fabrication.py)
    fabrication_intent: dict = field(default_factory=dict)  # material/printer names: stored for cut and print
    seed: int | None = None  # jitter the initial nodes (2 % of a tile edge) to explore other local minima
    second_opinion: bool = True  # auto: also run the full solver when the rigid family's fit is least-squares
    # ... up to 16x16 tiles only when its outline misses by more than this share of the target's size (the
    # CLI passes its --shape-tol): where the rigid design already meets the tolerance the full solver is skipped
    second_opinion_above: float = 0.02
    start: np.ndarray | None = None  # deployed nodes (mm) to start from instead of ``init`` (a warm start)
    rigid_first: bool = True  # a mid-size non-rigid design tries the rigid family first (VIA_RIGID_FIRST_TILES)
    coarse_solver: str | None = None  # --init coarse: the coarse levels' solver (None: ``solver``)
    fit_weights: dict | None = None  # fit family name -> row weights (``refine.py``: towards the minimax fit)

    def validate(self) -> None:
        if int(self.rows) != self.rows or int(self.cols) != self.cols or self.rows < 2 or self.cols < 2:
            raise InputError(f"inverse design needs at least 2x2 tiles, got {self.rows}x{self.cols}")
        if self.holes not in ("rhombus", "parallelogram"):
            raise InputError(f"--holes must be rhombus or parallelogram, not {self.holes!r}")
        if self.solver not in SOLVERS:
            raise InputError(f"--solver must be one of {', '.join(SOLVERS)}, not {self.solver!r}")
        if self.solver == "reduced" and not reduced_applies(self):
            raise InputError("--solver reduced needs --rigid, rhombus holes, a --target, and no --symmetry or "
                             "--contracted-target (the closed-form rigid family covers only that)")
        if self.symmetry not in (None, "x", "y"):
            raise InputError(f"--symmetry must be x or y, not {self.symmetry!r}")
        if not (np.isfinite(self.tol) and 0 < self.tol < 1e-2):
            raise InputError(f"--tol must lie in (0, 1e-2), got {self.tol}")
        for s, spec in self.contracted.items():
            if s not in (1, 2):
                raise InputError(f"closed states are 1 and 2, not {s}")
            if isinstance(spec, Target) and self.holes == "parallelogram" and not offset_outline.covers(self):
                raise InputError("a closed-state target curve needs rhombus holes (parallelogram holes leave "
                                 "T-junctions, so the closed state is not a grid)")
        if self.target is None and not any(isinstance(v, Target) for v in self.contracted.values()):
            raise InputError("nothing to fit: give --target or a --contracted-target curve")
        if self.symmetry:
            for tgt in [self.target, *[v for v in self.contracted.values() if isinstance(v, Target)]]:
                if tgt is not None and tgt.mirror_error(self.symmetry) > 1e-3:
                    raise InputError(f"target {tgt.name!r} is not symmetric about the {self.symmetry} axis, "
                                     f"so --symmetry {self.symmetry} contradicts it")


@dataclass
class DesignResult:
    pattern: Pattern  # deployed design in mm (no closed states: the caller contracts)
    report: dict
    converged: bool
    closed_grids: dict  # state -> (V, 2) closed-state pattern vertices in mm
    closed_targets: dict  # state -> Target (mm) the closed grid was fitted to, scaled to the tiles' area


class _Problem:
    """Families over one node array (deployed nodes, then closed grids)."""

    def __init__(self, req: DesignRequest):
        self.req = req
        std = standard_pattern(req.rows, req.cols, tile_size=1.0)
        self.std = std
        st = C.Stencils.from_pattern(std)
        self.st = st
        base = std.nodes.copy()
        n = len(base)
        self.coarse = None
        self.start_member = None  # (seeds in mm, ψ) when the start is a rigid-family member (coarse to fine)
        self.unfold = None  # fold repair of a coarse-to-fine rigid start (``unfold.convex_member``)
        self._rigid: RigidFamily | None = None
        if req.start is not None:  # a warm start (continuation): its own tile size is the unit
            L0 = geometry.mean_edge_length(np.asarray(req.start, float)[st.tiles])
            X0 = np.asarray(req.start, float) / L0
        elif req.init == "coarse":
            X0, L0 = self._coarse_guess(base, st)
        else:
            X0, L0 = initial_guess(base, st, req.target, req.init)
        if req.seed is not None:  # a sweep's seeds axis: another start of the same guess (not the rigid family's)
            X0 = X0 + np.random.default_rng(req.seed).normal(0.0, 0.02, X0.shape)
        curves = {s: v for s, v in req.contracted.items() if isinstance(v, Target)}
        if req.target is None:
            first = curves[min(curves)]
            L0 = float(np.sqrt(abs(first.area) / (req.rows * req.cols)))
        self.L0 = L0
        # a closed state has the area of its tiles: compare outlines by shape, at MN tiles of size L0
        curves = {s: c.transformed(float(np.sqrt(req.rows * req.cols * L0 * L0 / abs(c.area))))
                  for s, c in curves.items()}
        self.curves_mm = curves
        self.grids: dict[int, C.ClosedGrid] = {}
        blocks = [X0]
        nv = n
        for s in sorted(curves):
            g = C.ClosedGrid.build(st, s, nv)
            self.grids[s] = g
            M, N = req.rows, req.cols
            gx, gy = np.meshgrid(np.arange(N + 1), np.arange(M + 1))
            grid = np.stack([gx.ravel() - N / 2, gy.ravel() - M / 2], -1).astype(float)
            lo, hi = curves[s].bbox
            blocks.append(grid + 0.5 * (lo + hi) / L0)
            nv += g.n_vertices
        self.nv = nv
        self.n = n
        self.X0 = np.vstack(blocks)
        fam: list[C.Family] = []
        if req.holes == "rhombus":
            fam += [C.edge_pairs(st, 1, nv), C.edge_pairs(st, 2, nv)]
        else:
            fam += [C.hole_opposite_sides(st, nv), C.notch_pairs(st, 1, nv), C.notch_pairs(st, 2, nv)]
        if req.rigid or req.holes == "parallelogram":
            fam.append(C.hinge_sums(st, nv))
        else:
            fam += [C.rings(st, 1, nv), C.rings(st, 2, nv)]
        if req.symmetry:
            fam.append(C.symmetry(st, base, req.symmetry, nv))
        for s, spec in sorted(req.contracted.items()):
            if isinstance(spec, Target):
                # with parallelogram holes only the grid's boundary is a closed state's (T-junctions inside)
                if req.holes == "rhombus":
                    fam.append(self.grids[s].congruence(st, nv))
            else:
                fam.append(C.rectangle_outline(st, s, nv))
                if spec[1] is not None:
                    fam.append(C.outline_ratio(st, s, float(spec[1]), nv))
        if req.target is not None:
            tgt = req.target.transformed(1.0 / L0)
            fam.append(C.shape_match(st.tip_nodes, st.tip_side, tgt, nv, "shape"))
            if req.outline:
                top = std.topology
                order = boundary_tip_order(top.tiles, top.hole_nodes, top.hole_tiles, top.free_nodes)
                fam.append(C.outline_match(order, tgt, nv))
        for s, g in self.grids.items():
            fam.append(C.shape_match(g.boundary, g.boundary_side, curves[s].transformed(1.0 / L0), nv,
                                     f"closed_shape_{s}"))
        fam.append(regularizer(st, nv))
        fam += [C.non_overlap(st, nv), C.convexity(st, nv)]
        fam += fabrication_families(st, nv, req.fabrication, L0, base)
        if req.fit_weights:  # a weighted fit (``refine.py``); reports measure the unweighted rows
            fam = [weighted(f, req.fit_weights[f.name]) if f.name in req.fit_weights else f for f in fam]
        for g in self.grids.values() if req.holes == "rhombus" else ():
            fam.append(g.orientation(st, nv))
        self.families = fam
        self._normal = None
        # a family may ask its own margin (``meta["margin"]``, tile units: the fabrication rows of a continuation step)
        self.margin = {f.name: f.meta.get("margin", CONVEX_MARGIN if "convexity" in f.name else GAP_MARGIN)
                       for f in fam if f.kind == "ineq"}

    def _coarse_guess(self, base: np.ndarray, st: C.Stencils) -> tuple[np.ndarray, float]:
        """Coarse-to-fine start: solve at half resolution, map the result onto the standard pattern."""
        req = self.req
        rc, cc = req.rows // 2, req.cols // 2
        if req.target is None or min(rc, cc) < 4:
            return initial_guess(base, st, req.target, "rescaled")
        sub = DesignRequest(rc, cc, req.target, rigid=req.rigid, symmetry=req.symmetry, holes=req.holes,
                            contracted=dict(req.contracted),
                            init="coarse" if min(rc, cc) >= COARSE_MIN else "rescaled",
                            tol=req.tol, reg_weight=req.reg_weight, max_iter=req.max_iter,
                            solver=req.coarse_solver or req.solver,
                            # the coarse level is only a start: tips-only keeps its grid unfolded when resampled
                            # (with the outline rows a rigid 8x8 ellipse's grid folded 4 fine tiles)
                            outline=False, fabrication=req.fabrication)
        res = _design(sub, False)
        sc = standard_pattern(rc, cc, tile_size=1.0)
        if reduced_applies(req) and req.solver != "full":
            xmm = self._rigid_refinement(sc, res.pattern.nodes)
            how = "closed-state grid resampled in the rigid family"
        else:
            xmm = coarse_tile_map(sc.nodes, res.pattern.nodes, sc.tiles, cc, base, st.tiles, req.cols)
            how = "deployed tiles mapped"
        c = xmm[st.tiles]
        area = geometry.signed_areas(c)
        self.coarse = {"rows": rc, "cols": cc, "map": how, "status": res.report["status"],
                       "time_s": res.report["time_s"],
                       "iterations_total": res.report["iterations_total"],
                       "factorisations": res.report["factorisations"], "folded_tiles": int((area <= 0).sum())}
        if self.unfold is not None:
            self.coarse["unfold"] = self.unfold
        # an unconverged coarse design or a map that folds tiles is no better a start than rescaled
        self.coarse["used"] = bool(res.converged and not (area <= 0).any())
        if not self.coarse["used"]:
            return initial_guess(base, st, req.target, "rescaled")
        L0 = geometry.mean_edge_length(c)
        return xmm / L0, L0

    def _rigid_refinement(self, coarse: Pattern, x_mm: np.ndarray) -> np.ndarray:
        """Fine start (mm) from a coarse rigid design: its closed-state-1 grid resampled to this lattice.

        The coarse design is a member of its own rigid family at its deployment angle ψ (every hole opens
        to 2ψ); the fine start is the fine member nearest the resampled grid, deployed to the same ψ.
        """
        st_c = C.Stencils.from_pattern(coarse)
        fam_c = RigidFamily.build(st_c, coarse.topology.spanning_tree(0))
        psi = RigidFamily.deployment_angle(x_mm, st_c)
        S_c, _ = fam_c.fit(x_mm, psi)
        grid = resample_grid(fam_c.grid(S_c).reshape(coarse.lattice["rows"] + 1, coarse.lattice["cols"] + 1, 2),
                             self.req.rows, self.req.cols)
        fam = self.rigid_family
        # the nearest fine member can fold cells the resampled grid does not: repaired (``unfold.py``)
        S, self.unfold = convex_member(fam, fam.node_vertex[self.st.tiles], grid.reshape(-1, 2))
        self.start_member = (S, psi)  # the start's seeds: the reduced solver need not fit them again
        return fam.nodes(S, psi)

    @property
    def rigid_family(self) -> RigidFamily:
        """The closed-form rigid family of this lattice (``rigid.py``), built on first use."""
        if self._rigid is None:
            self._rigid = RigidFamily.build(self.st, self.std.topology.spanning_tree(0))
        return self._rigid

    def _ordering(self) -> np.ndarray | None:
        """Variable order for the normal equations, from the union of all Jacobian patterns."""
        if self.nv < 200:
            return None
        S = None
        for f in self.families:
            _, J = f(self.X0)
            P = abs(J).T @ abs(J)
            S = P if S is None else S + P
        S = S.tocoo()
        node = sparse.csr_matrix((np.ones(S.nnz), (S.row // 2, S.col // 2)), shape=(self.nv, self.nv))
        o = nested_dissection(node, self.X0)
        return np.stack([2 * o, 2 * o + 1], 1).ravel()

    @property
    def normal(self) -> _Normal:
        """Normal-equation solver of the full problem, built on first use (its ordering costs a Jacobian)."""
        if self._normal is None:
            self._normal = _Normal(self._ordering())
        return self._normal

    def of(self, kind: str) -> list[C.Family]:
        return [f for f in self.families if f.kind == kind]


def _ineq_values(prob: _Problem, X: np.ndarray) -> np.ndarray:
    return np.concatenate([f.residual(X) for f in prob.of("ineq")])


def _stacked(prob: _Problem, X: np.ndarray, rho: float, hard: list[C.Family] | None = None):
    """Residual vector and Jacobian of the phase-1 merit (or of ``hard`` rows only)."""
    rs, Js = [], []
    if hard is not None:
        for f in hard:
            r, J = f(X)
            if f.kind == "ineq":  # projection keeps inequalities with half their margin
                act = r < 0.5 * prob.margin[f.name]
                r = np.where(act, r - 0.5 * prob.margin[f.name], 0.0)
                J = sparse.diags(act.astype(float)) @ J
            rs.append(r)
            Js.append(J)
        return np.concatenate(rs), sparse.vstack(Js).tocsr()
    sq = np.sqrt(rho)
    w = np.sqrt(prob.req.reg_weight)
    for f in prob.families:
        r, J = f(X)
        if f.kind == "eq":
            rs.append(sq * r)
            Js.append(sq * J)
        elif f.kind == "fit":
            rs.append(r)
            Js.append(J)
        elif f.kind == "reg":
            rs.append(w * r)
            Js.append(w * J)
        else:
            v = r - prob.margin[f.name]
            act = v < 0
            rs.append(sq * np.where(act, v, 0.0))
            Js.append(sparse.diags(sq * act.astype(float)) @ J)
    return np.concatenate(rs), sparse.vstack(Js).tocsr()


def nested_dissection(adj: sparse.csr_matrix, pos: np.ndarray, leaf: int = 48) -> np.ndarray:
    """Geometric nested dissection of a node graph (separators last).

    The pattern is a planar mesh, so splitting at the median of the longer
    axis and numbering each separator after its two halves gives far less fill
    than SuperLU's generic orderings (about half at 64x64).
    """
    adj = adj.tocsr()
    out: list[np.ndarray] = []
    stack = [(np.arange(adj.shape[0]), 0)]
    # iterative post-order: (idx, 0) = split, (idx, 1) = emit separator
    while stack:
        idx, emit = stack.pop()
        if emit:
            out.append(idx)
            continue
        if len(idx) <= leaf:
            out.append(idx)
            continue
        p = pos[idx]
        ax = int(np.argmax(p.max(0) - p.min(0)))
        left = p[:, ax] < np.median(p[:, ax])
        A, B = idx[left], idx[~left]
        if len(A) == 0 or len(B) == 0:
            out.append(idx)
            continue
        inB = np.zeros(adj.shape[0])
        inB[B] = 1.0
        touches = (adj[A] @ inB) > 0
        S, A = A[touches], A[~touches]
        stack += [(S, 1), (B, 0), (A, 0)]
    return np.concatenate(out)


class _Normal:
    """Solves (JᵀJ + μI) dx = -Jᵀr for successive LM steps.

    A sparse LU (SuperLU, fixed nested-dissection order) of one step's matrix
    preconditions conjugate gradients on the next ones: the matrix changes
    slowly from step to step, so a few CG iterations usually replace a new
    factorisation. When CG needs more than ``max_cg`` iterations the matrix is
    factorised afresh.
    """

    def __init__(self, perm: np.ndarray | None, max_cg: int = MAX_CG):
        self.perm = perm
        self.max_cg = max_cg
        self.lu = None
        self.factorisations = 0
        self.cg_steps = 0

    def _factor(self, A):
        self.factorisations += 1
        if self.perm is not None:
            p = self.perm
            try:
                lu = splu(A[p][:, p].tocsc(), permc_spec="NATURAL", diag_pivot_thresh=0.0,
                          options={"SymmetricMode": True})
                inv = np.empty_like(p)
                inv[p] = np.arange(len(p))

                def apply(b, lu=lu, p=p):
                    out = np.empty_like(b)
                    out[p] = lu.solve(b[p])
                    return out

                test = apply(np.ones(A.shape[0]))
                if np.isfinite(test).all():
                    return apply
            except RuntimeError:  # a zero pivot: fall back to pivoting
                pass
        lu = splu(A.tocsc(), permc_spec="MMD_ATA", options={"SymmetricMode": True})
        return lu.solve

    def solve(self, J: sparse.csr_matrix, r: np.ndarray, mu: float, rtol: float = 1e-10) -> np.ndarray:
        from scipy.sparse.linalg import LinearOperator, cg

        A = (J.T @ J).tocsr()
        A = A + mu * sparse.identity(A.shape[0], format="csr")
        b = -(J.T @ r)
        if self.lu is not None:
            M = LinearOperator(A.shape, matvec=self.lu)
            count = [0]

            def cb(_):
                count[0] += 1

            x, info = cg(A, b, x0=self.lu(b), rtol=rtol, maxiter=self.max_cg, M=M, callback=cb)
            self.cg_steps += count[0]
            if info == 0 and np.isfinite(x).all():
                return x
        self.lu = self._factor(A)
        return self.lu(b)


class _Log:
    def __init__(self, progress):
        self.progress = progress
        self.t0 = time.perf_counter()

    def __call__(self, msg: str) -> None:
        if self.progress:
            print(f"[design {time.perf_counter() - self.t0:7.2f}s] {msg}", file=sys.stderr, flush=True)


def _lm(prob: _Problem, X: np.ndarray, rho: float, max_iter: int, log, hard=None, tol_inf=0.0, stall_tol=STALL):
    """Levenberg-Marquardt on the merit (or on the hard rows); returns X, iterations."""
    shape = X.shape
    x = X.reshape(-1).copy()
    r, J = _stacked(prob, x.reshape(shape), rho, hard)
    cost = 0.5 * float(r @ r)
    gviol = max(0.0, -_ineq_values(prob, x.reshape(shape)).min(initial=0.0))
    diag_mean = float((J.multiply(J)).sum() / max(len(x), 1))
    mu = (1e-3 if hard is None else 1e-12) * max(diag_mean, 1e-30)
    nu = 2.0
    it = 0
    stall = 0
    worst: list[float] = []  # max |row| after each accepted Gauss-Newton step (hard rows)
    for it in range(1, max_iter + 1):
        if hard is not None and np.abs(r).max(initial=0.0) <= tol_inf:
            return x.reshape(shape), it - 1
        dx = prob.normal.solve(J, r, mu, rtol=LM_CG_RTOL if hard is None else 1e-13)
        # step limiting: halve the step until it creates no new inequality violation
        for _ in range(6):
            xn = x + dx
            gv = _ineq_values(prob, xn.reshape(shape))
            gviol_n = max(0.0, -gv.min(initial=0.0))
            if gviol_n <= gviol + 1e-15:
                break
            dx = 0.5 * dx
        rn, Jn = _stacked(prob, xn.reshape(shape), rho, hard)
        cn = 0.5 * float(rn @ rn)
        Jdx = J @ dx
        pred = -(float(r @ Jdx) + 0.5 * float(Jdx @ Jdx))
        ratio = (cost - cn) / pred if pred > 0 else -1.0
        ok = np.isfinite(cn) and gviol_n <= gviol + 1e-15
        if hard is not None:
            ok = ok and np.abs(rn).max() < np.abs(r).max()
        else:
            ok = ok and ratio > 1e-4
        if ok:
            small = (cost - cn) <= stall_tol * max(cost, 1e-300) or np.abs(dx).max() <= 1e-13 * (1 + np.abs(x).max())
            x, r, J, cost, gviol = xn, rn, Jn, cn, gviol_n
            if hard is None:
                mu *= max(1 / 3, 1 - (2 * ratio - 1) ** 3)
            else:
                mu = max(mu / 10, 1e-14 * diag_mean)
            nu = 2.0
            stall = stall + 1 if small else 0
            if hard is not None:
                worst.append(float(np.abs(r).max(initial=0.0)))
                if len(worst) > HARD_STALL_STEPS and worst[-1] > HARD_STALL_GAIN * worst[-1 - HARD_STALL_STEPS]:
                    break  # linear, not quadratic: the rows conflict (e.g. an inequality pinned at half margin)
            if it % 10 == 0:
                log(f"  rho={rho:g} it {it}: cost {cost:.3e} mu {mu:.1e} ratio {ratio:.2f} gviol {gviol:.1e}")
            if stall >= 3:
                break
        else:
            mu *= nu if hard is None else 10.0
            nu *= 2
            if mu > 1e20 * max(diag_mean, 1e-30):
                break
    return x.reshape(shape), it


def exact_fits(fits: list[C.Family]) -> list[C.Family]:
    """The fit rows an exact fit drives to zero (not the soft outline rows, whose minimum is not zero)."""
    return [f for f in fits if not f.meta.get("soft")]


def family_residuals(prob: _Problem, X: np.ndarray, L: float) -> dict:
    out = {}
    for f in prob.families:
        if f.kind == "eq" or (f.kind == "fit" and not f.meta.get("soft")):
            r = f.residual(X)
            out[f.name] = float(np.abs(r).max(initial=0.0)) / L ** f.dim
    return out


def design(req: DesignRequest, progress: bool = False) -> DesignResult:
    """Solve the inverse-design problem ``req``; never raises on non-convergence."""
    req.validate()
    with single_thread_blas():
        return _design(req, progress)


def _mean_edge(prob: _Problem, X: np.ndarray) -> float:
    return geometry.mean_edge_length(X[prob.st.tiles])


def via_rigid_applies(req: DesignRequest) -> bool:
    """A non-rigid request answered by the rigid family (``VIA_RIGID_TILES``)."""
    return (req.solver == "auto" and not req.rigid and req.holes == "rhombus" and not req.symmetry
            and not req.contracted and req.target is not None
            and (req.rows * req.cols >= VIA_RIGID_TILES or req.init == VIA_RIGID_INIT))


def rigid_first_applies(req: DesignRequest) -> bool:
    """A non-rigid request that tries the rigid family before the full solver (``VIA_RIGID_FIRST_TILES``)."""
    return (req.rigid_first and req.start is None and req.seed is None and not via_rigid_applies(req)
            and req.solver == "auto" and not req.rigid and req.holes == "rhombus" and not req.symmetry
            and not req.contracted and req.target is not None and req.rows * req.cols >= VIA_RIGID_FIRST_TILES)


def _solve_rigid_first(prob: _Problem, log, iters: dict):
    """The rigid family's closest member to the target (reduced solver only, from each of ``RIGID_FIRST_INITS``)
    that passes every family of the non-rigid problem: ``(X, mode, solver)`` if its outline is within the shape
    tolerance (``second_opinion_above``), else None and the full solver takes over."""
    best = None
    for init in RIGID_FIRST_INITS:
        sub = replace(prob.req, rigid=True, init=init, name="", solver="reduced", second_opinion=False)
        res = _design(sub, False)
        iters.update({f"rigid_{init}_{k}": v for k, v in res.report["iterations"].items()})
        X = res.pattern.nodes / prob.L0
        if not (res.converged and _acceptable(prob, X)):
            log(f"rigid family from {init}: fails a non-rigid family check ({_why_not(prob, X)})")
            continue
        h = deployed_conformance(res.pattern.nodes, res.pattern.topology, prob.req.target)["hausdorff_rel"]
        log(f"rigid family from {init}: outline within {h:.2%} of the target size")
        if best is None or h < best[0]:
            best = (h, X, res.report["shape_matching"], res.report["solver"])
        if h <= RIGID_FIRST_GOOD:
            break
    if best is None or best[0] > prob.req.second_opinion_above:
        log("no rigid-family member within the shape tolerance: the full solver takes over")
        return None
    return best[1:]


def _solve_via_rigid(prob: _Problem, log, iters: dict):
    """The same target as a rigid design (coarse to fine); ``(X, mode, solver)`` if it passes every family of
    the non-rigid problem, else None."""
    big = prob.req.rows * prob.req.cols >= VIA_RIGID_TILES
    # no full-solver second opinion on a big rigid problem at this level (its coarse levels keep theirs): at
    # 32x32 it took about 45 of the 52 CPU s of a heart and lost (the non-rigid full solver below still takes
    # over when the rigid design fails a non-rigid check); below that it is the CLI's last resort, kept whole
    sub = replace(prob.req, rigid=True, init="coarse" if big else "rescaled", name="",
                  second_opinion=prob.req.second_opinion and not big)
    log("non-rigid design from the rigid family (a rigid member satisfies every non-rigid equality)")
    # a big design keeps the rigid auto rules on its coarse levels only: main's 32x32 heart went on to the full
    # solver on the rigid problem when its reduced design failed a family check, stopped at 5e-5, then the
    # non-rigid one at 6e-3 (14 % off, 66 CPU s). Next, the reduced solver alone down the coarse levels (1.37 %).
    first = replace(sub, solver="reduced", coarse_solver="auto") if big else sub
    for tag, attempt in (("rigid", first), ("rigid_reduced", replace(sub, solver="reduced"))):
        res = _design(attempt, False)
        iters.update({f"{tag}_{k}": v for k, v in res.report["iterations"].items()})
        X = res.pattern.nodes / prob.L0
        if res.converged and _acceptable(prob, X):
            return X, res.report["shape_matching"], res.report["solver"]
        log(f"the {'rigid-family' if tag == 'rigid' else 'reduced-only'} design fails a non-rigid family check "
            f"({_why_not(prob, X)})")
    log("the full solver takes over")
    return None


def reduced_applies(req: DesignRequest) -> bool:
    """The closed-form rigid family covers the request (see ``rigid.py``)."""
    return (req.rigid and req.holes == "rhombus" and not req.symmetry and not req.contracted
            and req.target is not None)


def _objective(prob: _Problem, X: np.ndarray) -> float:
    """Σ fit² + w E_reg: what both solvers minimise over the feasible set."""
    return sum(energy(f, X) for f in prob.of("fit")) + prob.req.reg_weight * sum(energy(f, X) for f in prob.of("reg"))


def _acceptable(prob: _Problem, X: np.ndarray) -> bool:
    res = family_residuals(prob, X, _mean_edge(prob, X))
    worst = max((res[f.name] for f in prob.of("eq")), default=0.0)
    return worst <= prob.req.tol and float(_ineq_values(prob, X).min(initial=0.0)) >= 0.0


def _why_not(prob: _Problem, X: np.ndarray) -> str:
    """The worst equality family and the smallest inequality, for the log."""
    res = family_residuals(prob, X, _mean_edge(prob, X))
    eq = max(((res[f.name], f.name) for f in prob.of("eq")), default=(0.0, "none"))
    g = min(((float(f.residual(X).min(initial=0.0)), f.name) for f in prob.of("ineq")), default=(0.0, "none"))
    return f"worst equality {eq[1]} {eq[0]:.1e}, smallest inequality {g[1]} {g[0]:.1e}"


def _outline_misses(prob: _Problem, X: np.ndarray, above: float, log) -> bool:
    """Whether the deployed outline's Hausdorff distance to the target (``design/conformance.py``, the measure
    ``--shape-tol`` judges) exceeds ``above`` of the target's size: below it the full solver's second opinion
    is skipped. With the outline fit it reached the same outline at 8x8 on circle, ellipse, superellipse,
    hexagon and heart (Hausdorff within 0.005 % of the size) for 4-6x the rigid family's time."""
    pat = Pattern(nodes=X[: prob.n] * prob.L0, tiles=prob.std.tiles)
    h = deployed_conformance(pat.nodes, pat.topology, prob.req.target)["hausdorff_rel"]
    if h <= above:
        log(f"rigid family outline within {h:.2%} of the target size (<= {above:.2%}): no second opinion")
    return h > above


def _solve_reduced(prob: _Problem, log, iters: dict):
    """Solve in the rigid family; ``(X, mode)`` if every family checks out, else None."""
    req = prob.req
    fam = prob.rigid_family
    log(f"rigid family: {2 * fam.n_seeds + 1} reduced unknowns ({fam.n_seeds} seed points and ψ)")
    # the standard starts sit at ψ = π/4; a coarse-to-fine or warm start at whatever it opened to
    psi0 = RigidFamily.deployment_angle(prob.X0, prob.st) if prob.coarse or req.start is not None else np.pi / 4
    S0 = None
    if prob.start_member is not None and prob.coarse and prob.coarse["used"]:
        S0, psi0 = prob.start_member[0] / prob.L0, prob.start_member[1]
    X, mode, its = solve_reduced(fam, prob.st, prob.X0, psi0, prob.families, prob.margin, req.reg_weight,
                                 0.1 * req.tol * _mean_edge(prob, prob.X0), lambda Y: _mean_edge(prob, Y), log,
                                 max_iter=req.max_iter,
                                 # small patterns get the full solver's second opinion anyway
                                 miss_tol=np.inf if req.rows * req.cols <= FULL_ALWAYS_TILES else FULL_ABOVE,
                                 S0=S0)
    iters.update(its)
    if _acceptable(prob, X) or req.solver == "reduced":
        return X, mode
    log("the rigid family's result fails a family check: falling back to the full solver")
    return None


def _solve_outline(prob: _Problem, log, iters: dict, solver=None):
    """Square/circle closed-state outlines in the rigid family (``outline.py``); ``(X, mode)`` or None.

    A circle target is size-free: its state's target becomes the fitted circle (centre and radius), so the
    report and the CLI's outline check measure against that circle.
    """
    res = (solver or outline.solve_outline)(prob, log, iters)
    if res is None:
        return None
    X, mode, fitted = res
    saved = dict(prob.curves_mm), list(prob.families)
    M, N = prob.req.rows, prob.req.cols
    for s, (centre, radius) in fitted.items():
        g = prob.grids[s]
        # the fitted circle, split into its four arcs at the directions of the grid's corners (BL, BR, TR, TL)
        corners = X[g.offset + np.array([0, N, (M + 1) * (N + 1) - 1, M * (N + 1)])] - centre
        unit = prob.req.contracted[s]
        lo, hi = unit.bbox
        start = unit.points[0] - 0.5 * (lo + hi)  # a circle's parameter is its angle from the first point over 2π
        u = np.mod((np.arctan2(corners[:, 1], corners[:, 0]) - np.arctan2(start[1], start[0])) / (2 * np.pi), 1.0)
        pts = (unit.points - 0.5 * (lo + hi)) * (radius * prob.L0 / (0.5 * float((hi - lo).max()))) + centre * prob.L0
        mm = Target(unit.name, unit.kind, pts, corners=u, source=dict(unit.source))
        prob.curves_mm[s] = mm
        prob.families = [C.shape_match(g.boundary, g.boundary_side, mm.transformed(1.0 / prob.L0), prob.nv,
                                       f.name) if f.name == f"closed_shape_{s}" else f for f in prob.families]
    if _acceptable(prob, X):
        return X, mode
    log("the closed-state outline design fails a family check: falling back to the full solver "
        f"({_why_not(prob, X)})")
    prob.curves_mm, prob.families = saved
    return None


def _solve_full(prob: _Problem, log, iters: dict):
    """Penalty LM stages then projection (module docstring); returns ``(X, mode)``."""
    req = prob.req

    def eq_max(Y):
        return max((float(np.abs(f.residual(Y)).max()) for f in prob.of("eq")), default=0.0)

    eqs = prob.of("eq")
    fits = exact_fits(prob.of("fit"))

    def project(X):
        """Projection onto c = 0 (and s = 0 when the fit is nearly exact); returns X, mode, iterations."""
        L = _mean_edge(prob, X)
        tol_abs = lambda fams: min(req.tol * L ** f.dim for f in fams)  # noqa: E731
        fit_rel = max((float(np.abs(f.residual(X)).max()) / L for f in fits), default=0.0)
        if fits and fit_rel < 1e-2:
            # the least-squares fit is (nearly) exact: try to make it exact
            Xh, kh = _lm(prob, X, 0.0, 50, log, hard=eqs + fits + prob.of("ineq"),
                         tol_inf=0.1 * tol_abs(eqs + fits))
            if all(v <= req.tol for v in family_residuals(prob, Xh, _mean_edge(prob, Xh)).values()):
                return Xh, "hard", kh
        Xp, kp = _lm(prob, X, 0.0, 50, log, hard=eqs + prob.of("ineq"), tol_inf=0.1 * tol_abs(eqs))
        if max((float(np.abs(f.residual(Xp)).max()) for f in eqs), default=0.0) > 0.1 * tol_abs(eqs):
            # the half margins may block the last steps: project on the equalities alone (steps that
            # would violate g >= 0 are still halved or refused)
            Xq, kq = _lm(prob, Xp, 0.0, 50, log, hard=eqs, tol_inf=0.1 * tol_abs(eqs))
            return Xq, "least-squares", kp + kq
        return Xp, "least-squares", kp

    first = COARSE_PENALTIES if prob.coarse is not None and prob.coarse["used"] else PENALTIES
    best = None
    for attempt, schedule in enumerate((first, STIFF_PENALTIES)):
        tag = "_restart" if attempt else ""
        X = prob.X0.copy()
        for rho, stall_tol, cap in schedule:
            X, k = _lm(prob, X, rho, min(cap, req.max_iter), log, stall_tol=stall_tol)
            iters[f"lm_rho_{rho:g}{tag}"] = k
            log(f"rho={rho:g}: {k} iterations, max equality row {eq_max(X):.2e}")
        if attempt == 0 and eq_max(X) > RESTART_ABOVE:
            # the fit dragged the pattern off the constraint manifold into a wall of inequalities:
            # start again keeping the constraints stiff from the first step
            log(f"max equality row {eq_max(X):.2e} > {RESTART_ABOVE:g}: restarting with stiff penalties")
            continue
        Xp, mode, kp = project(X)
        iters[f"projection{tag}"] = kp
        res = family_residuals(prob, Xp, _mean_edge(prob, Xp))
        worst = max((res[f.name] for f in eqs), default=0.0)
        if best is None or worst < best[0]:
            best = (worst, Xp, mode)
        if worst <= req.tol:
            break
        log(f"projection stopped at {worst:.2e} > tol: " + ("restarting with stiff penalties" if not attempt
                                                             else "giving up"))
    _, X, mode = best
    return X, mode


def _design(req: DesignRequest, progress: bool) -> DesignResult:
    log = _Log(progress)
    c0 = time.process_time()
    if offset_outline.covers(req) and not offset_outline.applies(req):
        log(f"parallelogram holes above {offset_outline.OFFSET_MAX_TILES} tiles: rhombus holes (zero offsets)")
        return _design(replace(req, holes="rhombus"), progress)
    t0 = time.perf_counter()
    # a non-rigid request answered by the rigid family needs no guess of its own (least of all a coarse solve)
    prob = _Problem(replace(req, init="rescaled") if via_rigid_applies(req) else req)
    log(f"{req.rows}x{req.cols} tiles, {2 * prob.nv} unknowns, families: "
        + ", ".join(f.name for f in prob.families))
    iters: dict = {}
    eqs = prob.of("eq")
    fits = prob.of("fit")
    reduced_name = "closed-form rigid family (reduced Levenberg-Marquardt)"
    full_name = "sparse Levenberg-Marquardt (penalty continuation) + Gauss-Newton projection, SuperLU"
    out = None
    if req.solver != "full" and reduced_applies(req):
        out = _solve_reduced(prob, log, iters)
    solver = reduced_name
    if out is not None and req.solver == "auto" and req.second_opinion and out[1] != "hard":
        miss = fit_miss(exact_fits(fits), out[0])
        if miss > FULL_ABOVE and req.rows * req.cols > FULL_MAX_TILES:
            log(f"rigid family fit misses by {miss:.2%} of the target size; the full solver is not tried above "
                f"{FULL_MAX_TILES} tiles (--solver full forces it; --init coarse helps large lattices)")
        elif miss > FULL_ABOVE and req.rows * req.cols > FULL_ALWAYS_TILES or (
                req.rows * req.cols <= FULL_ALWAYS_TILES and _outline_misses(prob, out[0], req.second_opinion_above,
                                                                             log)):
            log(f"rigid family fit is least-squares (misses by {miss:.2%} of the target size): "
                f"trying the full solver too")
            full = _solve_full(prob, log, iters)
            f_red, f_full = _objective(prob, out[0]), _objective(prob, full[0])
            ok_full = _acceptable(prob, full[0])
            log(f"objective: rigid family {f_red:.4e}, full {f_full:.4e}" + ("" if ok_full else " (unconverged)"))
            if ok_full and f_full < f_red:
                out, solver = full, full_name
    rigid_first = False  # the answer is the rigid family's, tried first (the API stops its guesses there)
    if out is None and rigid_first_applies(req):
        first = _solve_rigid_first(prob, log, iters)
        if first is not None:
            out, solver, rigid_first = first[:2], f"{first[2]}, for a non-rigid request (rigid family first)", True
    if out is None and via_rigid_applies(req):
        via = _solve_via_rigid(prob, log, iters)
        if via is not None:
            out, solver = via[:2], f"{via[2]}, for a non-rigid request"
    if out is None and req.solver == "auto" and outline.applies(req):
        out = _solve_outline(prob, log, iters)
        solver = "closed-form rigid family, closed-state outlines (exact square, size-free circle)"
    if out is None and offset_outline.applies(req):
        out = _solve_outline(prob, log, iters, offset_outline.solve_offset_outline)
        if out is None:  # no other solver takes parallelogram holes with closed-state curves
            log("the parallelogram-hole outline design failed its checks: designing with rhombus holes")
            return _design(replace(req, holes="rhombus"), progress)
        solver = ("closed-form rigid family with parallelogram holes (an offset per hole), closed-state "
                  "outlines (exact square, size-free circle)")
    if out is None:
        out = _solve_full(prob, log, iters)
        solver = full_name
    X, mode = out
    fits = prob.of("fit")  # again: a size-free circle replaces its state's fit family with the fitted circle
    L = _mean_edge(prob, X)
    res = family_residuals(prob, X, L)
    eq_worst = max((res[f.name] for f in eqs), default=0.0)
    gvals = {f.name: f.residual(X) for f in prob.of("ineq")}
    ineq_min = min((float(v.min()) for v in gvals.values()), default=0.0)
    active = {k: int((v < prob.margin[k] + 1e-6 * L * L).sum()) for k, v in gvals.items()}
    converged = eq_worst <= req.tol and ineq_min >= 0.0
    elapsed = time.perf_counter() - t0
    L0 = prob.L0
    Xmm = X * L0
    fit = {}
    for f in fits:
        f = f.meta.get("unweighted", f)
        r = f.residual(X)
        fit[f.name] = {"max_mm": float(np.abs(r).max()) * L0, "rms_mm": float(np.sqrt(np.mean(r * r))) * L0,
                       "max_rel_size": float(np.abs(r).max()) / f.meta["target"].size,
                       "points": int(len(r)), "soft": bool(f.meta.get("soft"))}
    report = {
        "status": "converged" if converged else "unconverged",
        "tolerance": req.tol,
        "max_equality_residual": eq_worst,
        "residuals": res,
        "residual_units": "lengths relative to the mean tile edge, angles in radians",
        "iterations": iters,
        "iterations_total": int(sum(iters.values())),
        "time_s": elapsed,
        "cpu_s": time.process_time() - c0,  # on a loaded machine wall time says more about the neighbours
        "unknowns": 2 * prob.nv,
        "equations": int(sum(len(f.residual(X)) for f in eqs)),
        "shape_matching": mode if fits else "none",
        "fit": fit,
        "min_inequality": ineq_min / (L * L),
        "active_inequalities": active,
        "regularizer": energy(prob.of("reg")[0], X),
        "factorisations": prob._normal.factorisations if prob._normal else 0,
        "cg_iterations": prob._normal.cg_steps if prob._normal else 0,
        "coarse": prob.coarse,
        "solver": solver,
        "rigid_first": rigid_first,
    }
    fab_names = [f.name for f in prob.of("ineq") if f.name.startswith("fabrication_")]
    if fab_names:  # the fabrication family: its rows, how many are active, the smallest (mm)
        report["fabrication"] = {"limits": req.fabrication.to_dict(), "rows": {k: int(len(gvals[k])) for k in fab_names},
                                 "active": {k: active[k] for k in fab_names},
                                 # smallest row: mm for lengths, a sine for the hinge angles
                                 "min": {k: float(gvals[k].min()) * (L0 if "angle" not in k else 1.0)
                                         for k in fab_names}}
    log(f"{report['status']}: max equality residual {eq_worst:.2e}, fit {mode}, "
        f"{report['iterations_total']} iterations, {elapsed:.2f}s")
    lat = {"kind": "quad", "rows": req.rows, "cols": req.cols, "angle_deg": 45.0,
           "tile_size": float(L * L0)}
    options = {"rigid": req.rigid, "symmetry": req.symmetry, "holes": req.holes, "init": req.init,
               "tol": req.tol, "reg_weight": req.reg_weight, **({"seed": req.seed} if req.seed is not None else {}),
               **({"fabrication": dict(req.fabrication_intent)} if req.fabrication_intent else {}),
               "contracted": {str(s): (v.name if isinstance(v, Target) else
                                       ({"rectangle": True, "ratio": v[1]})) for s, v in req.contracted.items()}}
    design_meta = {"options": options, "report": report}
    if req.target is not None:
        design_meta["target"] = req.target.to_dict()
    if req.contracted:
        design_meta["contracted_targets"] = {str(s): v.to_dict() for s, v in prob.curves_mm.items()}
    nodes = Xmm[: prob.n]
    pattern = Pattern(nodes=nodes, tiles=prob.std.tiles, name=req.name or "design", lattice=lat,
                      design=design_meta)
    grids = {s: Xmm[g.offset: g.offset + g.n_vertices] for s, g in prob.grids.items()}
    return DesignResult(pattern=pattern, report=report, converged=converged, closed_grids=grids,
                        closed_targets=prob.curves_mm)
