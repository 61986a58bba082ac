"""Continuation in the fabrication limits (issue 14), the design front door's last try.

The rows held from the first step wall the fit in (16x16 heart at 200 mm, acrylic-3: 5-19 of 1024 width rows
active, Hausdorff 16 % against 1.75 % without them). From the design without them, the limits are raised in
steps, each step warm-started from the last. A rigid request takes one step (measured, heart: straight to the
limits 2.88 %, in four steps 3.13 %). When it applies is :mod:`.design`'s call (``_continuation_applies``).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import replace
from typing import TYPE_CHECKING

import numpy as np

from ..design.core import stages
from ..design.core.conformance import deployed as deployed_conformance
from ..design.core.refine import refine_minimax
from ..design.quad.fabrication import FabricationLimits
from ..design.quad.solve import (
    VIA_RIGID_INIT,
    DesignRequest,
    design,
    design_problem,
    via_rigid_applies,
)
from ..design.targets.lookup import Target
from ..errors import SolveError
from ..fabricate import design_limits
from ..fabricate import fabricability as fb
from ..fabricate.print.printers import load_printer
from ..mechanics.contract import contract
from ..pattern.model import Pattern
from .design_judge import DesignAttempt, _check, _fit_miss, _hausdorff, _rank, _shape_met
from .design_strip import strip_design, strip_of

if TYPE_CHECKING:  # design.py imports this module
    from .design import DesignOutcome, PatternRequest

CONTINUATION = (0.25, 0.5, 0.75, 1.0)
# first the full limits in one jump from the design without them, with no second opinion of the full solver
# (measured on a fabrication-aware heart: faster and no worse than the steps, see
# docs/speed.md#figures-from-code-comments); the steps only when the jump does not converge
JUMP = (1.0,)
# the refinement stops after this many steps without a better design (16x16 heart, acrylic-3: its best in
# step 2 of 10, the last 8 no better; star 150 mm prusa-mk4: 10 steps within 0.13 % of each other)
PATIENCE = 3
# from this many tiles the steps also follow a jump that converged but missed, and a continuation whose steps
# say the limits cost the shape is not retried from the guesses (measured at 16x16; below, an 8x8 heart for
# prusa-mk4 was kept from the standard guess, which fit the bed, and the 8x8 star6 for prusa-xl-2t paid for
# steps that kept the jump's 2.20 %)
LIMITS_COST_TILES = 16 * 16
# the refinement takes a miss at most this many times lower (Lawson's steps measured: 16x16 ellipse for
# prusa-xl-2t 18.9 -> 16.8 %, 8x8 star6 2.34 -> 2.20 %, 16x16 heart for acrylic-3 1.57 -> 1.50 %)
REFINE_WITHIN = 2.0
CONTINUATION_MARGIN = (
    0.02  # the rows' penalty margin in a step (tile edges; FabricationLimits.margin)
)


def continuation(
    request: PatternRequest,
    req: DesignRequest,
    target: Target | None,
    shape_tol: tuple,
    attempts: list,
    redesign: Callable[[PatternRequest], DesignOutcome],
):
    """The design without fabrication rows (:func:`_free_design`), then the rows raised from it: in one jump
    to the full limits (``JUMP``), else in steps (``CONTINUATION``), each warm started from the last; a last
    step that does not converge is tried in the rigid family (where it may) from the last converged step; on a
    bent strip's lattice where that design is one. The ``_check`` outcome, or None where it fails."""
    free, spent = _free_design(request, req, redesign)  # wall s, as the attempts
    if free is None:
        return None

    def judge(result):
        return _check(result, {}, request, target, shape_tol)

    req = strip_design(req, free)  # a bent strip's design: the rows are raised on its lattice
    req = _print_state(req, request.printer, free)
    # a non-rigid request below 32x32 steps in the rigid family when it may (a member meets every non-rigid
    # equality): with the full solver the steps from 7/8 of the limits on stalled against closed holes
    # (hundreds of non-overlap rows at zero; heart 16x16: equality 1e-5 to 6e-5, unconverged, 2.2-3.3 %)
    init = VIA_RIGID_INIT if via_rigid_applies(replace(req, init=VIA_RIGID_INIT)) else req.init
    trace: list = []  # [fraction, Hausdorff] of the steps
    steps, step, last_ok, outcome, spent = _jump_or_steps(
        req, free.pattern.nodes, init, judge, spent, trace
    )
    how = "continuation"
    if not outcome.valid and via_rigid_applies(replace(req, init=VIA_RIGID_INIT)):
        rigid = judge(design(replace(step, init=VIA_RIGID_INIT, start=last_ok)))
        spent += rigid.report["time_s"]
        if _rank(rigid) < _rank(outcome):
            outcome, how = rigid, "continuation, rigid family last"
    held = shape_held_to(
        [[0.0, _hausdorff(free.report) if free.shape_met else None], *trace],
        req.second_opinion_above,  # the tolerance over the size
    )
    prints = _print_gate(req, request.printer)
    # only where the rows cost a shape the design without them met (8x8 heart, star6 6x6: it misses too), and
    # not where the steps say the limits cost it far (``_refine_worth``: 16x16 heart at 200 mm, prusa-mk4, the
    # steps without the pads ended at 24.3 % against 23.9 % with them, a quarter of the design's time)
    if (
        prints is not None
        and free.shape_met
        and not _good_fit(outcome)
        and _pads_bind(outcome)
        and _refine_worth(req, held, _hausdorff(outcome.report))
    ):
        padless, spent = _without_pads(req, free.pattern.nodes, init, judge, prints, spent)
        if padless is not None and _rank(padless[0]) < _rank(outcome):
            outcome, step = padless
            how, steps = "continuation without the pad rows, print's check", (1.0, *CONTINUATION)
    refinement: list[float] = []
    if not _good_fit(outcome) and _refine_worth(req, held, _hausdorff(outcome.report)):
        # the fit was least squares, the tolerance is a maximum;
        # from an unconverged continuation too (only converged steps are kept: 16x16 heart, prusa-mk4, 2.53 %)
        outcome, how, refinement, secs = _refine(
            replace(step, init=VIA_RIGID_INIT if "rigid family" in how else init),
            outcome,
            how,
            judge,
            request.printer,
            req.fabrication,
            prints if "print's check" in how else None,
        )
        spent += secs
    outcome.report["continuation"] = {
        "steps": list(steps),
        "how": how,
        "free_hausdorff_rel": _hausdorff(free.report),
        "margin": CONTINUATION_MARGIN,
        "refinement_hausdorff_rel": refinement,
        "steps_hausdorff_rel": trace,
        "shape_held_to": held,  # the design without the rows is fraction 0
    }
    attempts.append(_attempt(outcome, how, spent))
    outcome.report.update(strip_of(free.report))
    return outcome


