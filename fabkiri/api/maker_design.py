"""``make``'s design step, and what it does when the design misses the shape: other tile counts, run.

The tile count ``make`` chose is a guess from the size and the process's thinnest feature
(:mod:`.maker_tiles`); a design just outside the tolerance there often meets it with a neighbouring
count. So after a shape miss within :data:`RETRY_WITHIN` times the tolerance, up to :data:`MAX_RETRIES`
counts of :func:`.maker_tiles.retry_tiles` are designed in turn (each costs about what the first
design did, the progress line says so; none starts once they cost :data:`RETRY_BUDGET` times it). With tiles ``make`` chose, the first that meets the shape is
the design (the summary says which count missed and why the next was tried). With ``--tiles`` given,
the count is the user's: one that meets is only named, once its cut or print and deploy steps have
run too, as a ``fabkiri make ... --tiles RxC`` line (a checked alternative, never a count already
tried). A farther miss (a reflex corner, a pocket) is not retried at neighbouring counts: they move the
outline by about a tile, not by several tolerances; with tiles make chose, the next standard count up at
the same size is designed once instead (``maker_tiles.denser_tiles``: more tiles across an arm), and used if
it meets the shape (the held-out T and the letter L at 100 mm for card-0.3).

When tiles ``make`` chose still miss (far, or after its retries), the smallest larger size of
:data:`SIZE_STEPS` at which ``make`` would choose more tiles is made on a scratch result (design, cut or
print, deploy; nothing written) and, when all pass, named as a ``fabkiri make ... --size S`` line: the
six-point star for prusa-mk4 at 150 mm misses at 6x6 and 7x7, and is made at 190 mm with 8x8 tiles.
When that does not make it either, the options of :mod:`.maker_options` (other counts, styles or hinge
kinds, presets, the other process) are run the same way, likeliest first, and the first that makes it
is named (the heart at 200 mm on prusa-mk4 misses 8.6 % at 8x8 and 17.7 % at 250 mm; pp-0.5 tape
makes it at 200 mm); also when a cut or print refusal names nothing that passes. A size or option
whose arms cannot hold a strip's tiles across (:mod:`.maker_arms`) is not designed: the bound is a floor.
"""

from __future__ import annotations

import math
import resource
import shlex
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

from ..design.core import conformance as conf
from ..design.quad.corner_split import MIN_ACROSS
from ..design.targets.lookup import load_target
from ..errors import FabkiriError
from ..fabricate import design_limits
from . import maker_options as mo
from .maker_arms import NarrowArms, narrow_arms
from .maker_once import StepRun, name_lattice
from .maker_once import design_once as _design  # tests replace it here
from .maker_result import MakeResult
from .maker_tiles import TilesChoice, choose_tiles, denser_tiles, fewer_tiles, retry_tiles

Progress = Callable[[str], None]


StepFn = Callable[[MakeResult, Any, Progress], StepRun]
Checks = Mapping[str, Sequence[StepFn]]  # by process: the steps an alternative must pass
# a miss up to this many times the tolerance is retried with other tile counts (star6 at 150 mm on
# prusa-mk4: 3.85 % at 6x6 against 3 %); beyond it the outline's own limit is at work (letter L: 8-19 %)
RETRY_WITHIN = 2.0
MAX_RETRIES = 2  # each retry is a whole design at the counts make chooses (issue 32)
# and no further retry once they cost this many times the first design (star6 on prusa-mk4 at 150 mm:
# the 7x7 retry cost twice the 6x6 design, and all three counts missed)
RETRY_BUDGET = 2.0
# larger sizes (times the asked one) tried for a named alternative when tiles make chose miss the shape
SIZE_STEPS = (1.25, 1.5, 2.0)
CHECKED = "make's design, {process} and deploy steps, run at these tiles"


@dataclass
class _Attempt:
    """One design of the step: its tiles, what ``_design`` returned and what it left in the result."""

    tiles: TilesChoice
    run: StepRun
    pattern: Any
    figures: dict[str, Any]
    cpu_s: float
    size: float = 0.0  # the size designed at (mm)

    @property
    def miss(self) -> float | None:
        """The deployed Hausdorff distance over the tolerance (> 1: missed), None without figures."""
        f = self.figures
        if "hausdorff_rel" not in f:
            return None
        return float(f["hausdorff_rel"]) / float(f["shape_tol_rel"])

    def line(self) -> str:
        r, c = self.tiles.tiles
        f = self.figures
        shape = (
            f"Hausdorff {100 * f['hausdorff_rel']:.2f} %" if "hausdorff_rel" in f else "no shape"
        )
        verdict = "met" if self.run.ok else "missed"
        return f"{r}x{c} {verdict} ({shape}, CPU {self.cpu_s:.1f} s)"


