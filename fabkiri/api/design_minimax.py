"""Minimax finish of a large design (issue #37): its largest miss lowered after the least-squares fit.

The solvers minimise the *sum of squares* of the fit rows; the shape tolerance judges the *largest* miss
(Hausdorff). A larger lattice fits the sum better but can end with a larger largest miss at one feature, so
the fit did not improve with the size: the 64x64 heart's tip polygon passed 1.85 mm above the cusp, where the
48x48 one came within 0.37 mm. From this many tiles the front door's best valid design is refined by Lawson's
steps (:func:`fabkiri.design.core.refine.refine_minimax`: each a warm-started design under the same equalities,
inequalities and, where a closed state overlaps, the contact rows); a step is a candidate only when it passes
the front door's whole check (converged, both closed states closing, no overlapping tiles in any state), and
it replaces the design only with a smaller Hausdorff distance, measured on the final pattern as every design
is, and when ``verify`` fails none of its checks that the design passes. So the finish never makes a design worse; what it costs is recorded as an attempt.

Lawson's steps only move a design within its basin. Where they still leave more than ``REFIT_ABOVE`` of the
size, the design is made again from coarse levels refitted with the outline rows where they miss by more than
the finish's threshold (``coarse_refit``, which ``solve._design`` runs on its own only past the shape tolerance)
and the steps run from that too: the 32x32
drop ended at 1.78 % from its tips-only levels (16x16: 0.92 %), 0.51 % from the refitted ones.

Both thresholds, ``FINISH_ABOVE`` and ``REFIT_ABOVE``, are shares at 32x32 tiles and scale with the lattice's
resolution (``threshold``: 32/n for n tiles a side), so a larger design is asked to come closer; a free design
(neither rigid nor mirrored) has its own, lower, gate with no floor (``gate``, ``FREE_FINISH_ABOVE``), and none from
``FREE_FINISH_ALL_TILES`` tiles a side (a rigid one from ``RIGID_FINISH_ALL_TILES`` where its tips-only coarse
level misses the outline by more than the shape tolerance, under the rigid gate with cheaper steps, ``CHEAP_PATIENCE``;
a free one whose tips alone miss as well, ``_cheap``; after the full steps where they leave such a design above its
lattice's threshold, ``_cheap_after_full``; a mirrored one from ``SECOND_ROUTE_TILES`` past the free gate and further
than its coarse level, one cheaper step, ``_mirrored_step``; one under the rigid gate whose tips-only level misses past
it is designed again from refitted levels, ``_redesigned``). A step the
front door vetoes (a closed state overlapping) is not stepped from: the next goes back to the best step with half
the exponent (``backtrack`` in ``refine_minimax``).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import replace

from ..design.core.refine import refine_minimax
from ..design.core.request import FINISH_FLOOR
from ..design.quad.solve import DesignRequest, design
from .design_judge import DesignAttempt, _hausdorff, _rank, refinement_attempt
from .design_strip import strip_of

# from this many tiles (the coarse-to-fine sizes; below it the full solver's second opinion and the guesses in
# turn already weigh several fits, and a 16x16 design would pay several times its own time)
MINIMAX_TILES = 32 * 32
MINIMAX_STEPS = 6
# stop after this many steps in a row without a better design (heart 32x32: 1.61 % -> 0.34 % in step 3)
MINIMAX_PATIENCE = 2
# the miss's exponent in the weights' update: steadier than Lawson's 1 here (from main's designs, best of 3-6
# steps: heart 32x32 0.34 % against 0.46 %, peanut 32x32 0.40 % against 0.49 %)
MINIMAX_GAMMA = 0.5
# a step no better than the best so far is not stepped from: back to the best with half the exponent (refine.py)
MINIMAX_BACKTRACK = True
# above this share of the size at 32x32 tiles the steps start from the better of the design and its
# coarse-refitted redesign (the 32x32 peanut's steps left 0.40 %, the finish 0.31 % with it; the 32x32
# heart's 0.34 % were not worth its cost)
REFIT_ABOVE = 0.0035
# only a design that misses by more than this share of the size at 32x32 tiles is finished: the finish costs 2-6
# designs, and below it the circle, ellipse and star already fit within a few tenths of a per cent at every size
# (0.5 % left the 64x64 drop at 0.22 % above its finished 48x48 one, 0.20 %: 0.4 % is 0.2 % at 64x64)
FINISH_ABOVE = 0.004
# both thresholds follow the lattice's resolution, 1/n of the size for n tiles a side: a miss a 32x32 design may
# keep is too large for a 64x64 one (the 48x48 heart kept 0.37 %, the 32x32 one 0.34 %; the 48x48 drop's steps
# left 0.71 % in its tips-only basin, below the 1 % that asks for the refitted redesign, at 32x32 0.40 %)
THRESHOLD_TILES = 32
# a free design is finished above this share at 32x32 tiles, scaled and with no floor: under the rigid gate the
# star's 48x48 and 96x96 designs kept 0.24 % and 0.11 % (its 32x32 and 64x64 ones 0.07 % and 0.09 %); finished
# 0.069 % and 0.071 % (docs/design-solver.md, "Minimax finish below the rigid gate"). A mirrored design keeps the
# rigid gate: finished below it, the mirrored stars at 64x64 and 96x96 cost 4x the free ones
# (symmetry is asked to cost less than the free design, issue #37)
FREE_FINISH_ABOVE = 0.003
# from this many tiles a side a free design is finished whatever its miss: under the free gate the ellipse's
# 48x48 and 64x64 designs (0.151 %, 0.060 %) and the star's 64x64 one (0.090 %) sat above smaller lattices'
# designs; finished 0.036 %, 0.032 % and 0.062 % (docs/design-solver.md, "Every free design from 48 tiles a side
# finished"). Below it the finish's 2-6 designs would cost a 32x32 design several times its own time
FREE_FINISH_ALL_TILES = 48
# from this many tiles a side a design (free or rigid, not mirrored) the finish leaves above the free gate gets a
# second Lawson route: from the best design, fresh weights, Lawson's exponent 1 (the free 96x96 peanut's steps
# stalled at 0.249 %, above its 64x64's 0.211 %; the second route's first step 0.203 %; the heart, drop and bean at
# 96x96 kept their designs; the rigid peanut and bean alike: docs/design-solver.md, "The second route for rigid
# designs"). A rigid design under the rigid gate takes it with the cheaper steps (``CHEAP_PATIENCE``)
SECOND_ROUTE_TILES = 96
SECOND_ROUTE_GAMMA = 1.0
# a rigid design under the rigid gate gets cheaper steps (``_rigid_unmirrored``, ``finish_step``): the reduced
# solver's first LM scaling only (a warm-started step from a converged design: the other scaling's second start gave
# the lower merit in 2 of the 64x64 rigid circle's 6 steps, at half of each step's cost), no stiffer second stage
# after a feasible first (its 10 iterations pulled the fit back: the circle's finish 0.144 % with them, 0.007 %
# without) and this patience, stopping at the first step that comes no closer (docs/design-solver.md, "A cheaper
# finish for rigid designs")
CHEAP_PATIENCE = 1
# from this many tiles a side a rigid (not mirrored) design is finished whatever its miss, as a free one from
# ``FREE_FINISH_ALL_TILES``, where its tips alone miss (``_tips_miss``): the rigid star's 48x48 and 96x96 designs
# (0.24 %, 0.11 %) sat above its 32x32 and 64x64 ones (0.07 %, 0.09 %); finished with the cheaper steps 0.045 % and
# 0.032 % (docs/design-solver.md, "A cheaper finish for rigid designs", "Session 49 (rig49)")
RIGID_FINISH_ALL_TILES = 48
# a mirrored design from ``SECOND_ROUTE_TILES`` tiles a side above the free gate (which an unmirrored one would
# take a second route from) and further from the outline than its own coarse level gets this many cheaper steps
# (``_mirrored_step``): the mirrored 96x96 star (0.242 %, level 0.225 %, above its 64x64 design's 0.182 %) came to
# 0.097 % in one step under its free design's CPU, 0.046 % in six at twice it (docs/design-solver.md, "Session
# 50 (symstar50)")
MIRRORED_STEPS = 1


def threshold(share: float, req: DesignRequest) -> float:
    """``share`` (of the size, at ``THRESHOLD_TILES`` tiles a side) for ``req``'s lattice."""
    return share * THRESHOLD_TILES / max(req.rows, req.cols)


