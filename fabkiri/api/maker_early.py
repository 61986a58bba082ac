"""``make``'s refusal before any design: tiles too narrow for the print style, and the option that works.

A print-aware design whose tiles are narrower than the print style's own minimum tile
(:mod:`.print_tiles`) cannot hold its strips (or pins) apart; at 16x16 the continuation took a whole
design to find that out (heart at 200 mm on prusa-mk4: "the limits cost the shape"). ``make``
now refuses such a request before designing it (exit 1, as a design that misses), and names what works,
run before it is named (design, print and deploy on a scratch result, nothing written), cheapest and
likeliest first, at most :data:`~.maker_options.MAX_RUNS` designs in all:

1. this printer and style at this size, on the count ``make`` would choose there (the most room for
   the strips: likeliest to meet, and the fewest tiles, the cheapest design), unless the arms are too
   narrow there (:mod:`.maker_arms`: then not designed, and said so);
2. the tiles asked for at the size from which they are wide enough (``--tiles`` given; without it,
   ``make``'s own choice at that size), or from which the outline's arms hold a strip's tiles
   (:mod:`.maker_arms`), the larger;
3. the other options of :mod:`.maker_options` (counts, styles, presets, the other process), as after a
   missed design.
"""

from __future__ import annotations

import math
from dataclasses import replace

from ..design.quad.corner_split import MIN_ACROSS
from ..design.targets.lookup import load_target
from ..errors import FabkiriError
from . import maker_options as mo
from .maker_arms import NarrowArms, narrow_arms
from .maker_design import (
    SIZE_STEPS,
    Checks,
    Progress,
    StepRun,
    _Attempt,
    _attempt,
    _checked_alternative,
    _larger_size,
    _other_options,
    _target_and_limits,
    cpu_s,
)
from .maker_result import MakeResult
from .maker_tiles import choose_tiles, given_tiles
from .print_tiles import SIZE_STEP_MM, NarrowTiles, narrow_tiles


def narrow_of(plan) -> NarrowTiles | None:
    """The plan's tiles when they are too narrow for its print style (None: wide enough, or a cut)."""
    if plan.process != "print" or plan.least_tile_mm <= 0:
        return None
    if plan.tiles.corners is not None and not plan.tiles.given:
        # make's own re-split strip (corner_split): its count was checked before the split; the letter L at
        # 150 mm on prusa-mk4 becomes 16x4 (8.59 mm by the estimate) and prints (bench/make.py)
        return None
    target = load_target(plan.target, plan.size)
    return narrow_tiles(target, plan.tiles.tiles, plan.printer, plan.style, plan.fabrication)


def refuse_narrow(
    result: MakeResult, plan, say: Progress, checks: Checks, narrow: NarrowTiles
) -> StepRun:
    """The design step refused before any design (exit 1), naming the first option that makes it."""
    reason = narrow.reason()
    say(f"make: {reason}")
    result.refused = (
        True  # as a cut or print refusal: its options on stdout, one runnable line each
    )
    start = cpu_s()
    tried: list[_Attempt] = []
    lines: list[str] = []
    for label, other, sized in _candidates(plan, narrow):
        if len(tried) >= mo.MAX_RUNS:
            break
        if isinstance(other, NarrowArms):  # no count meets there (maker_arms): not designed
            lines.append(f"{label}: not designed: {other.reason()}")
            continue
        say(f"make: trying {label}, to name it if it makes")
        try:
            attempt = _attempt(MakeResult.of_plan(other), other, say)
        except FabkiriError as exc:  # refused up front (room): not counted
            lines.append(f"{label}: refused by the design ({exc.cli_message()})")
            continue
        tried.append(attempt)
        named = attempt.run.ok and _checked_alternative(
            other, attempt, checks[plan.process], result.output, sized, _tag(plan, other, sized)
        )
        lines.append(
            f"{label}: {attempt.line()}, " + ("print and deploy pass" if named else "does not make")
        )
        if named:
            result.alternatives = [named]
            break
    left = mo.MAX_RUNS - len(tried)
    if not result.alternatives and left > 0:
        first = tried[0].cpu_s if tried else None
        _, more = _other_options(result, plan, say, checks, tried, first, max_runs=left)
        lines += more
    if not result.alternatives:
        lines.append("no size or option designed here made it: no size is named")
    lines.append(f"the options cost CPU {cpu_s() - start:.1f} s (no design at the tiles asked)")
    return StepRun(False, 1, f"refused before any design: {reason}", {}, lines)


