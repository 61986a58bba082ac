"""The top-level doors that make files for a machine: ``fabkiri.cut``, ``fabkiri.print_pattern`` and
``fabkiri.make`` (the rest, and what they share, are in :mod:`.front`)."""

from __future__ import annotations

from collections.abc import Callable, Iterable
from dataclasses import fields
from pathlib import Path
from typing import Any

from ..errors import CheckFailed, InputError
from ..fabricate.cut.materials import Material, parse_setting
from ..fabricate.cut.sheets import CutOptions
from ..pattern.model import Pattern
from ..pattern.tilecount import tile_count
from .cut import cut_files, cut_material, parse_sheet
from .front import PatternLike, Progress, Tiles, _options, _pattern, _quiet
from .maker import make as _make
from .maker_result import MakeResult
from .print import PrintOptions
from .print import print_pattern as _print_pattern
from .results import CutResult, PrintResult, inputs_of, source_of, stem_of


def _material(
    pattern: Pattern, material: str | Material | None, hinge: str | None, settings: Iterable[str]
) -> tuple[Material, str | None]:
    """The material to cut with: a name (None: the design's, else acrylic-3) or a Material object,
    with the ``FIELD=VALUE`` settings applied."""
    if not isinstance(material, Material):
        return cut_material(pattern, material, hinge, settings=settings)
    changes = dict(parse_setting(s) for s in settings)
    return material.override(**changes), hinge


def cut(
    pattern: PatternLike,
    material: str | Material | None = None,
    *,
    hinge: str | None = None,
    state: int = 1,
    scale: float | str | None = None,
    width: float | str | None = None,
    sheet: str | tuple[float, float] = (600.0, 400.0),
    settings: Iterable[str] = (),
    progress: Progress | None = None,
    **options: Any,
) -> CutResult:
    """Laser-cut files of closed state ``state`` of ``pattern`` from ``material`` (a preset's name such
    as ``"acrylic-3"``, a material .json, a Material object, or None: the one the design was made for),
    verified by reading them back, as ``fabkiri cut`` makes them. ``scale`` or ``width`` (mm) may be
    ``"auto"``; ``settings`` are ``FIELD=VALUE`` material overrides; ``options`` the other
    :class:`~fabkiri.fabricate.cut.sheets.CutOptions` fields (``layout``, ``formats``, ``margin``, ...).
    A cut a check refuses (too thin for the material, a read-back that fails) is returned with ``ok``
    false, the ``problems`` and the checked ``alternatives`` (``advice``); bad input (an unknown
    material, an unreadable file) raises :class:`~fabkiri.errors.InputError`."""
    pattern = _pattern(pattern)
    say = progress or _quiet
    mat, kind = _material(pattern, material, hinge, settings)
    fixed = {"material", "hinge", "state", "scale", "width", "sheet", "stem", "pattern_file"}
    extra = _options("cut", options, {f.name for f in fields(CutOptions)} - fixed)
    if isinstance(extra.get("formats"), str):
        extra["formats"] = tuple(f.strip() for f in extra["formats"].split(","))
    stem, src = stem_of(pattern), source_of(pattern)
    opts = CutOptions(
        material=mat,
        hinge=kind,
        state=state,
        sheet=parse_sheet(sheet),
        scale=_number_or_auto(scale, "scale"),
        width=_number_or_auto(width, "width"),
        stem=stem,
        pattern_file="" if src is None else src.name,
        **extra,
    )
    say("cut", 0.0, f"cutting {stem} from {mat.name}")
    try:
        out = cut_files(pattern, opts)
    except CheckFailed as exc:  # refused (the command's exit 1): a result that says why
        say("cut", 1.0, f"refused: {exc}")
        return CutResult(
            files={},
            manifest={},
            material=mat.name,
            stem=stem,
            inputs=inputs_of(pattern),
            error=exc,
            alternatives=list(getattr(exc, "alternatives", [])),
        )
    say(
        "cut",
        1.0,
        f"{len(out.result.sheets)} sheet(s), read-back {'passed' if out.readback.ok else 'failed'}",
    )
    return CutResult(
        files=dict(out.files),
        manifest=out.result.manifest,
        material=mat.name,
        stem=stem,
        warnings=list(out.result.warnings),
        readback_ok=bool(out.readback.ok),
        outcome=out,
        inputs=inputs_of(pattern),
    )