def gate(req: DesignRequest, report: dict | None = None) -> float:
    """The share of the size past which ``req``'s design (its ``report``) is finished: ``FINISH_ABOVE`` scaled to
    its lattice (``threshold``) down to ``FINISH_FLOOR`` for a rigid or mirrored request, ``FREE_FINISH_ABOVE``
    scaled for a free one, none (0) for a free one from ``FREE_FINISH_ALL_TILES`` tiles a side and a rigid one from
    ``RIGID_FINISH_ALL_TILES`` whose tips alone miss (``_tips_miss``), whose chain bottoms at a level from
    rescaled (``_rescaled_bottom``) or that is a bent strip's (``strip_of``: from its fold-free start it has no
    coarse level and is finished so, coarse to fine it stays so); the free gate's share scaled, under the
    rigid gate, for a mirrored one from ``SECOND_ROUTE_TILES`` further than its coarse level (``_mirrored_step``)."""
    rigid_all = _rigid_unmirrored(req) and max(req.rows, req.cols) >= RIGID_FINISH_ALL_TILES
    if rigid_all and (
        _tips_miss(req, report) or _rescaled_bottom(report) or strip_of(report or {})
    ):
        return 0.0
    if _mirrored_step(req, report):
        return min(_rigid_gate(req), threshold(FREE_FINISH_ABOVE, req))
    if not _free(req):
        return _rigid_gate(req)
    if max(req.rows, req.cols) >= FREE_FINISH_ALL_TILES:
        return 0.0
    return threshold(FREE_FINISH_ABOVE, req)