def _candidates(plan, narrow: NarrowTiles):
    """``(label, plan, sized)`` of the first two options of the module docstring, where they apply; in
    place of the plan, the :class:`NarrowArms` of a size whose arms cannot hold a strip's tiles (not
    designed). The size of the second is where the tiles asked are wide enough by the estimate, or the
    first size (:data:`~.print_tiles.SIZE_STEP_MM` steps) past it whose arms hold them, the larger, up to
    make's own ladder (twice the size asked; past it, not designed)."""
    target, fab = _target_and_limits(plan, plan.size)
    auto = choose_tiles(target, fab, plan.fabrication, plan.least_tile_mm)
    if (
        auto.tiles != plan.tiles.tiles
        and narrow_tiles(target, auto.tiles, plan.printer, plan.style) is None
    ):
        label = f"{'x'.join(map(str, auto.tiles))} tiles at {plan.size:g} mm (make's choice there)"
        arms = narrow_arms(target, fab, plan.least_tile_mm, plan.fabrication)
        yield label, arms or replace(plan, tiles=auto), False
    held = _size_arms_hold(plan, narrow.size_for)
    if held is None:
        arms = _arms_at(plan, narrow.size_for)
        yield f"{narrow.size_for:g} mm, where the tiles asked are wide enough", arms, False
        return
    size, arms_from = held
    bigger, fab = _target_and_limits(plan, size)
    why = f" (the arms hold {MIN_ACROSS} tiles from there)" if arms_from else ""
    if plan.tiles.given:
        tiles = given_tiles(plan.tiles.tiles, bigger, fab)
        label = f"{'x'.join(map(str, tiles.tiles))} tiles at {size:g} mm{why}"
        yield label, replace(plan, size=size, tiles=tiles), False
    else:
        tiles = choose_tiles(bigger, fab, plan.fabrication, plan.least_tile_mm)
        label = f"{size:g} mm, where make chooses {'x'.join(map(str, tiles.tiles))} tiles{why}"
        yield label, replace(plan, size=size, tiles=tiles), True


def _size_arms_hold(plan, size: float) -> tuple[float, bool] | None:
    """``size``, or the first size past it (in :data:`~.print_tiles.SIZE_STEP_MM` steps) at which the
    outline's arms hold a strip's tiles of the plan's process (:mod:`.maker_arms`: the arm width is linear
    in the size); whether it moved. None past make's own ladder (``SIZE_STEPS``' largest times the size
    asked): such a size is not designed."""
    arms = _arms_at(plan, size)
    if arms is None:
        return size, False
    ratio = arms.need_mm * arms.across / arms.arm_mm
    moved = math.ceil(size * ratio / SIZE_STEP_MM) * SIZE_STEP_MM
    if moved > SIZE_STEPS[-1] * plan.size:  # beyond make's own ladder: not designed
        return None
    while _arms_at(plan, moved) is not None:
        moved += SIZE_STEP_MM  # round-off of the measured width
    return float(moved), True


def _arms_at(plan, size: float) -> NarrowArms | None:
    """The plan's outline at ``size`` when its arms cannot hold a strip's tiles (:mod:`.maker_arms`)."""
    target, fab = _target_and_limits(plan, size)
    return narrow_arms(target, fab, plan.least_tile_mm, plan.fabrication)


def _tag(plan, other, sized: bool) -> str:
    """The named line's output folder beside the run's: the size when the tiles stay (``--size S --tiles``)."""
    return f"{other.size:g}mm" if other.size != plan.size and not sized else ""


def skip_narrow_arms(
    result: MakeResult, plan, say: Progress, checks: Checks, arms: NarrowArms
) -> StepRun:
    """The asked size not designed, its arms too narrow for a strip's tiles (:mod:`.maker_arms`): make's
    larger sizes and then the options, each run before it is named and skipped where the arms are too
    narrow too (exit 1, as a design that misses); nothing is named that was not designed and met."""
    reason = arms.reason()
    say(f"make: {reason}; no count is designed at {plan.size:g} mm, larger sizes and options are")
    result.refused = (
        True  # as a cut or print refusal: its options on stdout, one runnable line each
    )
    start = cpu_s()
    larger: list[_Attempt] = []
    lines = _larger_size(result, plan, say, checks, larger)
    if not result.alternatives:
        first = larger[0].cpu_s if larger else 0.0  # 0: budgeted on the first option's design
        _, more = _other_options(result, plan, say, checks, larger, first, ran=[])
        lines += more
    if not result.alternatives:
        lines.append("no larger size or option designed here made it: no size is named")
    lines.append(
        f"the sizes and options cost CPU {cpu_s() - start:.1f} s (no design at the size asked)"
    )
    return StepRun(False, 1, f"not designed: {reason}", {}, lines)