def design_step(result: MakeResult, plan, say: Progress, checks: Checks) -> StepRun:
    """Design at ``plan.tiles``; after a shape miss, the retries and options of this module. ``checks``
    are, by process, the steps (cut or print, deploy) an alternative must pass before it is named. A miss
    left at the end words its tile count from every count designed here (:func:`_trend_checked`)."""
    ran: list[_Attempt] = []
    run = _trend_checked(result, _design_step(result, plan, say, checks, ran), ran)
    name_lattice(result)
    return run


def _trend_checked(result: MakeResult, run: StepRun, ran: list[_Attempt]) -> StepRun:
    """``run`` with its miss line's tile count checked against the designs of ``ran`` at two or more
    counts (their measured trend, ``conformance.tile_trend``, also in the figures as ``tile_trend``)
    instead of the one design's 1/tiles per side estimate."""
    points = [[*a.tiles.tiles, a.figures["hausdorff_rel"]] for a in ran if a.miss is not None]
    report = ((result.pattern.design or {}) if result.pattern else {}).get("report") or {}
    j = (report.get("shape") or {}).get("deployed") or {}
    c = (report.get("conformance") or {}).get("deployed")
    if run.ok or j.get("status") != "missed" or not c or len({(r, k) for r, k, _ in points}) < 2:
        return run
    result.figures["tile_trend"] = conf.tile_trend(points, float(j["tol_rel"]))
    line = "fabkiri: design failed: " + conf.describe_miss("deployed", {**j, "trend": points}, c)
    head = "fabkiri: design failed: shape missed (deployed)"
    return run._replace(details=[line if d.startswith(head) else d for d in run.details])


def _design_step(
    result: MakeResult, plan, say: Progress, checks: Checks, ran: list[_Attempt]
) -> StepRun:
    first = _attempt(result, plan, say, ran)
    miss = first.miss
    if first.run.ok or miss is None or miss <= 1:
        return first.run  # met, or failed for another reason than the shape
    if miss > RETRY_WITHIN:
        denser = _denser(result, plan, say, first, ran)
        if denser is not None and denser.run.ok:
            return _adopt(result, denser, [first, denser])
        tried = [first] if denser is None else [first, denser]
        note = (
            f"no neighbouring tile count tried: the miss is {miss:.1f}x the tolerance, more than the "
            f"{RETRY_WITHIN:g}x a neighbouring count is likely to close"
            + (f"; {denser.line()} at this size" if denser is not None else "")
        )
        run = _with_details(_keep_best(result, tried) if denser else first.run, [note])
        return _fallbacks(result, plan, say, checks, tried, run, ran)
    target, fab = _target_and_limits(plan, plan.size)
    tried = [first]
    retries = retry_tiles(target, fab, plan.tiles, plan.least_tile_mm)
    if not retries and not plan.tiles.given:  # no larger count wide enough: a smaller one
        retries = fewer_tiles(target, fab, plan.tiles)
    for choice in retries[:MAX_RETRIES]:
        r, c = choice.tiles
        spent = sum(a.cpu_s for a in tried[1:])
        if spent > RETRY_BUDGET * first.cpu_s:
            say(f"make: not trying {r}x{c}: the retries cost {spent:.0f} CPU s already")
            break
        how = "to name it if it makes" if plan.tiles.given else "to use it if it meets the shape"
        say(
            f"make: the design at {_rc(plan.tiles)} missed the shape ({miss:.2f}x the tolerance); "
            f"trying {r}x{c} tiles {how} ({choice.reason}); about {first.cpu_s:.0f} CPU s more"
        )
        try:
            attempt = _attempt(result, replace(plan, tiles=choice), say, ran)
        except FabkiriError as exc:  # a count the design refuses up front: the next one
            say(f"make: {r}x{c} tiles refused by the design ({exc.cli_message()}); not counted")
            continue
        tried.append(attempt)
        if not attempt.run.ok:
            continue
        if not plan.tiles.given:
            return _adopt(result, attempt, tried)
        named = _checked_alternative(plan, attempt, checks[plan.process], result.output)
        if named is not None:
            result.alternatives = [named]
            break
    run = _keep_best(result, tried)
    if result.alternatives:
        return run
    return _fallbacks(result, plan, say, checks, tried, run, ran)