def _tips_miss(req: DesignRequest, report: dict | None) -> bool:
    """Whether the design of ``report`` has no coarse level fitted by its tips alone that met the outline within the
    shape tolerance its levels are judged by (``second_opinion_above``, ``DesignProblem._coarse_level``). Such a
    level fits the outline but where the fine lattice resolves a feature it cannot: there the least-squares fit
    leaves its largest miss, the finish's case (the rigid star's levels 10-17 %, the drop's 13 %). Where the tips
    alone fit, the design keeps the rigid gate: the rigid circles (levels 0.10-0.20 %, their 64x64 and 128x128
    designs 0.21 %, 0.22 %: finished, 2.6x and 3.3x their CPU), and the peanut's and bean's 64x64 designs (levels
    0.64 %, 0.77 %: finished, 0.14 %, under the 96x96 ones that main's full finish leaves at 0.20 % and 0.17 %)."""
    level = _level(report)
    h = level.get("hausdorff_rel")
    return not (level.get("fit") == "tips" and h is not None and h <= req.second_opinion_above)


def _redesigned(req: DesignRequest, report: dict | None) -> bool:
    """Whether ``req``'s design (its ``report``), unmirrored, from ``RIGID_FINISH_ALL_TILES`` tiles a side and within
    the free gate's share (``threshold(FREE_FINISH_ABOVE)``, under the rigid gate), came from a tips-only coarse
    level that fits within the shape tolerance (``_tips_miss``) but misses by more than the rigid gate: then it is
    designed again from the levels refitted with the outline rows, as a design above the gate is, and the closer
    kept, with no steps (the rigid and free 96x96 ellipse, 0.063 % from its 0.43 % level, 0.0066 % redesigned; a
    mirrored level has the outline rows already). The circles' levels fit within the gate (issue #36's 64x64 and
    128x128 rows keep their cost); the peanut's and bean's 64x64 designs, past the free gate's share, paid 2-3x
    their CPU for redesigns further than they (docs/design-solver.md, "Session 51 (ell51)")."""
    h, level = _hausdorff(report or {}), _level(report).get("hausdorff_rel")
    return (
        not req.symmetry
        and max(req.rows, req.cols) >= RIGID_FINISH_ALL_TILES
        and not _tips_miss(req, report)
        and not _rescaled_bottom(report)
        and level is not None
        and h <= threshold(FREE_FINISH_ABOVE, req)
        and _rigid_gate(req) < level
    )