def _jump_or_steps(req: DesignRequest, X: np.ndarray, init: str, judge, spent: float, trace: list):
    """The jump to the full limits from the design without rows ``X``; the steps (``CONTINUATION``, their
    Hausdorff in ``trace``) when it stalls, as before the jump, or when it converged but missed the shape far
    (``_far``): then
    they say whether the limits cost it (16x16 ellipse at 200 mm, prusa-xl-2t: the jump converged at 18.9 %; in
    the rigid family the steps met 0.5 % at half the limits and 19.0 % at all of them, cheaply), and
    the better of the two is kept. ``(steps, last step, last converged nodes, outcome, wall s)``."""
    step, result, last_ok, spent = _raise_limits(req, X, init, JUMP, spent)
    outcome = judge(result)
    if (
        req.rigid
        or _good_fit(outcome)
        or (
            result.converged and (req.rows * req.cols < LIMITS_COST_TILES or not _far(req, outcome))
        )
    ):
        return (1.0,), step, last_ok, outcome, spent
    jumped = (step, last_ok, outcome) if result.converged else None
    step, result, last_ok, spent = _raise_limits(req, X, init, CONTINUATION, spent, trace)
    outcome = judge(result)
    if jumped is not None and _rank(jumped[2]) <= _rank(outcome):
        step, last_ok, outcome = jumped
    return (1.0, *CONTINUATION), step, last_ok, outcome, spent


def _far(req: DesignRequest, outcome: DesignAttempt) -> bool:
    """A miss over ``REFINE_WITHIN`` times the tolerance: a nearer one is the refinement's (16x16 heart for
    acrylic-3: the jump missed at 3.0 %, the slower steps at 3.1 %, the refinement of the jump met 1.5 %)."""
    return _hausdorff(outcome.report) > REFINE_WITHIN * req.second_opinion_above