def _denser(
    result: MakeResult, plan, say: Progress, first: _Attempt, ran: list[_Attempt]
) -> _Attempt | None:
    """After a far miss with tiles make chose: the design at the next standard count up at this size
    (``maker_tiles.denser_tiles``), None when there is none or the design refuses it up front."""
    if plan.tiles.given:
        return None
    target, fab = _target_and_limits(plan, plan.size)
    choice = denser_tiles(target, fab, plan.tiles, plan.least_tile_mm)
    if choice is None:
        return None
    say(
        f"make: the design at {_rc(plan.tiles)} missed the shape ({first.miss:.2f}x the tolerance); "
        f"trying {_rc(choice)} tiles at {plan.size:g} mm to use it if it meets the shape "
        f"({choice.reason}); about {first.cpu_s:.0f} CPU s more"
    )
    try:
        return _attempt(result, replace(plan, tiles=choice), say, ran)
    except FabkiriError as exc:  # a count the design refuses up front
        say(f"make: {_rc(choice)} tiles refused by the design ({exc.cli_message()}); not counted")
        return None


def _fallbacks(
    result: MakeResult,
    plan,
    say: Progress,
    checks: Checks,
    tried: list[_Attempt],
    run: StepRun,
    ran: list[_Attempt],
) -> StepRun:
    """Tiles, counts and retries missed: the larger size (tiles make chose), then the other options of
    :mod:`.maker_options`, each run before it is named (a count of this process, with tiles make
    chose, is adopted instead); ``run`` (the missed design's) with the lines saying what was tried. Each
    design run is added to ``ran``."""
    larger: list[_Attempt] = []
    lines = _larger_size(result, plan, say, checks, larger)
    ran += larger
    if result.alternatives:
        return _with_details(run, lines)
    adopted, more = _other_options(result, plan, say, checks, tried + larger, ran=ran)
    return _with_details(adopted or run, lines + more)


def options_after_refusal(result: MakeResult, plan, say: Progress, checks: Checks) -> list[str]:
    """The design met the shape but ``plan.process`` refused it, naming nothing that passes: the
    options of :mod:`.maker_options` but this design, each run before it is named (none adopted)."""
    step = result.step("design")
    _, lines = _other_options(result, plan, say, checks, [], step.cpu_s if step else 1.0)
    return lines


def _other_options(
    result: MakeResult,
    plan,
    say: Progress,
    checks: Checks,
    tried: list[_Attempt],
    base_cpu: float | None = None,
    max_runs: int | None = None,
    ran: list[_Attempt] | None = None,
) -> tuple[StepRun | None, list[str]]:
    """The options of :mod:`.maker_options`, likeliest first, run until one passes (named, or adopted:
    a count of this process with tiles make chose, after a miss), :data:`~.maker_options.MAX_RUNS`
    designs (``max_runs``, read when called) ran or they cost :data:`~.maker_options.BUDGET` times the first
    design (``base_cpu`` without ``tried``; 0: the first option's own design); the adopted run and the lines. Each design run is added to
    ``ran``."""
    max_runs = mo.MAX_RUNS if max_runs is None else max_runs
    first_cpu = tried[0].cpu_s if tried else float(base_cpu or 1.0)
    own = result.tiles.tiles
    every = [o for o in mo.options(plan) if tried or o.group or o.tiles.tiles != own]
    done = mo.tried_of(plan, tried)
    start = cpu_s()
    runs: list[_Attempt] = []
    lines: list[str] = []
    narrow: list[str] = []  # options whose arms cannot hold a strip's tiles across
    while order := mo.ranked(every, done):
        spent = sum(a.cpu_s for a in runs)
        if len(runs) >= max_runs or spent > mo.BUDGET * first_cpu:
            lines.append(f"{len(order)} more option(s) not tried ({mo.limit_text()})")
            break
        option = order[0]
        every.remove(option)
        other = mo.plan_of(plan, option)
        arms = arms_of(other)
        if arms is not None:  # no count of it meets at this size: not designed
            narrow.append(
                f"{option.name} ({arms.arm_mm / arms.across:.3g} < {arms.need_mm:.3g} mm)"
            )
            continue
        adopt = option.group == 0 and not plan.tiles.given and bool(tried)
        say(
            f"make: trying {option.name} at {plan.size:g} mm ({mo.GROUPS[option.group]}), "
            f"{'to use it' if adopt else 'to name it'} if it makes; about {first_cpu:.0f} CPU s more"
        )
        try:
            attempt = _attempt(MakeResult.of_plan(other), other, say, ran)
        except FabkiriError as exc:  # refused up front (room, tiles): not counted
            lines.append(f"{option.name}: refused by the design ({exc.cli_message()})")
            continue
        runs.append(attempt)
        if not tried and base_cpu == 0 and len(runs) == 1:  # no design before: budget on this one
            first_cpu = attempt.cpu_s
        if attempt.run.ok and adopt:
            result.pattern, result.figures = attempt.pattern, attempt.figures
            return _adopt(result, attempt, [*tried, attempt]), lines
        named = attempt.run.ok and _checked_alternative(
            other, attempt, checks[other.process], result.output, option.auto, mo.tag(plan, option)
        )
        verdict = f"{other.process} and deploy pass" if named else "does not make"
        lines.append(f"{option.name}: {attempt.line()}, {verdict}")
        if named:
            result.alternatives = [named]
            break
        done += mo.tried_of(other, [attempt])  # what it missed by rules out options no looser
    if narrow:
        lines.insert(
            0, f"not designed, the arms too narrow for {MIN_ACROSS} tiles: " + "; ".join(narrow)
        )
    if runs or lines:
        lines.append(
            f"the options ran {len(runs)} design(s), CPU {sum(a.cpu_s for a in runs):.1f} s "
            f"({cpu_s() - start:.1f} s with the checks of what was named)"
        )
    return None, lines