def _rescaled_bottom(report: dict | None) -> bool:
    """Whether the design of ``report`` came from a chain whose bottom level started from rescaled (a target with no
    mirror, ``quad/chain.py``): finished whatever its miss where rigid, the cheaper steps under the rigid gate (the
    rigid 96x96 bean from that chain, 0.112 %, under the gate and above its 64x64 design's 0.040 %: 0.040 %), and no
    refitted redesign (``_redesigned``): its levels are that other chain already (docs/design-solver.md, "Session 52
    (bean52)")."""
    return bool(_level(report).get("rescaled_bottom"))


def _level(report: dict | None) -> dict:
    """The coarse level a design's ``report`` names (``report["coarse"]``: its fit and Hausdorff distance), or {}."""
    return (report or {}).get("coarse") or {}


def _free(req: DesignRequest) -> bool:
    """Neither rigid nor mirrored: the request the free gate is for."""
    return not (req.rigid or req.symmetry)


def _rigid_gate(req: DesignRequest) -> float:
    return max(threshold(FINISH_ABOVE, req), FINISH_FLOOR)


def applies(req: DesignRequest, contracted: dict, best) -> bool:
    """A valid deployed-target design from ``MINIMAX_TILES`` tiles asked (``_tiles_asked``) that misses by more
    than its ``gate``,
    or one that fails on overlapping tiles alone (``overlapping_only``),
    without fabrication rows (the continuation refines those) or a floor on the opening (``refine_to_floor``
    does)."""
    return (
        best is not None
        and (bool(best.valid) or overlapping_only(best))
        and req.target is not None
        and not contracted
        and req.fabrication is None
        and not req.min_opening
        and _tiles_asked(req, best.report) >= MINIMAX_TILES
        and (
            not best.valid
            or _hausdorff(best.report) > gate(req, best.report)
            or _redesigned(req, best.report)
        )
    )


def _tiles_asked(req: DesignRequest, report: dict) -> int:
    """The tiles asked of ``req``'s design (its ``report``): a bent strip's lattice (``strip_of``) has at most as
    many as asked, in other rows and columns (the arch's 12x85 for the 32x32 asked, 1020 tiles: unfinished below
    ``MINIMAX_TILES`` at 0.18 %, above its 16x16 strip's 0.13 %; finished 0.08 %)."""
    asked = strip_of(report).get("strip", {}).get("asked")
    return int(asked[0] * asked[1]) if asked else req.rows * req.cols


def overlapping_only(outcome: DesignAttempt) -> bool:
    """Whether a ``_check`` outcome fails on overlapping tiles alone (converged, both closed states closing):
    the refitted redesign may find a valid design in another basin (the 64x64 drop's tips-only design
    overlapped in state 1 where the solver's contact rows had not seen the pair)."""
    checks = outcome.report.get("checks") or {}
    overlaps = sum(1 for k, v in checks.items() if k.startswith("overlaps_") and v)
    return not outcome.valid and overlaps > 0 and len(outcome.problems) == overlaps