def _number_or_auto(value: float | str | None, what: str) -> float | Any:
    """A positive number, ``"auto"`` or None, as ``--scale``/``--width`` take them."""
    if value is None or (isinstance(value, str) and value.strip().lower() == "auto"):
        return None if value is None else "auto"
    try:
        number = float(value)
    except (TypeError, ValueError):
        number = float("nan")
    if not 0 < number < float("inf"):
        raise InputError(f"{what} expects a positive number or 'auto', got {value!r}")
    return number


def print_pattern(
    pattern: PatternLike,
    printer: str | None = None,
    *,
    style: str | None = None,
    scale: float | str = 1.0,
    state: int | None = None,
    progress: Progress | None = None,
    **options: Any,
) -> PrintResult:
    """3D-print files of ``pattern`` for ``printer`` (a preset's name or a printer .json; None: the one
    the design was made for, else the default) in ``style`` (``tiles-and-strips``, ``strips``,
    ``pinned``), at ``scale`` (or ``"auto"``), verified, as ``fabkiri print`` makes them. ``options``
    are the other :class:`~.print.PrintOptions` fields (``step``, ``marks``, ``gap``, ...). A print a
    check refuses (past the bed, strips too narrow, a mesh check) is returned with ``ok`` false, the
    ``problems`` and the checked ``alternatives`` (``advice``); bad input raises
    :class:`~fabkiri.errors.InputError`."""
    pattern = _pattern(pattern)
    say = progress or _quiet
    fixed = {"printer", "style", "scale", "state"}
    extra = _options("print_pattern", options, {f.name for f in fields(PrintOptions)} - fixed)
    opts = PrintOptions(
        printer=printer,
        style=style,
        scale=_number_or_auto(scale, "scale") or 1.0,
        state=state,
        **extra,
    )
    stem, src = stem_of(pattern), source_of(pattern)
    say("print", 0.0, f"printing {stem}")
    messages: list[str] = []

    def heard(text: str) -> None:
        messages.append(text)
        say("print", None, text)

    try:
        out = _print_pattern(
            pattern,
            opts,
            stem=stem,
            source=f"{stem}.json" if src is None else src.name,
            notify=heard,
        )
    except CheckFailed as exc:  # refused (the command's exit 1): a result that says why
        say("print", 1.0, f"refused: {exc}")
        return PrintResult(
            files={},
            scale=opts.scale if isinstance(opts.scale, float) else float("nan"),
            printer=printer or "",
            description="",
            stem=stem,
            messages=messages,
            inputs=inputs_of(pattern),
            error=exc,
            alternatives=list(getattr(exc, "alternatives", [])),
        )
    say("print", 1.0, out.describe(cli=False))
    return PrintResult(
        files=dict(out.files),
        scale=float(out.scale),
        printer=str(out.printer.name),
        description=out.describe(cli=False),
        stem=stem,
        messages=list(out.messages),
        outcome=out,
        inputs=inputs_of(pattern),
    )


def make(
    target: str,
    size: float,
    *,
    tiles: Tiles | None = None,
    output: str | Path | None = None,
    progress: Progress | Callable[[str], None] | None = None,
    **options: Any,
) -> MakeResult:
    """From a target outline at ``size`` mm to files a machine accepts in one call
    (:func:`fabkiri.api.maker.make`): with ``material=`` it is cut, with ``printer=`` printed.
    ``tiles`` (``"8x8"`` or a pair; None: chosen for the process). ``progress(stage, fraction,
    message)`` hears each of make's lines with its step (``design``, ``cut`` or ``print``,
    ``deploy``, ``report``) and the share of the steps done; a one-argument callback hears the
    lines alone."""
    extra = _options(
        "make", options, ("material", "hinge", "printer", "style", "shape_tol", "min_opening")
    )
    return _make(
        target,
        size,
        tiles=None if tiles is None else tile_count(tiles),
        output=output,
        progress=progress,
        **extra,
    )