def _larger_size(
    result: MakeResult, plan, say: Progress, checks: Checks, ran: list[_Attempt] | None = None
) -> list[str]:
    """Tiles make chose missed the shape: the smallest of :data:`SIZE_STEPS` times the size (rounded up
    to 10 mm) where make chooses more tiles is made on a scratch result, and named as a ``fabkiri make
    ... --size S`` line when its design meets the shape and every step of ``checks`` passes."""
    if plan.tiles.given:
        return []
    count = plan.tiles.tiles[0] * plan.tiles.tiles[1]
    skipped: list[str] = []
    for k in SIZE_STEPS:
        size = float(math.ceil(plan.size * k / 10.0) * 10)
        target, fab = _target_and_limits(plan, size)
        arms = narrow_arms(target, fab, plan.least_tile_mm, plan.fabrication)
        if arms is not None:  # before make's count there: a bent strip's split costs seconds
            skipped.append(f"{size:g} mm not designed: {arms.reason()}")
            continue
        choice = choose_tiles(target, fab, plan.fabrication, plan.least_tile_mm)
        if choice.tiles[0] * choice.tiles[1] > count:
            break
    else:
        return skipped + [
            f"no larger size up to {SIZE_STEPS[-1]:g}x gives make more tiles"
            + (" with arms that hold them" if skipped else "")
        ]
    bigger = replace(plan, size=size, tiles=choice)
    say(f"make: trying {size:g} mm, where make chooses {_rc(choice)} tiles, to name it if it makes")
    scratch = MakeResult.of_plan(bigger)
    attempt = _attempt(scratch, bigger, say)
    if ran is not None:
        ran.append(attempt)
    named = attempt.run.ok and _checked_alternative(
        bigger, attempt, checks[plan.process], result.output, sized=True
    )
    if named:
        result.alternatives = [named]
        return skipped + [f"at {size:g} mm: {attempt.line()}, {plan.process} and deploy pass"]
    return skipped + [
        f"at {size:g} mm ({_rc(choice)} tiles) it does not make either: {attempt.line()}"
    ]


def arms_of(plan, given_too: bool = False) -> NarrowArms | None:
    """The plan's outline at its size when its arms cannot hold a strip's tiles of its process
    (:mod:`.maker_arms`); None when they can, or the tiles are the user's (``--tiles``) and not
    ``given_too``."""
    if plan.tiles.given and not given_too:
        return None
    target, fab = _target_and_limits(plan, plan.size)
    return narrow_arms(target, fab, plan.least_tile_mm, plan.fabrication)


def _target_and_limits(plan, size: float):
    """The plan's outline at ``size`` and its fabrication limits, as make's planning resolves them."""
    target = load_target(plan.target, size)
    fab, _ = design_limits.resolve(
        plan.material, plan.hinge, plan.printer, plan.style, None, None, target
    )
    assert fab is not None  # make always names a process
    return target, fab


def cpu_s() -> float:
    """This process's CPU time so far (user and system, s)."""
    r = resource.getrusage(resource.RUSAGE_SELF)
    return r.ru_utime + r.ru_stime


