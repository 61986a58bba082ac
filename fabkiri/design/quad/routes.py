"""The rigid-family routes of the design solver: each answers a request, or says None and the next one tries.

``_solve_reduced`` solves a rigid request in the closed-form family (and
``_second_opinion`` asks the full solver too where that family's fit is
least-squares); ``_solve_rigid_first`` and ``_solve_via_rigid`` answer a
non-rigid request with a rigid member; ``_solve_outline`` fits square/circle
closed-state outlines. Each returns ``(X, mode)`` (tile units) or None.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from ...errors import SolveError
from ...pattern.model import Pattern
from ..core.conformance import deployed as deployed_conformance
from ..core.request import FINISH_FLOOR, VIA_RIGID_TILES, coarse_refit_applies
from ..targets.lookup import Target
from . import constraints as C
from .constraints import exact_fits
from .initial import initial_guess
from .measures import _acceptable, _mean_edge, _objective, _why_not
from .penalty import _solve_full
from .problem import RIGID_FIRST_GOOD, DesignProblem
from .rigid import outline
from .rigid.family import RigidFamily
from .rigid.mirror import Mirror
from .rigid.reduced import (
    MEMBER_STAGE,
    MEMBER_STAGE_KEPT,
    POLISH_STEPS,
    SCALINGS,
    ReducedSearch,
    solve_reduced,
)
from .rigid.steps import fit_miss

REDUCED_NAME = "closed-form rigid family (reduced Levenberg-Marquardt)"
FULL_NAME = "sparse Levenberg-Marquardt (penalty continuation) + Gauss-Newton projection, SuperLU"
POLISHED = ", its first schedule's end taken to the rigid family (reduced Levenberg-Marquardt)"
# auto: a least-squares fit from the rigid family also gets the full solver when the pattern is small
# (up to FULL_ALWAYS_TILES) and its outline misses ``second_opinion_above`` (the CLI's --shape-tol), or
# when it misses the target by more than FULL_ABOVE of its size; the lower objective wins. The family's LM
# often stops in a worse local minimum on non-convex or elongated targets (rigid 100 mm, 16x16 rectangle
# 0.088 vs 0.022 mm, 8x8 heart 0.42 vs 0.15 mm), while on the rigid circle both reach the same fit (32x32
# 0.16 vs 0.14 mm, 64x64 0.22 vs 0.21 mm) and the full solver would only cost time.
FULL_ALWAYS_TILES = 16 * 16
FULL_ABOVE = 2.5e-3
# ... but not above this many tiles: at 64x64 the full solver is very slow and did not find the better
# design on hard targets (rigid heart from rescaled: 21.6 mm either way; ellipse: 7.4 mm)
FULL_MAX_TILES = 32 * 32
# the rigid-first route (``request.VIA_RIGID_FIRST_TILES``): its starts, and the outline that ends the search
RIGID_FIRST_INITS = ("coarse", "rescaled")
# ... and up to this many tiles, where no reduced member meets the shape, the rigid design with the full
# solver's second opinion next (the CLI's last guess, ``_solve_via_rigid``), before the full solver over all
# nodes: the 16x16 heart (100 mm) went through the conformal, rescaled and standard full solves (missed,
# missed, unconverged) before the rigid design met it (1.77 %)
RIGID_FULL_FIRST_TILES = 16 * 16
# a symmetric design gets no full-solver second opinion (over all nodes with the symmetry rows it took
# minutes on a 16x16 heart, and missed); instead the reduced solver over half the seeds from these
# guesses too, cheap each (8x8 rigid heart, tips fit, misses by: rescaled 2.56 %,
# conformal 1.05 %, standard 0.20 % of the size)
MIRRORED_STARTS = ("standard", "conformal", "rescaled")
# ... standard first (the start kept most often), until the best would ask for no second opinion: the peanut's
# 32x32 level of its 64x64 chain missed by 0.66 %, and only standard met 0.25 %, after rescaled and conformal
# with both scalings each (standard first cut that level's time by two thirds, the same start kept). Kept by
# the closest outline instead of the objective up to 16x16 tiles: the symmetric 32x32 drop 0.84 -> 0.31 %, but
# the 64x64 star 0.19 -> 0.45 %; not kept

# the lattices (tiles, least and most) whose top level, started from its coarse design, tries the stiffer stage
# alone first (``MEMBER_STAGE``): measured closer at 48x48 and 64x64 (the rigid circle 0.214 -> 0.197 % at 64),
# further at 96x96 and 128x128 (forming the regulariser block at every step; above ``KEEP_BLOCK_TILES`` a level that
# keeps it tries ``MEMBER_STAGE_KEPT``); never on a coarse level, which would change the start of the level above
MEMBER_STAGE_TILES = (48 * 48, 64 * 64)
# above this many tiles the lattice asked for and its coarse levels (not a symmetric design, nor a contact
# rerun) keep each stage's regulariser grid block (``steps.stage``, ``keeps_block``): there forming it is most of
# a step; issue #37's table (up to 96x96) keeps the block formed at every step
KEEP_BLOCK_TILES = 96 * 96


def keeps_block(prob: DesignProblem) -> bool:
    """Whether ``prob``'s reduced search keeps each stage's regulariser grid block: a lattice of a chain above
    ``KEEP_BLOCK_TILES`` tiles started from a coarse level fitted by its tips alone within ``FINISH_FLOOR`` of the
    size (not a rescaled bottom). From a level further off (``api/design_minimax``: the tips missing, a rescaled
    bottom, a level past the rigid gate) the design is the start of a minimax finish whose steps stop at the
    first that comes no closer, so a start moved by the kept block moves where they stop (the 128x128 rigid star,
    0.0246 -> 0.0311 %, docs/speed.md, "Session 51 (big51)"); a warm-started finish step has no coarse level."""
    req, level = prob.req, prob.coarse or {}
    return (
        (req.chain_tiles or req.rows * req.cols) > KEEP_BLOCK_TILES
        and bool(level.get("used"))
        and level.get("fit") == "tips"
        and not level.get("rescaled_bottom")
        and level.get("hausdorff_rel", np.inf) <= FINISH_FLOOR
    )


def _solve_reduced(prob: DesignProblem, log, iters: dict):
    """Solve in the rigid family; ``(X, mode)`` if every family checks out, else None."""
    req = prob.req
    fam = prob.rigid_family
    log(f"rigid family: {2 * fam.n_seeds + 1} reduced unknowns ({fam.n_seeds} seed points and ψ)")
    X, mode = _reduced_from(prob, *_start(prob), log, iters, "")
    if _acceptable(prob, X) or req.solver == "reduced":
        return X, mode
    log("the rigid family's result fails a family check: falling back to the full solver")
    return None


def _start(prob: DesignProblem) -> tuple[np.ndarray, float, np.ndarray | None]:
    """``(X0, ψ0, S0)``: the reduced solver's start (seeds ``S0`` when the start is a member already)."""
    # the standard starts sit at ψ = π/4; a coarse-to-fine or warm start at whatever it opened to
    psi0 = (
        RigidFamily.deployment_angle(prob.X0, prob.st)
        if prob.coarse or prob.req.start is not None
        else np.pi / 4
    )
    if prob.start_member is not None and prob.coarse and prob.coarse["used"]:
        return prob.X0, prob.start_member[1], prob.start_member[0] / prob.L0
    return prob.X0, psi0, None


