"""The inverse-design solvers.

``--rigid`` designs with rhombus holes (no symmetry, no closed-state targets)
are solved in the closed-form rigid family (``rigid/family.py``, ``rigid/reduced.py``);
``_design`` tries the routes (``routes.py``) in order and says when the full
solver is asked as well. The full solver (``penalty.py``):
sparse Levenberg-Marquardt with penalty continuation and a final Gauss-Newton
projection onto the equality manifold.

Why this design (see ``docs/design-solver.md``): the reconfigurable constraint
set has dependent and redundant rows at every feasible point (rank deficit of
about one row per hole, docs/algorithm.md#reconfigurability), which breaks LICQ-based NLP solvers
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

This module is the front door: the request and result types live in
``request.py``, the problem's families in ``problem.py``, the normal equations
in ``normal.py``; their names stay importable from here.
"""

from __future__ import annotations

import contextlib
import sys
import time
from dataclasses import replace

import numpy as np

from ... import blas
from ...pattern.model import Pattern
from ..core.conformance import deployed as deployed_conformance
from ..core.request import (  # noqa: F401  (re-exported: callers import these from here)
    SOLVERS,
    VIA_RIGID_FIRST_TILES,
    VIA_RIGID_INIT,
    VIA_RIGID_TILES,
    DesignRequest,
    DesignResult,
    coarse_refit_applies,
    reduced_applies,
    rigid_first_applies,
    via_rigid_applies,
)
from ..targets.lookup import Target
from .measures import (  # noqa: F401  (re-exported: callers import these from here)
    _acceptable,
    _ineq_values,
    _mean_edge,
    _objective,
    _why_not,
    family_residuals,
)
from .objective import energy
from .penalty import _solve_full
from .problem import CONVEX_MARGIN, GAP_MARGIN, DesignProblem  # noqa: F401  (re-exported)
from .rigid import offset_outline, outline
from .routes import (
    FULL_NAME,
    REDUCED_NAME,
    _mirrored_starts,
    _second_opinion,
    _solve_outline,
    _solve_reduced,
    _solve_rigid_first,
    _solve_via_rigid,
)

_BLAS = None  # one controller per process: finding the loaded BLAS libraries is slow


def single_thread_blas():
    """Context manager that limits BLAS to one thread: the solver's vector operations are too small to gain from
    threads, and on a loaded machine OpenBLAS threads contend. A no-op where OpenBLAS started with one thread
    (the CLI starts it so, ``fabkiri/blas.py``) and without threadpoolctl."""
    global _BLAS
    if blas.single_threaded():
        return contextlib.nullcontext()
    if _BLAS is None:
        try:
            from threadpoolctl import ThreadpoolController
        except ImportError:  # pragma: no cover
            return contextlib.nullcontext()
        _BLAS = ThreadpoolController()
    return _BLAS.limit(limits=1, user_api="blas")


class _Log:
    def __init__(self, progress):
        self.progress = progress
        self.t0 = time.perf_counter()

    def __call__(self, msg: str) -> None:
        if self.progress:
            print(
                f"[design {time.perf_counter() - self.t0:7.2f}s] {msg}", file=sys.stderr, flush=True
            )


def design(req: DesignRequest, progress: bool = False) -> DesignResult:
    """Solve the inverse-design problem ``req``; never raises on non-convergence."""
    req.validate()
    with single_thread_blas():
        return _design(req, progress)


def design_problem(req: DesignRequest) -> DesignProblem:
    """The full problem of ``req`` with this module's designer for its coarse levels and rigid routes."""
    return DesignProblem(req, _design)


def _design(req: DesignRequest, progress: bool) -> DesignResult:
    log = _Log(progress)
    c0 = time.process_time()
    if offset_outline.covers(req) and not offset_outline.applies(req):
        log(
            f"parallelogram holes above {offset_outline.OFFSET_MAX_TILES} tiles: rhombus holes (zero offsets)"
        )
        return _design(replace(req, holes="rhombus"), progress)
    t0 = time.perf_counter()
    # a non-rigid request answered by the rigid family needs no guess of its own (least of all a coarse solve)
    prob = DesignProblem(replace(req, init="rescaled") if via_rigid_applies(req) else req, _design)
    log(
        f"{req.rows}x{req.cols} tiles, {2 * prob.nv} unknowns, families: "
        + ", ".join(f.name for f in prob.families)
    )
    iters: dict = {}
    picked = _solve(req, prob, log, iters)
    if picked is None:  # no other solver takes parallelogram holes with closed-state curves
        log("the parallelogram-hole outline design failed its checks: designing with rhombus holes")
        return _design(replace(req, holes="rhombus"), progress)
    (X, mode), solver, rigid_first = picked
    report = _report(req, prob, X, mode, solver, rigid_first, iters, t0, c0)
    log(
        f"{report['status']}: max equality residual {report['max_equality_residual']:.2e}, fit {mode}, "
        f"{report['iterations_total']} iterations, {report['time_s']:.2f}s"
    )
    return _coarse_refit(req, prob, _result(req, prob, X, report), progress, log)