def _attempt(
    result: MakeResult, plan, say: Progress, ran: list[_Attempt] | None = None
) -> _Attempt:
    start = cpu_s()
    run = _design(result, plan, say)
    out = _Attempt(
        plan.tiles, run, result.pattern, dict(result.figures), cpu_s() - start, plan.size
    )
    if ran is not None:
        ran.append(out)
    return out


def _rc(tiles: TilesChoice) -> str:
    return "x".join(map(str, tiles.tiles))


def _with_details(run: StepRun, lines: list[str]) -> StepRun:
    return run._replace(details=[*run.details, *lines])


def _tried_lines(tried: list[_Attempt]) -> list[str]:
    extra = sum(a.cpu_s for a in tried[1:])
    return [
        "tile counts designed: "
        + "; ".join(a.line() for a in tried)
        + f" (the retries cost {extra:.1f} CPU s)"
    ]


def _adopt(result: MakeResult, attempt: _Attempt, tried: list[_Attempt]) -> StepRun:
    """The retry that met the shape becomes the design: ``make``'s tiles, with the reason."""
    first = tried[0]
    result.tiles = replace(
        attempt.tiles,
        reason=f"{_rc(first.tiles)} missed the shape ({first.miss:.2f}x the tolerance), so make tried "
        f"{_rc(attempt.tiles)}, {attempt.tiles.reason}",
    )
    result.retried = [a.line() for a in tried]
    return _with_details(attempt.run, _tried_lines(tried))


def _keep_best(result: MakeResult, tried: list[_Attempt]) -> StepRun:
    """Nothing adopted: the closest design is the step's (files, figures, tiles), the others listed."""
    best = min(tried, key=lambda a: a.miss if a.miss is not None else float("inf"))
    if tried[0].tiles.given:
        best = tried[0]  # the count the user named stays the design; the others are only reported
    result.pattern, result.figures = best.pattern, best.figures
    if best is not tried[0]:
        result.tiles = replace(
            best.tiles,
            reason=f"the closest of the counts tried ({best.tiles.reason})",
            given=tried[0].tiles.given,
        )
    result.retried = [a.line() for a in tried]
    return _with_details(best.run, _tried_lines(tried))


def _checked_alternative(
    plan,
    attempt: _Attempt,
    checks: Sequence[StepFn],
    output: Path | None,
    sized: bool = False,
    tag: str = "",
):
    """The ``fabkiri make ... --tiles RxC`` line of ``attempt`` (``sized``: ``--size S``, the tiles
    make's choice there) when its design passes every step of ``checks`` (run on a scratch result,
    nothing written); None when one fails."""
    from .advice import Alternative

    scratch = MakeResult.of_plan(plan, tiles=attempt.tiles, pattern=attempt.pattern)
    for step in checks:
        try:
            if not step(scratch, plan, lambda text: None).ok:
                return None
        except FabkiriError:
            return None
    r, c = attempt.tiles.tiles
    command = make_command(plan, None if sized else attempt.tiles.tiles, output, tag)
    at = f"at {plan.size:g} mm " if sized or tag.endswith("mm") else ""
    detail = (
        f"{r}x{c} tiles {at}meet the shape ({attempt.line()}) and {plan.process} and deploy pass"
    )
    changes: dict[str, Any] = {"size": plan.size} if sized else {"tiles": (r, c)}
    return Alternative("make", command, detail, CHECKED.format(process=plan.process), changes)


def make_command(plan, tiles: tuple[int, int] | None, output: Path | None, tag: str = "") -> str:
    """The ``fabkiri make`` line of ``plan`` at ``tiles`` (None: make's choice at the plan's size),
    writing beside ``output`` (the run's; ``tag``, the process when it differs, names the folder)."""
    how = (
        ["--material", plan.material, "--hinge", plan.hinge]
        if plan.material
        else ["--printer", plan.printer, "--style", plan.style]
    )
    tail = f"{plan.size:g}mm" if tiles is None else "x".join(map(str, tiles))
    tail = f"{tag}-{tail}" if tag else tail
    out = f"{output}-{tail}" if output is not None else f"{plan.stem}-{tail}"
    words = ["fabkiri", "make", plan.target, "--size", f"{plan.size:g}", *how]
    if tiles is not None:
        words += ["--tiles", "x".join(map(str, tiles))]
    if plan.shape_tol != conf.DEFAULT_SHAPE_TOL:
        words += ["--shape-tol", plan.shape_tol]
    if plan.min_opening is not None:
        words += ["--min-opening", f"{plan.min_opening:g}"]
    return shlex.join([*words, "-o", str(Path(out))])