def minimax_finish(
    req: DesignRequest,
    best: DesignAttempt,
    judge: Callable,
    attempts: list[dict],
    say: Callable[[str], None],
    shape_tol: tuple = (0.02, "rel"),
):
    """Lawson's steps from ``best`` (a ``_check`` outcome), and from its coarse-refitted redesign where they
    leave more than ``REFIT_ABOVE`` (scaled, ``threshold``); the refined outcome when one passes every check with a smaller Hausdorff
    distance (ranking no worse, failing no ``verify`` check ``best`` passes), else None. From an overlapping
    ``best`` only the refitted redesign and its steps, kept when valid. The attempt is recorded either way."""
    h0, valid = _hausdorff(best.report), bool(best.valid)
    polish = valid and h0 <= _rigid_gate(req)
    # a rigid design under the rigid gate, and a free one whose tips alone miss (``_cheap``): the cheaper steps
    # (``CHEAP_PATIENCE``), asked by the steps' request
    stepped = replace(req, finish_step=True) if polish and _cheap(req, best.report) else req
    fails, seen = _memo(shape_tol), list[DesignAttempt]()
    if stepped is not req:  # every judged step kept: ``_verified`` falls back on them
        judge = _recording(judge, seen)
    # no steps from an overlapping design (``overlapping_only``): the refitted redesign, and the steps from that;
    # none either for a design under its gate let in by ``_redesigned``: the redesign alone
    gated = valid and h0 > gate(req, best.report)
    cand, trace, secs = _steps(stepped, best, judge) if gated else (None, [], 0.0)
    redesigned = valid and _redesigned(req, best.report)
    refit, left = None, min(h0, _hausdorff(cand.report) if cand else h0) if valid else float("inf")
    # still past REFIT_ABOVE: another basin, the design from refitted coarse levels and the steps from it (not
    # for a symmetric design: its levels have the outline rows already, ``DesignProblem._coarse_level``, the same design)
    # nor for a design under the rigid gate (``gate``): its steps alone (the free 64x64 peanut, 0.21 %: the
    # redesign and its steps cost twice the steps alone and found no better design; docs/design-solver.md) but
    # one whose tips-only level misses past that gate (``_redesigned``): the redesign alone
    if (
        not req.coarse_refit
        and not req.symmetry
        and (not polish and left > threshold(REFIT_ABOVE, req) or redesigned)
    ):
        refit, more, more_trace, more_secs = _refitted(req, judge, steps=not redesigned)
        trace, secs = trace + more_trace, secs + more_secs
        for c in (refit, more) if refit.valid else ():
            if c is not None and (cand is None or _rank(c) < _rank(cand)):
                cand = c
    start = cand if cand is not None and _closer(cand, best) else best
    more, more_trace, more_secs = _second_route(stepped, start, judge)
    if more is not None and (cand is None or _rank(more) < _rank(cand)):
        cand = more
    trace, secs = trace + more_trace, secs + more_secs
    if stepped is req and _cheap_after_full(req, best, cand):
        more, more_trace, more_secs = _steps(
            replace(req, finish_step=True), _ok(refit) or best, _recording(judge, seen)
        )
        cand = more if more is not None and (cand is None or _rank(more) < _rank(cand)) else cand
        trace, secs = trace + more_trace, secs + more_secs
    cand = _verified(cand, seen, best, fails)
    # a valid design replaces an overlapping one; a valid one only with a smaller Hausdorff distance
    better = cand is not None and (
        _rank(cand) < _rank(best)
        if not valid
        else _hausdorff(cand.report) < h0
        and _rank(cand) <= _rank(best)
        and fails(cand) <= fails(best)
    )
    attempts.append(
        refinement_attempt(
            "minimax refinement", cand, secs, trace, better, "no refinement step passed every check"
        )
        | {"refit_hausdorff_rel": _hausdorff(refit.report) if refit else None}
    )
    if better:
        assert cand is not None
        if cand.report.get("coarse") is None:  # a warm-started step: its start came coarse to fine
            cand.report["coarse"] = best.report.get("coarse")
        cand.report["minimax"] = {"from_hausdorff_rel": h0, "steps_hausdorff_rel": trace}
        cand.report.update(strip_of(best.report))  # refined on the bent strip's lattice
        say(
            f"fabkiri: minimax refinement: Hausdorff {100 * h0:.2f} % -> {100 * _hausdorff(cand.report):.2f} % "
            f"of the size ({len(trace)} steps)"
        )
    return cand if better else None