def _coarse_refit(
    req: DesignRequest, prob: DesignProblem, result: DesignResult, progress: bool, log
) -> DesignResult:
    """A coarse-to-fine design whose outline misses the shape tolerance (``second_opinion_above``) is designed
    again with its coarse levels refitted where their tips-only outline misses it (``coarse_refit``); the
    converged design with the closer outline is kept. Not every time: from a better coarse start the 32x32 heart
    ended at 3.96 % instead of 1.61 %, while the drop's 64x64 design went from 22.16 % to 0.22 %."""
    # (a mirrored level has the outline rows already, ``DesignProblem._coarse_level``: it would be the same design)
    if not (req.coarse_refit_on_miss and coarse_refit_applies(req, prob.coarse)):
        return result
    assert req.target is not None
    h = deployed_conformance(result.pattern.nodes, result.pattern.topology, req.target)
    if result.converged and h["hausdorff_rel"] <= req.second_opinion_above:
        return result
    log(
        f"outline misses by {h['hausdorff_rel']:.2%} of the target size from the tips-only coarse levels: "
        "again with the coarse levels that miss refitted with the outline rows"
    )
    alt = _design(replace(req, coarse_refit=True), progress)
    h_alt = deployed_conformance(alt.pattern.nodes, alt.pattern.topology, req.target)
    keep = (
        alt
        if (not alt.converged, h_alt["hausdorff_rel"]) < (not result.converged, h["hausdorff_rel"])
        else result
    )
    keep.report["coarse_refit"] = {
        "tips_only_hausdorff_rel": h["hausdorff_rel"],
        "refit_hausdorff_rel": h_alt["hausdorff_rel"],
        "kept": "refit" if keep is alt else "tips_only",
    }
    for k in ("time_s", "cpu_s"):  # both designs' time
        keep.report[k] = result.report[k] + alt.report[k]
    return keep


def _solve(req: DesignRequest, prob: DesignProblem, log, iters: dict):
    """The routes in order, until one answers: ``((X, mode), solver name, rigid_first)``.

    ``req`` is the caller's request, not ``prob.req`` (a via-rigid problem is built from rescaled). None when
    the parallelogram-hole outline design fails (the caller designs with rhombus holes).
    """
    out = None
    if req.solver != "full" and reduced_applies(req):
        out = _solve_reduced(prob, log, iters)
    solver = REDUCED_NAME
    # no full-solver second opinion for a symmetric design: over all nodes with the symmetry rows it is what
    # took minutes (16x16 heart, and missed); its 12x12 coarse level cost most of that and lost.
    # The reduced solver from the other guesses instead (``routes._mirrored_starts``).
    if out is not None and req.solver == "auto" and req.second_opinion and out[1] != "hard":
        if not req.symmetry:
            out, solver = _second_opinion(req, prob, out, log, iters)
        else:
            out = _mirrored_starts(prob, out, log, iters)
    rigid_first = (
        False  # the answer is the rigid family's, tried first (the API stops its guesses there)
    )
    if out is None and rigid_first_applies(req):
        first = _solve_rigid_first(prob, log, iters)
        if first is not None:
            out, solver, rigid_first = (
                first[:2],
                f"{first[2]}, for a non-rigid request (rigid family first)",
                True,
            )
    if out is None and via_rigid_applies(req):
        via = _solve_via_rigid(prob, log, iters)
        if via is not None:
            out, solver = via[:2], f"{via[2]}, for a non-rigid request"
    if out is None and req.solver == "auto" and outline.applies(req):
        out = _solve_outline(prob, log, iters)
        solver = "closed-form rigid family, closed-state outlines (exact square, size-free circle)"
    if out is None and offset_outline.applies(req):
        out = _solve_outline(prob, log, iters, offset_outline.solve_offset_outline)
        if out is None:
            return None
        solver = (
            "closed-form rigid family with parallelogram holes (an offset per hole), closed-state "
            "outlines (exact square, size-free circle)"
        )
    if out is None:
        out = _solve_full(prob, log, iters)
        solver = FULL_NAME
    return out, solver, rigid_first


def _fit_report(prob: DesignProblem, X: np.ndarray) -> dict:
    """Per fit family: max and rms distance (mm), max over the target's size, points, soft (unweighted rows)."""
    fit = {}
    # the families now: a size-free circle replaces its state's fit family with the fitted circle
    for f in prob.of("fit"):
        f = f.meta.get("unweighted", f)
        r = f.residual(X)
        fit[f.name] = {
            "max_mm": float(np.abs(r).max()) * prob.L0,
            "rms_mm": float(np.sqrt(np.mean(r * r))) * prob.L0,
            "max_rel_size": float(np.abs(r).max()) / f.meta["target"].size,
            "points": int(len(r)),
            "soft": bool(f.meta.get("soft")),
        }
    return fit