def _reduced_from(
    prob: DesignProblem, X0, psi0: float, S0, log, iters: dict, tag: str, scalings=SCALINGS
) -> tuple:
    """``(X, mode)`` of the reduced solver from ``X0`` (or seeds ``S0``) at ``psi0``: over half the seeds
    with ``--symmetry`` (``rigid/mirror.py``). ``tag`` prefixes its iteration counts. The second of
    ``scalings`` only where the first misses by more than ``FULL_ABOVE``, and on small patterns not at all
    (they get the full solver's second opinion, ``_second_opinion``, or ``_mirrored_starts``) unless a tag
    asks for it."""
    req, fam = prob.req, prob.rigid_family
    mirror = None
    if req.symmetry:  # half the seeds (``rigid/mirror.py``)
        mirror = Mirror.build(fam, req.rows, req.cols, req.symmetry)
        log(f"mirror symmetry {req.symmetry}: {mirror.P.shape[1]} reduced unknowns")
    small = req.rows * req.cols <= FULL_ALWAYS_TILES and not tag
    # from a coarse design's member (``_start``), on the lattice asked for only; above the bounds where the level
    # keeps its regulariser block, and nowhere a minimax finish follows (``keeps_block``)
    lo, hi = MEMBER_STAGE_TILES
    keep = not mirror and keeps_block(prob)
    member = None
    if S0 is not None and not req.coarse_level:
        member = (
            MEMBER_STAGE if lo <= req.rows * req.cols <= hi else MEMBER_STAGE_KEPT if keep else None
        )
    X, mode, its = solve_reduced(
        fam,
        prob.st,
        X0,
        psi0,
        prob.families,
        prob.margin,
        ReducedSearch(
            req.reg_weight,
            0.1 * req.tol * _mean_edge(prob, prob.X0),
            lambda Y: _mean_edge(prob, Y),
            log,
            max_iter=req.max_iter,
            miss_tol=np.inf if small else FULL_ABOVE,
            # a finish step: its first scaling, no stiffer stage after a feasible first (``finish_step``)
            scalings=scalings[:1] if req.finish_step else scalings,
            polish_steps=0 if req.finish_step else POLISH_STEPS,
            member=member,
            keep_block=keep,
        ),
        S0=S0,
        mirror=mirror,
    )
    iters.update({tag + k: v for k, v in its.items()})
    return X, mode