def _refitted(req: DesignRequest, judge: Callable, steps: bool):
    """``req``'s design again from its coarse levels refitted where they miss by more than the finish's own threshold
    (not only past the shape tolerance: the 32x32 peanut's steps left 0.40 %, with its 16x16 level refitted
    0.31 %), and where ``steps`` Lawson's steps from it when it is valid: the redesign's outcome, the steps' best
    (or None), their trace and the seconds of both."""
    again = replace(req, init="coarse", start=None, coarse_refit=True)
    refit = judge(design(replace(again, coarse_refit_above=threshold(FINISH_ABOVE, req))))
    secs = float(refit.report["time_s"])
    if not (refit.valid and steps):
        return refit, None, [], secs
    more, trace, more_secs = _steps(req, refit, judge)
    return refit, more, trace, secs + more_secs


def _cheap(req: DesignRequest, report: dict) -> bool:
    """Whether ``req``'s design (its ``report``) under the rigid gate gets the cheaper steps: a rigid (not mirrored)
    one, a free one whose tips alone miss (``_tips_miss``: the free 48x48-96x96 stars and 96x96 drop, whose full
    steps stalled above the rigid cells' cheaper ones; docs/design-solver.md, "Session 50 (drop50)") or whose chain
    bottoms at a level from rescaled (``_rescaled_bottom``: from a tips-only bottom the free 96x96 bean's full steps
    stalled at 0.043 %, above its 64x64 design), and a mirrored one that ``_mirrored_step`` names
    (``MIRRORED_STEPS`` of them, ``_steps``)."""
    return (
        _rigid_unmirrored(req)
        or (_free(req) and (_tips_miss(req, report) or _rescaled_bottom(report)))
        or _mirrored_step(req, report)
    )


def _mirrored_step(req: DesignRequest, report: dict | None) -> bool:
    """Whether ``req`` is mirrored, from ``SECOND_ROUTE_TILES`` tiles a side (the second route's size, which a
    mirrored design does not take), and its design (``report``) misses by more than its coarse level, the design at
    half its tiles (a mirrored level is fitted with the outline rows, ``DesignProblem._coarse_level``, so twice the
    tiles should come no further): past the free gate it gets ``MIRRORED_STEPS`` cheaper steps. The mirrored
    96x96 heart and drop came closer than their levels (0.65 % against 0.93 %, 0.26 % against 0.38 %) and keep the
    rigid gate, above which they take the full steps."""
    h = _level(report).get("hausdorff_rel")
    big = bool(req.symmetry) and max(req.rows, req.cols) >= SECOND_ROUTE_TILES
    return big and h is not None and _hausdorff(report or {}) > h


def _cheap_after_full(req: DesignRequest, best: DesignAttempt, cand) -> bool:
    """Whether the full steps (and the refitted redesign's) left an unmirrored ``best`` whose tips alone miss
    (``_tips_miss``) above its lattice's finish threshold without the floor (``threshold(FINISH_ABOVE)``): then the
    cheaper steps run as well, from the refitted redesign where there is one (the 64x64 drop's full steps stalled at
    0.237 %, above its 48x48's 0.202 %; the refit's cheaper steps 0.164 %). After the full ones, not instead: the
    48x48 drop, which they leave under its threshold, came to 0.083 % with the cheaper ones (a rise into the 64x64)."""
    left = min(_hausdorff(c.report) for c in (best, cand) if c is not None)
    return (
        bool(best.valid)
        and not req.symmetry
        and _tips_miss(req, best.report)
        and left > threshold(FINISH_ABOVE, req)
    )


def _ok(outcome):
    """``outcome`` where it is valid, else None."""
    return outcome if outcome is not None and outcome.valid else None


def _closer(cand: DesignAttempt, best: DesignAttempt) -> bool:
    return not best.valid or _hausdorff(cand.report) < _hausdorff(best.report)


def _memo(shape_tol: tuple) -> Callable[[DesignAttempt], set[str]]:
    """``_fails`` of each outcome once (the finish's outcomes live as long as it does)."""
    # the outcome kept beside its fails, so that its id is not reused while the finish runs
    known: dict[int, tuple[DesignAttempt, set[str]]] = {}

    def fails(outcome: DesignAttempt) -> set[str]:
        if id(outcome) not in known:
            known[id(outcome)] = (outcome, _fails(outcome, shape_tol))
        return known[id(outcome)][1]

    return fails