def _report(
    req: DesignRequest,
    prob: DesignProblem,
    X: np.ndarray,
    mode: str,
    solver: str,
    rigid_first: bool,
    iters: dict,
    t0: float,
    c0: float,
) -> dict:
    """The design's report: status, residuals, iterations, times, fit, inequalities and fabrication rows."""
    eqs = prob.of("eq")
    L = _mean_edge(prob, X)
    res = family_residuals(prob, X, L)
    eq_worst = max((res[f.name] for f in eqs), default=0.0)
    gvals = {f.name: f.residual(X) for f in prob.of("ineq")}
    ineq_min = min((float(v.min()) for v in gvals.values()), default=0.0)
    active = {k: int((v < prob.margin[k] + 1e-6 * L * L).sum()) for k, v in gvals.items()}
    converged = eq_worst <= req.tol and ineq_min >= 0.0
    elapsed = time.perf_counter() - t0
    fit = _fit_report(prob, X)
    report = {
        "status": "converged" if converged else "unconverged",
        "tolerance": req.tol,
        "max_equality_residual": eq_worst,
        "residuals": res,
        "residual_units": "lengths relative to the mean tile edge, angles in radians",
        "iterations": iters,
        "iterations_total": int(sum(iters.values())),
        "time_s": elapsed,
        "cpu_s": time.process_time()
        - c0,  # on a loaded machine wall time says more about the neighbours
        "unknowns": 2 * prob.nv,
        "equations": int(sum(len(f.residual(X)) for f in eqs)),
        "shape_matching": mode if prob.of("fit") else "none",
        "fit": fit,
        "min_inequality": ineq_min / (L * L),
        "active_inequalities": active,
        "regularizer": energy(prob.of("reg")[0], X),
        "factorisations": prob._normal.factorisations if prob._normal else 0,
        "cg_iterations": prob._normal.cg_steps if prob._normal else 0,
        "coarse": prob.coarse if prob.coarse is not None else prob.via_coarse,
        "solver": solver,
        "rigid_first": rigid_first,
    }
    fab_names = [f.name for f in prob.of("ineq") if f.name.startswith("fabrication_")]
    if (
        fab_names and req.fabrication is not None
    ):  # the fabrication family: its rows, how many are active, the smallest (mm)
        report["fabrication"] = {
            "limits": req.fabrication.to_dict(),
            "rows": {k: int(len(gvals[k])) for k in fab_names},
            "active": {k: active[k] for k in fab_names},
            # smallest row: mm for lengths, a sine for the hinge angles
            "min": {
                k: float(gvals[k].min()) * (prob.L0 if "angle" not in k else 1.0) for k in fab_names
            },
        }
    return report


def _result(req: DesignRequest, prob: DesignProblem, X: np.ndarray, report: dict) -> DesignResult:
    """The deployed pattern in mm, its lattice, options (``req``'s, not ``prob.req``'s) and report, closed grids."""
    L0 = prob.L0
    Xmm = X * L0
    lat = {
        "kind": "quad",
        "rows": req.rows,
        "cols": req.cols,
        "angle_deg": 45.0,
        "tile_size": float(_mean_edge(prob, X) * L0),
    }
    options = {
        "rigid": req.rigid,
        "symmetry": req.symmetry,
        "holes": req.holes,
        "init": req.init,
        "tol": req.tol,
        "reg_weight": req.reg_weight,
        **({"seed": req.seed} if req.seed is not None else {}),
        **({"min_opening": req.min_opening} if req.min_opening else {}),
        **({"fabrication": dict(req.fabrication_intent)} if req.fabrication_intent else {}),
        "contracted": {
            str(s): (v.name if isinstance(v, Target) else ({"rectangle": True, "ratio": v[1]}))
            for s, v in req.contracted.items()
        },
    }
    design_meta = {"options": options, "report": report}
    if req.target is not None:
        design_meta["target"] = req.target.to_dict()
    if req.contracted:
        design_meta["contracted_targets"] = {str(s): v.to_dict() for s, v in prob.curves_mm.items()}
    pattern = Pattern(
        nodes=Xmm[: prob.n],
        tiles=prob.std.tiles,
        name=req.name or "design",
        lattice=lat,
        design=design_meta,
    )
    grids = {s: Xmm[g.offset : g.offset + g.n_vertices] for s, g in prob.grids.items()}
    return DesignResult(
        pattern=pattern,
        report=report,
        converged=report["status"] == "converged",
        closed_grids=grids,
        closed_targets=prob.curves_mm,
    )