def _mirrored_starts(prob: DesignProblem, out: tuple, log, iters: dict) -> tuple:
    """A symmetric design's second opinion, where the full solver's would run (``_second_opinion``: up to
    ``FULL_ALWAYS_TILES`` when the outline misses the shape tolerance, up to ``FULL_MAX_TILES`` when the fit
    misses by more than ``FULL_ABOVE``): the reduced solver over half the seeds from its own start with the
    other LM scaling and from each guess of ``MIRRORED_STARTS`` it did not start from, with both, until the best
    would ask for no second opinion. The best
    ``(X, mode)`` (family checks, then the objective)."""
    req = prob.req
    if not _second_opinion_due(
        req, prob, out[0], lambda: fit_miss(exact_fits(prob.of("fit")), out[0]), log
    ):
        return out

    def rank(X):
        return (not _acceptable(prob, X), _objective(prob, X))

    best = (rank(out[0]), out)
    starts: list[tuple[str, np.ndarray, float, np.ndarray | None, tuple[str, ...]]] = [
        ("again_", *_start(prob), SCALINGS[1:])
    ]
    for init in MIRRORED_STARTS:
        if init == req.init:
            continue
        try:
            X0, L = initial_guess(prob.std.nodes, prob.st, prob.target, init)
        except SolveError as exc:  # a harmonic map that folds tiles
            log(f"mirrored start {init}: {exc}")
            continue
        starts.append((f"{init}_", X0 * (L / prob.L0), np.pi / 4, None, SCALINGS))
    for tag, X0, psi0, S0, scalings in starts:
        X, mode = _reduced_from(prob, X0, psi0, S0, log, iters, tag, scalings)
        log(f"mirrored start {tag[:-1]}: objective {rank(X)[1]:.4e} (best so far {best[0][1]:.4e})")
        best = min(best, (rank(X), (X, mode)), key=lambda b: b[0])
        Xb = best[1][0]
        if not best[0][0] and not _second_opinion_due(
            req, prob, Xb, lambda X=Xb: fit_miss(exact_fits(prob.of("fit")), X), log
        ):  # the best now would have asked for no second opinion: the rest cannot be needed
            break
    return best[1]