def _refine_worth(req: DesignRequest, held: float | None, miss: float) -> bool:
    """Whether the minimax refinement may bring a miss within the tolerance: not from 16x16 tiles when the
    limits cost the shape (``held``) and the miss is over ``REFINE_WITHIN`` times the tolerance (the 16x16
    ellipse at 200 mm, prusa-xl-2t: 10 costly steps from 18.9 % to 16.8 %)."""
    far = miss > REFINE_WITHIN * req.second_opinion_above
    return not (held is not None and far and req.rows * req.cols >= LIMITS_COST_TILES)


def _attempt(outcome: DesignAttempt, how: str, spent: float) -> dict:
    """The continuation's entry in the design's attempts."""
    return {
        "init": how,
        "status": outcome.report["status"],
        "problems": outcome.problems,
        "time_s": spent,
        "fit_max_rel_size": _fit_miss(outcome.report),
        "hausdorff_max_rel": _hausdorff(outcome.report),
        "shape": "met" if _shape_met(outcome.report) else "missed",
    }


def _free_design(
    request: PatternRequest, req: DesignRequest, redesign
) -> tuple[DesignOutcome | None, float]:
    """The design without the rows, by the front door's guesses in turn; where the first of them (conformal)
    cannot be built (a non-convex target) and a non-rigid request may be answered in the rigid family, that
    family alone first (the steps are taken in it; 16x16 heart at 200 mm: the same design as the guesses in
    turn, which ended there, in about half their time), the guesses only when it misses the shape.
    Returns the valid design (or None; a bent strip's is on its own lattice) and the wall seconds spent."""
    free = replace(
        request,
        material=None,
        hinge=None,
        printer=None,
        style=None,
        min_feature=None,
        min_hole=None,
        quiet=True,
    )
    spent = 0.0
    if _rigid_first(request, req):
        first = redesign(replace(free, init=VIA_RIGID_INIT))
        spent = first.report.get("time_s_total", 0.0)
        if first.success:
            return first, spent
    out = redesign(free)
    return (out if out.valid else None), spent + out.report.get("time_s_total", 0.0)


def _rigid_first(request: PatternRequest, req: DesignRequest) -> bool:
    """Whether the design without the rows is asked of the rigid family first: no --init, non-rigid, the rigid
    family may answer, and the conformal guess (the guesses' first) folds a tile."""
    if request.init or req.rigid or not via_rigid_applies(replace(req, init=VIA_RIGID_INIT)):
        return False
    try:
        design_problem(replace(req, init="conformal", fabrication=None, start=None))
    except SolveError:
        return True
    return False


def _print_state(req: DesignRequest, printer: str | None, free: DesignOutcome) -> DesignRequest:
    """For a printer, the strip rows follow the closed state that fits the bed (2:1 ellipse: state 2)."""
    fab = req.fabrication
    assert fab is not None, "_continuation_applies admits only fabrication-aware requests"
    if not printer:
        return req
    fab = replace(fab, print_state=design_limits.bed_state(free.pattern.contracted, printer))
    return replace(
        req,
        fabrication=fab,
        fabrication_intent={**req.fabrication_intent, "state": fab.print_state},
    )


def _print_gate(req: DesignRequest, printer: str | None) -> Callable[[Pattern], str] | None:
    """For a printer whose limits carry the strip pad rows: ``print``'s own check of a design at its size in the
    preset's style and the printed closed state ('' accepted, else why not), the gate of a design made
    without the pad rows (8x8 star at 150 mm, prusa-mk4: the rows' margin walls the fit in, 3.80 %; the steps
    without them 1.77 %, and print accepts it at scale 1). None where there are no pad rows."""
    fab = req.fabrication
    if not printer or fab is None or fab.strip_pad_mm2 <= 0:
        return None
    pr, style = load_printer(printer), str(req.fabrication_intent["style"])  # resolve sets it
    return lambda pattern: fb.print_refusal(pattern, style, pr, fab.print_state, 1.0)


def _good_fit(outcome: DesignAttempt) -> bool:
    return bool(outcome.valid and _shape_met(outcome.report))


def _pads_bind(outcome: DesignAttempt) -> bool:
    """Whether any strip pad row of the outcome is active (else the steps without them are not worth trying)."""
    active = (outcome.report.get("fabrication") or {}).get("active") or {}
    return active.get("fabrication_strip_pads", 0) > 0


