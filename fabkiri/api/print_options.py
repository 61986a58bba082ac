"""What ``print`` is asked (:class:`PrintOptions`), the printer it uses and the smallest scale it prints
at: shared by the front door (:mod:`.print`) and its advice (:mod:`.advice`), which sits below it."""

from __future__ import annotations

from dataclasses import dataclass

from ..errors import InputError, Param
from ..fabricate import fabricability as fb
from ..fabricate.print.job import print_style
from ..fabricate.print.printers import load_printer
from ..pattern.model import Pattern

DEFAULT_STYLE = "tiles-and-strips"


@dataclass(frozen=True)
class PrintOptions:
    """What to print and how; ``None`` keeps the design's intent or the printer preset's value.

    ``scale`` is mm printed per mm of the pattern, or ``"auto"``: the smallest scale the plan
    checks accept. Thicknesses, widths, gaps and clearances (mm) override the printer preset;
    ``tile_thickness`` is the pinned tiles' thickness for ``style="pinned"``.
    """

    style: str | None = None
    state: int | None = None  # None: the state the design was made to print (its intent), else 1
    printer: str | None = None
    scale: float | str = 1.0
    tile_thickness: float | None = None
    strip_thickness: float | None = None
    strip_width: float | None = None
    strip_reach: float | None = None
    gap: float | None = None
    radial_clearance: float | None = None
    axial_clearance: float | None = None
    step: bool = False
    marks: bool = False
    material: str = "acrylic-3"
    force: bool = False


def minimum(pattern: Pattern, style: str, printer, state: int, memo: dict):
    """:func:`~fabkiri.fabricate.fabricability.print_minimum`, kept in ``memo`` (one pattern's answers):
    a refused print and its advice both ask for the printer and style asked for (a bisection on the plan
    checks, seconds at 32x32)."""
    key = ("minimum", style, printer, int(state))
    if key not in memo:
        memo[key] = fb.print_minimum(pattern, style, printer, int(state))
    return memo[key]


def printer_for(name: str | None, style: str, o: PrintOptions):
    """The printer ``print`` uses for ``style``: the preset with the options' overrides (pinned tiles
    have their own, thicker, preset thickness)."""
    pinned = print_style(style).own_tile_thickness
    return load_printer(name).with_overrides(
        tile_thickness_mm=None if pinned else o.tile_thickness,
        pin_tile_thickness_mm=o.tile_thickness if pinned else None,
        strip_thickness_mm=o.strip_thickness,
        strip_width_mm=o.strip_width,
        strip_reach_mm=o.strip_reach,
        gap_mm=o.gap,
        radial_clearance_mm=o.radial_clearance,
        axial_clearance_mm=o.axial_clearance,
    )


def refuse_unread(style: str, o: PrintOptions) -> None:
    """Refuse, before any work, an option ``style`` reads nothing of: strip sizes for pinned hinges, the
    axial clearance of pins for strip hinges, pad marks for tiles that are printed."""
    kind = print_style(style)
    pins = ["strip_thickness", "strip_width", "strip_reach"]  # what pin hinges leave unread
    unread = ["axial_clearance"] if kind.strip_hinges else pins
    for name in unread:
        if getattr(o, name) is not None:
            raise InputError(
                Param(name),
                f" is read by nothing in {style} prints; drop it, or choose another ",
                Param("style"),
            )
    if o.marks and not kind.loose_strips:
        raise InputError(
            Param("marks", True),
            " engraves strip pads on laser-cut tiles: it needs ",
            Param("style", "strips"),
        )