def _second_opinion_due(req, prob: DesignProblem, X: np.ndarray, miss, log) -> bool:
    """Whether a second opinion of ``X`` runs (the full solver's, or ``_mirrored_starts``): up to
    ``FULL_ALWAYS_TILES`` when its outline misses the shape tolerance, up to ``FULL_MAX_TILES`` when its fit
    misses by more than ``FULL_ABOVE`` (``miss()``, asked only there)."""
    tiles = req.rows * req.cols
    if tiles > FULL_MAX_TILES:
        return False
    if tiles > FULL_ALWAYS_TILES:
        return miss() > FULL_ABOVE
    return _outline_misses(prob, X, req.second_opinion_above, log)


def _outline_misses(prob: DesignProblem, X: np.ndarray, above: float, log) -> bool:
    """Whether the deployed outline's Hausdorff distance to the target (``design/core/conformance.py``, the measure
    ``--shape-tol`` judges) exceeds ``above`` of the target's size: below it the full solver's second opinion
    is skipped. With the outline fit it reached the same outline at 8x8 on circle, ellipse, superellipse,
    hexagon and heart (Hausdorff within 0.005 % of the size) for 4-6x the rigid family's time."""
    h = _outline_rel(prob, X)
    if h <= above:
        log(
            f"rigid family outline within {h:.2%} of the target size (<= {above:.2%}): no second opinion"
        )
    return h > above


def _outline_rel(prob: DesignProblem, X: np.ndarray) -> float:
    """The deployed outline's Hausdorff distance to the target, a fraction of its size (tile units ``X``)."""
    pat = Pattern(nodes=X[: prob.n] * prob.L0, tiles=prob.std.tiles)
    return deployed_conformance(pat.nodes, pat.topology, prob.target)["hausdorff_rel"]


def _second_opinion(req, prob: DesignProblem, out: tuple, log, iters: dict) -> tuple[tuple, str]:
    """The full solver as well, where the rigid family's least-squares fit may be a worse local minimum
    (``FULL_ALWAYS_TILES``, ``FULL_ABOVE``, ``FULL_MAX_TILES``); ``(out, solver name)``, the lower objective.
    ``req`` is the caller's request (``_design``'s), which ``prob.req`` may not be."""
    solver = REDUCED_NAME
    miss = fit_miss(exact_fits(prob.of("fit")), out[0])
    if miss > FULL_ABOVE and req.rows * req.cols > FULL_MAX_TILES:
        log(
            f"rigid family fit misses by {miss:.2%} of the target size; the full solver is not tried above "
            f"{FULL_MAX_TILES} tiles (--solver full forces it; --init coarse helps large lattices)"
        )
    elif _second_opinion_due(req, prob, out[0], lambda: miss, log):
        log(
            f"rigid family fit is least-squares (misses by {miss:.2%} of the target size): "
            f"trying the full solver too"
        )
        polished: list = []
        full = _solve_full(prob, log, iters, lambda X: _polish(prob, X, log, iters, polished))
        f_red, f_full = _objective(prob, out[0]), _objective(prob, full[0])
        ok_full = _acceptable(prob, full[0])
        log(
            f"objective: rigid family {f_red:.4e}, full {f_full:.4e}"
            + ("" if ok_full else " (unconverged)")
        )
        if ok_full and f_full < f_red:
            out, solver = full, FULL_NAME + (POLISHED if polished else "")
    return out, solver


