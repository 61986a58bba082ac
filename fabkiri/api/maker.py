"""``make``: from a target outline to files a machine accepts, in one call.

The steps are the other front doors in order: a fabrication-aware design for the named process
(:func:`~.design.design_pattern` with the material or printer, as ``design --material/--printer``),
then :func:`~.cut.cut_files` or :func:`~.print.print_pattern` at the designed size,
:func:`~.deploy.deploy_pattern` (plot and GIF) and the HTML report. Bad input is refused before any
work, with nothing written; after that each step's files are written as it finishes (each step
all-or-nothing, through :mod:`fabkiri.fileio`), and the first step that fails stops the run,
keeping what is done, except a failed deploy check: the report is still written, and the run fails. Without ``tiles`` the count comes from :func:`.maker_tiles.choose_tiles`; a design that
misses the shape by a little is designed again at other counts (:mod:`.maker_design`).
"""

from __future__ import annotations

import tempfile
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .. import limits
from ..design.core import conformance as conf
from ..design.targets.lookup import load_target
from ..errors import FabkiriError, InputError, Param
from ..fabricate import design_limits
from ..fileio import atomic_write_many, check_output_folder, input_named_by
from ..pattern.tilecount import tile_count
from .maker_design import StepRun, arms_of, design_step, options_after_refusal
from .maker_design import cpu_s as _cpu
from .maker_early import narrow_of, refuse_narrow, skip_narrow_arms
from .maker_once import opening_lines as _opening_lines  # noqa: F401 (re-exported)
from .maker_result import MANIFEST, MakeResult, Step
from .maker_tiles import TilesChoice, choose_tiles, given_tiles
from .print_tiles import check_room, least_tile_mm
from .progress import three_args

Progress = Callable[[str], None]  # a step's lines
Told = Callable[[str, float | None, str], None]  # (stage, fraction of the steps done, line)
# a failed deploy check (collisions) still gets its report: the report documents the design and is
# what a maker reads to decide; the run still exits 1 naming the deploy failure
GOES_ON = frozenset({"deploy"})
MAKE_STEPS = ("design", "process", "deploy", "report")  # in order; "process" is cut or print


@dataclass(frozen=True)
class _Plan:
    """A checked request: what to make, how, and where."""

    target: str
    size: float
    material: str | None
    hinge: str | None
    printer: str | None
    style: str | None
    shape_tol: str
    min_opening: float | None
    tiles: TilesChoice
    process: str
    fabrication: str
    stem: str

    @property
    def least_tile_mm(self) -> float:
        """The print style's own minimum tile (:func:`.print_tiles.least_tile_mm`, memoised); 0 for a cut."""
        return least_tile_mm(self.printer, str(self.style)) if self.printer else 0.0


def make(  # noqa: PLR0913 (the options of `fabkiri make`)
    target: str,
    size: float,
    *,
    material: str | None = None,
    hinge: str | None = None,
    printer: str | None = None,
    style: str | None = None,
    tiles: tuple[int, int] | str | None = None,
    shape_tol: str = conf.DEFAULT_SHAPE_TOL,
    min_opening: float | None = None,
    output: str | Path | None = None,
    progress: Told | Progress | None = None,
) -> MakeResult:
    """Design ``target`` at ``size`` mm for a laser ``material`` (``hinge`` kind) or a ``printer``
    (``style``), cut or print it at that size, deploy it and write the report. ``min_opening``: a
    floor on the deployed hole fraction, passed to the design (``design --min-opening``).

    With ``output`` every step's files are written into that folder as the step finishes; without
    it they stay in :attr:`MakeResult.files` (``write(folder)`` writes them). Raises
    :class:`InputError` for bad input before anything is done; a step that fails is recorded in
    the result (``ok`` false, ``exit_code`` the step's), not raised.

    ``progress(stage, fraction, line)`` hears each line with the step it belongs to (``make`` before
    the first) and the share of :data:`MAKE_STEPS` done; a one-argument callback hears the lines."""
    plan = _plan(
        target, size, material, hinge, printer, style, tiles, shape_tol, min_opening, output
    )
    say = _Steps(progress)
    out = Path(output) if output is not None else None
    result = MakeResult.of_plan(plan, out)
    say(
        f"make: {plan.target} at {plan.size:g} mm, {plan.fabrication}, "
        f"{plan.tiles.tiles[0]}x{plan.tiles.tiles[1]} tiles ({plan.tiles.reason})"
    )
    runs = {"design": _design, "cut": _cut, "print": _print, "deploy": _deploy, "report": _report}
    for name in (plan.process if step == "process" else step for step in MAKE_STEPS):
        run = runs[name]
        if not _run_step(result, plan, name, run, say) and name not in GOES_ON:
            break
    if out is not None:
        atomic_write_many(out, {MANIFEST: result.manifest_text()})
    return result