def _recording(judge: Callable, seen: list) -> Callable:
    """``judge`` that keeps every outcome it gives in ``seen``."""

    def judged(result):
        seen.append(judge(result))
        return seen[-1]

    return judged


def _verified(cand, seen: list, best: DesignAttempt, fails: Callable):
    """``cand``, or where it fails a ``verify`` check ``best`` passes, the best-ranked valid step of ``seen``
    closer than ``best`` that fails none (the cheaper steps' 128x128 rigid circle: its closest step, 0.012 %,
    left a tile edge under the verifier's minimum, its second 0.081 % did not)."""
    if cand is None or not seen or not best.valid or fails(cand) <= fails(best):
        return cand
    closer = [c for c in seen if c.valid and c is not cand and _closer(c, best)]
    return next((c for c in sorted(closer, key=_rank) if fails(c) <= fails(best)), cand)


def _rigid_unmirrored(req: DesignRequest) -> bool:
    """A rigid request, not a mirrored one: the one whose design under the rigid gate is finished with the cheaper
    steps (``CHEAP_PATIENCE``), and from ``RIGID_FINISH_ALL_TILES`` whatever its miss where its tips alone miss."""
    return req.rigid and not req.symmetry


def _second_route(
    req: DesignRequest, start: DesignAttempt, judge: Callable
) -> tuple[DesignAttempt | None, list[float], float]:
    """Lawson's steps again from ``start`` (the finish's best valid design) with ``SECOND_ROUTE_GAMMA``, for a free
    or rigid (not mirrored) design from ``SECOND_ROUTE_TILES`` tiles a side still above the free gate; else
    nothing."""
    if (
        req.symmetry
        or max(req.rows, req.cols) < SECOND_ROUTE_TILES
        or not start.valid
        or _hausdorff(start.report) <= threshold(FREE_FINISH_ABOVE, req)
    ):
        return None, [], 0.0
    return _steps(req, start, judge, gamma=SECOND_ROUTE_GAMMA)


def _steps(
    req: DesignRequest, start: DesignAttempt, judge: Callable, gamma: float = MINIMAX_GAMMA
) -> tuple[DesignAttempt | None, list[float], float]:
    """Lawson's steps from the outcome ``start``: the best step's ``_check`` outcome that passes every check
    (None if none does), the Hausdorff distance of every step and their seconds; the cheaper steps
    (``CHEAP_PATIENCE``) where ``req`` asks ``finish_step``."""
    checked: dict[int, DesignAttempt] = {}

    def valid(result) -> bool:
        checked[id(result)] = judge(result)
        return bool(checked[id(result)].valid)

    refined, trace, secs = refine_minimax(
        # the least-edge rows in the steps alone: they squeeze the tile at a point (the 96x96 drop's)
        replace(req, start=None, least_edge=True),
        start.pattern.nodes,
        steps=MIRRORED_STEPS if req.finish_step and req.symmetry else MINIMAX_STEPS,
        gamma=gamma,
        accept=valid,
        patience=CHEAP_PATIENCE if req.finish_step else MINIMAX_PATIENCE,
        backtrack=MINIMAX_BACKTRACK,
        # a vetoed first step does not end the cheaper steps (the rigid 64x64 peanut's, 0.139 %, overlapped)
        count_first_veto=not req.finish_step,
    )
    return (checked.get(id(refined)) if refined is not None else None), trace, secs


def _fails(outcome: DesignAttempt, shape_tol: tuple) -> set[str]:
    """The names of the ``verify`` checks the outcome's pattern (with its closed states) fails."""
    # the finish alone needs the verifier: a design without it loads none of it
    from ..verify import verify_pattern

    whole = outcome.pattern.with_contracted(outcome.states).with_parity(0)
    return {c.name for c in verify_pattern(whole, shape_tol=shape_tol).failed()}