def _polish(prob: DesignProblem, X: np.ndarray, log, iters: dict, polished: list):
    """Where the full solver's first schedule ends off the constraints (its projection stopped short), the rigid
    family's member closest to that end (reduced solver, warm from it), instead of the stiff restart, when it
    is valid and fits at least as well as the end itself (``(X, mode)``, else None). 16x16 heart at 200 mm:
    objective 1.152 against the end's 1.224 and the restart's 1.432, in a fraction of the restart's time."""
    psi = RigidFamily.deployment_angle(X, prob.st)
    Y, mode = _reduced_from(prob, X, psi, None, log, iters, "polish_", SCALINGS[:1])
    f_end, f_member = _objective(prob, X), _objective(prob, Y)
    if not (_acceptable(prob, Y) and f_member <= f_end):
        log(
            f"rigid member from the first schedule's end: objective {f_member:.4e} > {f_end:.4e} or invalid"
        )
        return None
    log(
        f"rigid member from the first schedule's end: objective {f_member:.4e} <= {f_end:.4e}, no restart"
    )
    polished.append(True)
    return Y, mode


def _solve_rigid_first(prob: DesignProblem, log, iters: dict):
    """The rigid family's closest member to the target (reduced solver only, from each of ``RIGID_FIRST_INITS``)
    that passes every family of the non-rigid problem: ``(X, mode, solver)`` if its outline is within the shape
    tolerance (``second_opinion_above``), else None and the full solver takes over. A coarse start whose
    tips-only levels miss is refitted (``coarse_refit``) only where no start meets: the 16x16 heart's refit
    missed too (4.61 %), and rescaled met (1.42 %)."""
    best, refit = None, None
    for init in RIGID_FIRST_INITS:
        sub = replace(
            prob.req,
            rigid=True,
            init=init,
            name="",
            solver="reduced",
            second_opinion=False,
            coarse_refit_on_miss=False,
        )
        best, res = _rigid_member(prob, sub, init, best, log, iters)
        if coarse_refit_applies(sub, res.report["coarse"]):
            refit = replace(sub, coarse_refit=True)
        if best is not None and best[0] <= RIGID_FIRST_GOOD:
            break
    if refit is not None and (best is None or best[0] > prob.req.second_opinion_above):
        log(
            "no start within the shape tolerance: coarse again, the levels that miss refitted (outline rows)"
        )
        best, _ = _rigid_member(prob, refit, f"{refit.init}_refit", best, log, iters)
    if best is None or best[0] > prob.req.second_opinion_above:
        return _rigid_full_first(prob, log, iters)
    return best[1:]


def _rigid_member(prob: DesignProblem, sub, name: str, best, log, iters: dict) -> tuple:
    """``(best, res)``: the rigid design of ``sub`` (``res``), and ``best`` ``(h, X, mode, solver)`` replaced by it
    where it passes every non-rigid family and its outline is closer (``h``, of the target's size)."""
    res = prob.design_whole(sub)  # a rigid design of the same target is a whole design
    iters.update({f"rigid_{name}_{k}": v for k, v in res.report["iterations"].items()})
    X = res.pattern.nodes / prob.L0
    if not (res.converged and _acceptable(prob, X)):
        log(f"rigid family from {name}: fails a non-rigid family check ({_why_not(prob, X)})")
        return best, res
    h = deployed_conformance(res.pattern.nodes, res.pattern.topology, prob.target)["hausdorff_rel"]
    log(f"rigid family from {name}: outline within {h:.2%} of the target size")
    if best is None or h < best[0]:
        best = (h, X, res.report["shape_matching"], res.report["solver"])
    return best, res


def _rigid_full_first(prob: DesignProblem, log, iters: dict):
    """Where no reduced member meets the shape, up to ``RIGID_FULL_FIRST_TILES``: the rigid design with the
    full solver's second opinion (``_solve_via_rigid``, the CLI's last guess), before the full solver over all
    nodes and its other guesses. ``(X, mode, solver)`` if within the shape tolerance, else None (and the CLI's
    last guess designs it again: a miss here costs that rigid design twice)."""
    if prob.req.rows * prob.req.cols > RIGID_FULL_FIRST_TILES:
        log("no rigid-family member within the shape tolerance: the full solver takes over")
        return None
    log(
        "no reduced rigid-family member within the shape tolerance: the rigid design, full solver too"
    )
    via = _solve_via_rigid(prob, log, iters, tag="via_")
    if via is None:
        return None
    h = _outline_rel(prob, via[0])
    if h <= prob.req.second_opinion_above:
        log(f"rigid design: outline within {h:.2%} of the target size")
        return via
    log(
        f"rigid design: outline within {h:.2%} of the target size, outside it: the full solver takes over"
    )
    return None