class _Steps:
    """make's lines for ``progress``, each with the step it belongs to and the share of the steps
    done: the loop over :data:`MAKE_STEPS` says when a step starts and ends."""

    def __init__(self, progress: Told | Progress | None) -> None:
        self.progress = None if progress is None else three_args(progress)
        self.stage, self.done = "make", 0

    def __call__(self, text: str) -> None:
        if self.progress is not None:
            self.progress(self.stage, min(self.done / len(MAKE_STEPS), 1.0), text)


def _floor(min_opening) -> float | None:
    """The ``--min-opening`` floor, checked as design checks it (a hole fraction in (0, 1))."""
    from .design_opening import check_floor

    if min_opening is None:
        return None
    try:
        floor = float(min_opening)
    except (TypeError, ValueError):
        raise InputError(Param("min_opening"), f" must be a number, got {min_opening!r}") from None
    check_floor(floor)
    return floor


def _plan(  # noqa: PLR0913 (make()'s options, checked before any design)
    target, size, material, hinge, printer, style, tiles, shape_tol, min_opening, output
) -> _Plan:
    """Every check of the request that needs no design: one :class:`InputError` naming the problem."""
    if (material is None) == (printer is None):
        raise InputError(
            "make needs exactly one of ",
            Param("material"),
            " (laser cut) or ",
            Param("printer"),
            " (3D print)",
        )
    try:
        size = float(size)
    except (TypeError, ValueError):
        raise InputError(Param("size"), f" must be a length in mm, got {size!r}") from None
    if not (np.isfinite(size) and 0 < size <= limits.MAX_LENGTH_MM):
        raise InputError(
            Param("size"),
            f" must be a positive length up to {limits.MAX_LENGTH_MM:g} mm, got {size:g}",
        )
    tiles = None if tiles is None else tile_count(tiles)  # "8x8" or (8, 8)
    if tiles is not None and (len(tiles) != 2 or min(tiles) < 2):
        raise InputError(
            Param("tiles"), f" needs at least 2x2 tiles, got {'x'.join(map(str, tiles))}"
        )
    curve = load_target(str(target), size)
    fab, intent = design_limits.resolve(material, hinge, printer, style, None, None, curve)
    assert fab is not None  # a material or a printer was given
    process = "cut" if material else "print"
    # the presets' own names and the hinge kind or style: "acrylic-3 tape", "prusa-mk4 tiles-and-strips"
    fabrication = fab.source
    least = least_tile_mm(printer, str(intent["style"])) if printer else 0.0
    choice = (
        given_tiles(tuple(tiles), curve, fab)
        if tiles is not None
        else choose_tiles(curve, fab, fabrication, least)
    )
    # the design's own refusals, before any step starts: too many tiles, tiles too wide to fit, tolerance
    limits.check_tiles(*choice.tiles, "design full", False)
    check_room(*choice.tiles, fab, curve)
    conf.parse_shape_tol(shape_tol)
    stem = Path(str(target)).stem if Path(str(target)).suffix else str(target)
    if output is not None:
        _check_output(Path(output), stem, process)
    floor = _floor(min_opening)  # last, as before: the other refusals first
    return _Plan(
        target=str(target),
        size=size,
        material=material,
        hinge=intent.get("hinge"),
        printer=printer,
        style=intent.get("style"),
        shape_tol=shape_tol,
        min_opening=floor,
        tiles=choice,
        process=process,
        fabrication=fabrication,
        stem=stem,
    )


