"""The top-level doors: ``fabkiri.standard``, ``load``, ``save``, ``design``, ``contract``, ``deploy``,
``verify``, ``cut``, ``print_pattern`` and ``make``.

Each takes plain values (``tiles="8x8"`` or ``(8, 8)``, a material's name or a
:class:`~fabkiri.fabricate.cut.materials.Material`, a pattern or the path of a pattern file) and
returns one result type (:mod:`fabkiri.api.results`). They are thin: the work and its policy are
the front doors the commands call (:func:`~.design.design_pattern`, :func:`~.cut.cut_files`,
:func:`~.print.print_pattern`, :func:`~.deploy.deploy_pattern`, :func:`~.maker.make`), so a
result's files are the bytes the command writes. Bad input raises
:class:`~fabkiri.errors.InputError`; a design, deployment, cut or print that a check refuses
is returned with ``ok`` false (a cut's or print's with the checked options that pass). ``progress(stage, fraction or None, message)`` hears how a long call goes.
"""

from __future__ import annotations

import os
from collections.abc import Callable, Iterable
from dataclasses import fields
from pathlib import Path
from typing import Any

from .. import limits
from ..design.core.stages import listening
from ..errors import InputError
from ..exchange.file_formats import format_names, pattern_format
from ..exchange.pattern_json import write_pattern
from ..fileio import atomic_write, atomic_write_many
from ..mechanics.contract import with_contracted_states
from ..mechanics.info import describe
from ..pattern.kinds.tessellation import DEFAULT_KIND, kinds, tessellation
from ..pattern.model import Pattern
from ..pattern.tilecount import tile_count
from .deploy import deploy_pattern
from .design import PatternRequest
from .designers import design_by_kind
from .patterns import export_pattern, load_pattern
from .results import (
    ContractResult,
    DeployResult,
    DesignResult,
    VerifyResult,
    inputs_of,
    remember_source,
    source_of,
    stem_of,
)
from .verification import DEFAULT_TOL_MM, verify_files

Progress = Callable[[str, float | None, str], None]  # (stage, fraction done or None, message)
PatternLike = Pattern | str | os.PathLike
Tiles = str | tuple[int, int] | list[int]


def _quiet(stage: str, fraction: float | None, message: str) -> None:
    """No progress wanted."""


def _pattern(pattern: PatternLike) -> Pattern:
    return pattern if isinstance(pattern, Pattern) else load(pattern)


def _options(what: str, given: dict[str, Any], allowed: Iterable[str]) -> dict[str, Any]:
    """``given`` when every name is one of ``allowed``; else one sentence naming the strangers."""
    known = set(allowed)
    unknown = sorted(set(given) - known)
    if unknown:
        raise InputError(
            f"{what} has no option {', '.join(map(repr, unknown))}; it takes {', '.join(sorted(known))}"
        )
    return given


def standard(
    tiles: Tiles = "8x8",
    kind: str = DEFAULT_KIND,
    *,
    tile_size: float = 10.0,
    angle_deg: float | None = None,
    name: str = "",
) -> Pattern:
    """The kind's standard pattern of ``tiles`` (``"8x8"`` or ``(8, 8)``) with both closed states
    stored, as ``fabkiri new`` makes it (``angle_deg`` None: the kind's open state)."""
    rows, cols = tile_count(tiles)
    limits.check_tiles(rows, cols, "new")
    limits.check_length(tile_size, "tile_size")
    if kind not in kinds():
        raise InputError(f"no {kind!r} tessellation; choose one of {', '.join(kinds())}")
    angle = {} if angle_deg is None else {"angle_deg": angle_deg}
    made = tessellation(kind).standard(rows, cols, tile_size=tile_size, name=name, **angle)
    return with_contracted_states(made)


def load(path: str | os.PathLike) -> Pattern:
    """The pattern in ``path``, its format chosen by the suffix (``.json``, ``.obj``, ``.fold``, a
    PyKirigami folder). Results made from it name their files after it and never write over it."""
    pattern = load_pattern(str(path))
    remember_source(pattern, Path(path))
    return pattern


def save(
    pattern: Pattern,
    path: str | os.PathLike,
    *,
    file_format: str | None = None,
    state: str = "deployed",
    unit: float | None = None,
    force: bool = False,
) -> Path:
    """Write ``pattern`` to ``path`` (atomically) in ``file_format`` or the format its suffix names:
    ``pattern.json`` as ``fabkiri new`` writes it, any other as ``fabkiri export`` does (``state``:
    ``deployed``, ``1`` or ``2``; a closed state the format needs is contracted and must close).
    Returns the path."""
    name = file_format or _format_named_by(Path(path))
    if name == "json":
        return write_pattern(pattern, path)
    out = export_pattern(pattern, name, state, unit=unit, force=force, output=str(path))
    if out.files is not None:
        atomic_write_many(path, out.files)
    elif out.text is not None:
        atomic_write(path, out.text)
    return Path(path)


