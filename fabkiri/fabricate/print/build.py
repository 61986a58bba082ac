"""What a print style builds: the job (:class:`PrintJob`: the bodies on each bed), the job with its
solids (:class:`Realised`), what the style's own checks found (:class:`StyleChecks`), and the helpers
the styles build with.

Apart from the styles' rules (:mod:`.job`): a design sizes every style for its summary and loads
none of this.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from typing import TYPE_CHECKING, Any

from ...errors import FabricationError

if TYPE_CHECKING:
    from ...pattern.model import Pattern
    from . import geometry as printgeom
    from . import pingeom
    from .printers import Printer
    from .solid import Body


@dataclass(frozen=True, eq=False)
class PrintJob:
    """Everything one ``fabkiri print`` run produces, before writing.

    ``beds[k]`` lists the bodies printed together on bed k; ``shift`` moved the
    closed-state plan onto the bed (for whole-pattern styles).
    """

    style: str
    state: int
    printer: Printer
    plan: printgeom.ClosedPlan
    beds: list[list[Body]]
    shift: tuple[float, float] = (0.0, 0.0)
    strips: printgeom.Strips | None = None
    pins: pingeom.PinPlan | None = None
    placements: list[dict] = field(default_factory=list)  # strips style: where each part went
    unlabelled: list[int] = field(default_factory=list)  # strips too small for their engraved ID
    layout: str = "recessed"  # tiles-and-strips: "recessed" or "stacked" (see tiles_and_strips)
    layer_changes: list = field(
        default_factory=list
    )  # (print_z, kind, material) filament swaps, one extruder

    def z_levels(self) -> dict[str, float]:
        """Heights (mm) of the sections the checks take: bottom strips, bare tile, top strips."""
        T, ts = self.printer.tile_thickness_mm, self.printer.strip_thickness_mm
        if self.layout == "stacked":
            return {"bottom": 0.5 * ts, "tiles": 0.5 * (ts + T), "top": T + 0.5 * ts}
        return {"bottom": 0.5 * ts, "tiles": 0.5 * T, "top": T - 0.5 * ts}


def fits(bounds, printer: Printer, what: str) -> None:
    """Refuse a plan whose ``bounds`` (x0, y0, x1, y1 in mm) overhang the printer's bed."""
    w, h = bounds[2] - bounds[0], bounds[3] - bounds[1]
    bx, by, _ = printer.bed_mm
    if w > bx or h > by:
        raise FabricationError(
            f"{what} is {w:.1f} x {h:.1f} mm and does not fit the {bx:g} x {by:g} mm bed of printer "
            f"{printer.name}"
        )


def centre_shift(bounds, printer: Printer) -> tuple[float, float]:
    """The shift that centres ``bounds`` on the bed."""
    bx, by, _ = printer.bed_mm
    return 0.5 * bx - 0.5 * (bounds[0] + bounds[2]), 0.5 * by - 0.5 * (bounds[1] + bounds[3])


def scaled(pattern: Pattern, k: float) -> Pattern:
    """The pattern ``k`` times its size (nodes and stored closed states)."""
    return replace(
        pattern,
        nodes=pattern.nodes * k,
        contracted={s: c * k for s, c in pattern.contracted.items()},
    )


@dataclass(eq=False)
class Realised:
    """A job with its solids: ``manifolds[k][i]`` is body i of bed k."""

    job: PrintJob
    manifolds: list[list]
    meshes: list[list]
    snaps: list[list[float]] = field(
        default_factory=list
    )  # grid (mm) a body's outlines were snapped to, 0: exact


@dataclass
class StyleChecks:
    """What a print style's own checks found: ``problems`` refuse the print (one line each),
    ``verifier`` is the layout verifier's report if one ran, ``notes`` are said to the user."""

    problems: list[str] = field(default_factory=list)
    verifier: Any = None
    notes: list[str] = field(default_factory=list)