def _check_output(folder: Path, stem: str, process: str) -> None:
    """The output folder can take every file ``make`` writes, none of them an input (the target)."""
    check_output_folder(folder)
    for name in (f"{stem}.json", f"{stem}.png", "report.html", MANIFEST, process, "deploy"):
        dest = folder / name
        if input_named_by(dest) is not None:
            raise InputError(
                f"refusing to write {dest}: it is an input of this command; choose another output"
            )
        if name in (process, "deploy") and dest.exists() and not dest.is_dir():
            raise InputError(f"output {dest} exists and is not a folder")
        if name not in (process, "deploy") and dest.is_dir():
            raise InputError(f"output {dest} is a folder where a file must go; nothing written")


def _run_step(result: MakeResult, plan: _Plan, name: str, run, say: _Steps) -> bool:
    """Run one step, time it, keep and write its files; whether the run goes on."""
    say.stage = name
    say(f"make: {name} ...")
    wall, cpu = time.perf_counter(), _cpu()
    try:
        ok, code, figures, files, details = run(result, plan, say)
    except FabkiriError as exc:
        if name == "design":  # refused before any work: bad input, nothing written
            raise
        # make's record names make's own command lines (its alternatives), so its flags too
        ok, code, figures, files, details = False, exc.exit_code, exc.cli_message(), {}, []
        result.alternatives = refusal_alternatives(result, plan, name, exc)
        if result.refused and not result.alternatives:  # nothing passes at this design: redesign
            details = options_after_refusal(result, plan, say, CHECKS)
    step = Step(
        name,
        ok,
        code,
        time.perf_counter() - wall,
        _cpu() - cpu,
        figures,
        sorted(files),
        details,
    )
    result.steps.append(step)
    result.files.update(files)
    if files and result.output is not None:
        atomic_write_many(result.output, files)
    say.done += 1
    say(
        f"make: {name} {'ok' if ok else f'failed (exit {code})'} in {step.wall_s:.1f} s "
        f"(CPU {step.cpu_s:.1f} s): {figures}"
    )
    return ok


def refusal_alternatives(result: MakeResult, plan: _Plan, step: str, error: FabkiriError) -> list:
    """The options that work when ``step`` (cut or print) refused: the seam of the ``advice`` work, whose
    refusal (``fabkiri.api.advice.Refused``) carries its checked alternatives, each with a ``.command``
    line the summary prints (and the CLI on stdout). Other failures (a read-back) name none."""
    from .advice import Refused

    result.refused = isinstance(error, Refused)
    return list(getattr(error, "alternatives", None) or [])


def _design(result: MakeResult, plan: _Plan, say: Progress) -> StepRun:
    """The design at the plan's tiles, and after a shape miss other counts and options
    (:mod:`.maker_design`); an alternative is named only once it also passes its cut or print and deploy.
    Tiles too narrow for the print style are refused before any design (:mod:`.maker_early`), and arms
    too narrow for a strip's tiles are not designed at this size (:mod:`.maker_arms`): larger sizes are
    (the tiles given, ``--tiles``, are, with a warning)."""
    narrow = narrow_of(plan)
    if narrow is not None:
        return refuse_narrow(result, plan, say, CHECKS, narrow)
    arms = arms_of(plan, given_too=True)
    if arms is not None and not plan.tiles.given:
        return skip_narrow_arms(result, plan, say, CHECKS, arms)
    if (
        arms is not None
    ):  # the user's tiles: designed as asked, with the figure (as design --printer)
        say(f"make: {arms.warning(plan.tiles.tiles)}")
    return design_step(result, plan, say, CHECKS)