def _without_pads(req: DesignRequest, X: np.ndarray, init: str, judge, prints, spent: float):
    """The steps (``CONTINUATION``) from the design without rows ``X`` under the limits less the strip pad rows,
    kept only where ``print``'s own check (``prints``) accepts the last: ``((outcome, step), wall s)``, or
    ``(None, wall s)``."""
    fab = req.fabrication
    assert fab is not None
    padless = replace(req, fabrication=replace(fab, strip_pad_mm2=0.0))
    step, result, _, spent = _raise_limits(padless, X, init, CONTINUATION, spent)
    outcome = judge(result)
    return ((outcome, step) if not prints(outcome.pattern) else None), spent


def _raise_limits(
    req: DesignRequest,
    X: np.ndarray,
    init: str,
    steps: tuple,
    spent: float,
    trace: list | None = None,
):
    """Each step's design warm started from the last: ``(last step, its result, last converged nodes, wall s)``;
    ``trace`` (if given) gets ``[fraction, Hausdorff over the size, or None unconverged]`` per step."""
    fab = req.fabrication
    assert fab is not None
    last_ok = X
    # the pad area times f² (``FabricationLimits.step``) from 16x16 only: below, the linear steps stay (the 12x12
    # pick for prusa-xl-2t at 200 mm: with f² 1.36 %, and print refused its bodies, overlapping by 0.014 mm³)
    alike = req.rows * req.cols >= LIMITS_COST_TILES
    for k, f in enumerate(steps):
        stages.step("continuation", k, len(steps))
        lim = fab.step(f, CONTINUATION_MARGIN) if alike else fab.scaled(f, CONTINUATION_MARGIN)
        step = replace(req, fabrication=lim, start=X, init=init)
        if steps is JUMP:
            step = replace(step, second_opinion=False)
        result = design(step)
        spent += result.report["time_s"]
        X = result.pattern.nodes
        if result.converged:
            last_ok = X
        if trace is not None and req.target is not None:
            h = deployed_conformance(X, result.pattern.topology, req.target)["hausdorff_rel"]
            trace.append([f, float(h) if result.converged else None])
    stages.step("continuation", len(steps), len(steps))
    return step, result, last_ok, spent


def limits_note(outcome: DesignAttempt) -> str:
    """Why a continuation missed, when its steps say the limits cost the shape ('' otherwise)."""
    cont = outcome.report.get("continuation") or {}
    held = cont.get("shape_held_to")
    if held is None:
        return ""
    last = cont["steps_hausdorff_rel"][-1][1]
    at_full = f"{last:.1%}" if last is not None else "unconverged"
    up_to = f" and up to {held:.0%} of them" if held > 0 else ""
    return (
        f" (the limits cost the shape: met without them ({cont['free_hausdorff_rel']:.1%}){up_to}, "
        f"at all of them {at_full})"
    )


def shape_held_to(trace: list, tol_rel: float) -> float | None:
    """The largest fraction of the limits whose converged step (``[fraction, Hausdorff or None]``; the design
    without the rows as fraction 0) met ``tol_rel`` when the last step (the full limits) missed it: the limits,
    not the start, cost the shape (16x16 ellipse at 200 mm for prusa-xl-2t in
    the rigid family: 0.86 % at 0.6 of the limits, 3.0 % at 0.65, 19 % at the full limits). None otherwise."""
    if not trace or (trace[-1][1] is not None and trace[-1][1] <= tol_rel):
        return None
    met = [f for f, h in trace[:-1] if h is not None and h <= tol_rel]
    return max(met) if met else None


def _refine(
    step: DesignRequest,
    outcome,
    how: str,
    judge,
    printer: str | None,
    fab: FabricationLimits | None,
    prints: Callable[[Pattern], str] | None = None,
):
    """Minimax refinement of the outcome's outline; for a printer only steps whose printed closed state (of the
    full limits ``fab``) fits the bed are kept, and with ``prints`` only those it accepts (''). Returns
    ``(outcome, how, trace, wall s)``, the outcome kept when it ranks better."""
    assert fab is not None

    def bed(r) -> bool:  # asked only with a printer
        assert printer is not None
        if prints is not None and prints(r.pattern):
            return False
        return design_limits.fits_bed(contract(r.pattern, fab.print_state).corners, printer)

    refined, trace, secs = refine_minimax(
        step, outcome.pattern.nodes, accept=bed if printer else None, patience=PATIENCE
    )
    if refined is not None and _rank(cand := judge(refined)) < _rank(outcome):
        outcome, how = cand, how + ", minimax refinement"
    return outcome, how, trace, secs