def _solve_via_rigid(prob: DesignProblem, log, iters: dict, tag: str = ""):
    """The same target as a rigid design (coarse to fine); ``(X, mode, solver)`` if it passes every family of
    the non-rigid problem, else None. ``tag`` prefixes its iteration counts."""
    big = prob.req.rows * prob.req.cols >= VIA_RIGID_TILES
    # no full-solver second opinion on a big rigid problem at this level (its coarse levels keep theirs): at
    # 32x32 it took most of a heart's design and lost (the non-rigid full solver below still takes
    # over when the rigid design fails a non-rigid check); below that it is the CLI's last resort, kept whole
    sub = replace(
        prob.req,
        rigid=True,
        init=prob.req.via_rigid_init or ("coarse" if big else "rescaled"),
        name="",
        second_opinion=prob.req.second_opinion and not big,
    )
    log(
        "non-rigid design from the rigid family (a rigid member satisfies every non-rigid equality)"
    )
    # a big design keeps the rigid auto rules on its coarse levels only: main's 32x32 heart went on to the full
    # solver on the rigid problem when its reduced design failed a family check, stopped at 5e-5, then the
    # non-rigid one at 6e-3 (14 % off). Next, the reduced solver alone down the coarse levels (1.37 %).
    first = replace(sub, solver="reduced", coarse_solver="auto") if big else sub
    for name, attempt in (("rigid", first), ("rigid_reduced", replace(sub, solver="reduced"))):
        res = prob.design_whole(attempt)  # a rigid design of the same target is a whole design
        iters.update({f"{tag}{name}_{k}": v for k, v in res.report["iterations"].items()})
        X = res.pattern.nodes / prob.L0
        if res.converged and _acceptable(prob, X):
            # the free design's start: its report's ``coarse`` (read by the minimax finish, ``_tips_miss``)
            prob.via_coarse = res.report["coarse"]
            return X, res.report["shape_matching"], res.report["solver"]
        log(
            f"the {'rigid-family' if name == 'rigid' else 'reduced-only'} design fails a non-rigid family check "
            f"({_why_not(prob, X)})"
        )
        if attempt.solver == "auto" and res.report["solver"] == REDUCED_NAME:
            break  # its answer was the reduced member itself: the reduced-only design is the same nodes
    log("the full solver takes over")
    return None


def _solve_outline(prob: DesignProblem, log, iters: dict, solver=None):
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
        start = unit.points[0] - 0.5 * (
            lo + hi
        )  # a circle's parameter is its angle from the first point over 2π
        u = np.mod(
            (np.arctan2(corners[:, 1], corners[:, 0]) - np.arctan2(start[1], start[0]))
            / (2 * np.pi),
            1.0,
        )
        pts = (unit.points - 0.5 * (lo + hi)) * (
            radius * prob.L0 / (0.5 * float((hi - lo).max()))
        ) + centre * prob.L0
        mm = Target(unit.name, unit.kind, pts, corners=u, source=dict(unit.source))
        prob.curves_mm[s] = mm
        prob.families = [
            C.shape_match(
                g.boundary, g.boundary_side, mm.transformed(1.0 / prob.L0), prob.nv, f.name
            )
            if f.name == f"closed_shape_{s}"
            else f
            for f in prob.families
        ]
    if _acceptable(prob, X):
        return X, mode
    log(
        "the closed-state outline design fails a family check: falling back to the full solver "
        f"({_why_not(prob, X)})"
    )
    prob.curves_mm, prob.families = saved
    return None