def _ask(result: MakeResult, plan: _Plan):
    """How a refusal's options name this run's files, so each is a line that runs as it is: the
    pattern ``make`` wrote and its step folder (relative names when nothing is written)."""
    from .advice import Ask

    where = result.output
    file = f"{plan.stem}.json" if where is None else str(where / f"{plan.stem}.json")
    folder = plan.process if where is None else str(where / plan.process)
    return Ask(file=file, output=folder, given=plan.material or plan.printer)


def _cut(result: MakeResult, plan: _Plan, say: Progress) -> StepRun:
    from ..fabricate.cut.sheets import CutOptions
    from .cut import cut_files, cut_material

    assert result.pattern is not None
    material, hinge = cut_material(result.pattern, plan.material, plan.hinge)
    options = CutOptions(
        material=material, hinge=hinge, stem=plan.stem, pattern_file=f"{plan.stem}.json"
    )
    cut = cut_files(result.pattern, options, ask=_ask(result, plan))
    for w in cut.result.warnings:
        say(f"warning: {w}")
    man = cut.result.manifest
    length = sum(s["cut_length_mm"] for s in man["sheets"])
    secs = sum(s["cut_time_s"] for s in man["sheets"])
    figures = (
        f"{len(man['sheets'])} sheet(s), {man['hinge']} hinges, {material.name} at scale "
        f"{float(man['scale']):g}, cut {length / 1000:.2f} m (~{secs / 60:.1f} min), "
        f"{len(cut.readback.checks)} read-back checks passed"
        + (", verifier passed" if cut.readback.verifier is not None else "")
    )
    return StepRun(True, 0, figures, {f"cut/{k}": v for k, v in cut.files.items()}, [])


def _print(result: MakeResult, plan: _Plan, say: Progress) -> StepRun:
    from .print import PrintOptions, print_pattern

    assert result.pattern is not None
    out = print_pattern(
        result.pattern,
        PrintOptions(style=plan.style, printer=plan.printer, scale=1.0),
        stem=plan.stem,
        source=f"{plan.stem}.json",
        notify=say,
        ask=_ask(result, plan),
    )
    return StepRun(True, 0, out.describe(), {f"print/{k}": v for k, v in out.files.items()}, [])


def _deploy(result: MakeResult, plan: _Plan, say: Progress) -> StepRun:
    from .deploy import deploy_pattern

    assert result.pattern is not None
    out = deploy_pattern(result.pattern, plot=True, gif=True, frames=False)
    s = out.summary
    figures = (
        f"{s['path']} path, {s['frames']} frames, max E {s['energy_max']:.2e} at t = "
        f"{s['t_at_energy_max']:.3f}, "
        + ("collision-free" if s["collision_free"] else f"{s['overlaps']} overlaps")
    )
    return StepRun(
        out.success,
        0 if out.success else 1,
        figures,
        {f"deploy/{k}": v for k, v in out.files.items()},
        list(out.problems),
    )


def _report(result: MakeResult, plan: _Plan, say: Progress) -> StepRun:
    from ..render.report import build_report

    assert result.pattern is not None
    pattern = result.pattern
    states = dict(pattern.contracted) if {1, 2} <= set(pattern.contracted) else None
    with tempfile.TemporaryDirectory(prefix="fabkiri-make-") as tmp:
        folder = result.output
        if folder is None:  # the report reads the step folders: lay them out in a scratch folder
            folder = Path(tmp)
            for name, data in result.files.items():
                (folder / name).parent.mkdir(parents=True, exist_ok=True)
                (folder / name).write_bytes(data.encode() if isinstance(data, str) else data)
        made: dict[str, str | None] = {"cut": None, "print": None}
        made[plan.process] = str(folder / plan.process)
        page = build_report(
            pattern,
            source=f"{plan.stem}.json",
            cut=made["cut"],
            printed=made["print"],
            deploy=str(folder / "deploy"),
            states=states,
        )
    return StepRun(True, 0, f"{len(page) / 1e6:.2f} MB", {"report.html": page}, [])


# the steps an alternative of each process must pass before it is named (maker_design)
CHECKS = {"cut": (_cut, _deploy), "print": (_print, _deploy)}