def _format_named_by(path: Path) -> str:
    """The pattern format whose suffix ``path`` has, or one sentence naming those it can write."""
    writable = ("json", *format_names(writable=True))
    for name in format_names():
        if path.suffix and path.suffix.lower() in pattern_format(name).suffixes:
            return name
    raise InputError(
        f"{path}: no pattern format is named by the suffix {path.suffix or '(none)'!r}; "
        f"give file_format= one of {', '.join(writable)}"
    )


def design(
    target: str | None = None,
    tiles: Tiles | None = None,
    *,
    size: float | None = None,
    rigid: bool = False,
    kind: str = DEFAULT_KIND,
    material: str | None = None,
    printer: str | None = None,
    progress: Progress | None = None,
    **options: Any,
) -> DesignResult:
    """Design a pattern of ``tiles`` whose deployed outline is ``target`` (a name such as ``"circle"``
    or a .csv/.json/.svg file) at ``size`` mm, as ``fabkiri design`` does; with ``material`` or
    ``printer`` the design is fabrication-aware. ``options`` are the other
    :class:`~.design.PatternRequest` fields (``symmetry``, ``hinge``, ``style``, ``shape_tol``,
    ``min_opening``, ``contracted_target``, ``name``, ``seed``, ...). ``progress`` hears the start
    and end (stage ``design``), each retry note (fraction None) and, in the stages whose steps are
    known, the share of the stage done (stage ``continuation`` or ``minimax``)."""
    say = progress or _quiet
    names = {f.name for f in fields(PatternRequest)} - {"target", "tiles", "size", "rigid", "kind"}
    extra = _options("design", options, names - {"material", "printer"})
    if isinstance(extra.get("contracted_target"), str):
        extra["contracted_target"] = (extra["contracted_target"],)
    request = PatternRequest(
        tiles=None if tiles is None else tile_count(tiles),
        target=target,
        size=size,
        rigid=rigid,
        kind=kind,
        material=material,
        printer=printer,
        **extra,
    )
    what = f"{target or 'closed-state targets'} {'x'.join(map(str, request.tiles or ()))}"
    say("design", 0.0, f"designing {what.strip()}")
    with listening(
        None if progress is None else lambda stage, f: say(stage, f, f"{stage} {f:.0%}")
    ):
        outcome = design_by_kind(request, notify=lambda text: say("design", None, text))
    say("design", 1.0, f"design {outcome.report.get('status', '')}".strip())
    return DesignResult(
        pattern=outcome.pattern,
        report=outcome.report,
        valid=bool(outcome.valid),
        stem=stem_of(outcome.pattern),
        messages=list(getattr(outcome, "messages", [])),
        outcome=outcome,
    )


def contract(pattern: PatternLike) -> ContractResult:
    """``pattern`` with both closed states computed and stored, and its figures (``fabkiri info``)."""
    pattern = _pattern(pattern)
    closed = with_contracted_states(pattern)
    src = source_of(pattern)
    if src is not None:  # the contracted pattern is named and guarded as the one it came from
        remember_source(closed, src)
    return ContractResult(
        pattern=closed, info=describe(closed), stem=stem_of(closed), inputs=inputs_of(closed)
    )


def deploy(
    pattern: PatternLike,
    steps: int = 40,
    *,
    path: str = "auto",
    driver: str = "auto",
    plot: bool = False,
    gif: bool = False,
    frames: bool = True,
    progress: Progress | None = None,
) -> DeployResult:
    """The deployment path of ``pattern`` from closed state 1 through the deployed state to closed
    state 2 in ``steps`` steps, and the files ``fabkiri deploy`` writes (``plot``: energy.png,
    ``gif``: deploy.gif, ``frames``: one pattern per frame)."""
    pattern = _pattern(pattern)
    say = progress or _quiet
    say("deploy", 0.0, f"deploying {pattern.name or 'the pattern'} in {steps} steps")
    out = deploy_pattern(
        pattern, steps, path=path, driver=driver, plot=plot, gif=gif, frames=frames
    )
    say("deploy", 1.0, "deployed" if out.success else "; ".join(out.problems))
    return DeployResult(
        figures=out.summary,
        problems=list(out.problems),
        stem=stem_of(pattern),
        outcome=out,
        inputs=inputs_of(pattern),
    )


def verify(
    pattern: PatternLike,
    *,
    layout: str | os.PathLike | None = None,
    tol_mm: float | None = DEFAULT_TOL_MM,
    tol_rad: float = 1e-6,
    shape_tol: str = "2%",
) -> VerifyResult:
    """``fabkiri verify``: that ``pattern`` closes into both closed states (``tol_mm`` None: the
    relative tier for solver output, as ``--exact``) and, with ``layout``, that a cut file (.dxf or
    .svg) matches it."""
    pattern = _pattern(pattern)
    report = verify_files(
        pattern,
        layout,
        tol_mm=DEFAULT_TOL_MM if tol_mm is None else tol_mm,
        exact=tol_mm is None,
        tol_rad=tol_rad,
        shape_tol=shape_tol,
    )
    return VerifyResult(
        pattern=pattern, report=report, stem=stem_of(pattern), inputs=inputs_of(pattern)
    )
