"""A print job, its solids, and the registry of print styles.

A print style turns a closed state into the bodies printed on each bed
(:class:`PrintJob`) and says how the clearances between them are measured. The
styles are one module each in :mod:`fabkiri.fabricate.print.styles`, loaded on first
use as trimesh loads its file-format handlers; a new style is one module that
calls :func:`register_style` and one line in the built-in table of :data:`_STYLES`.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field, replace
from typing import TYPE_CHECKING, Any

from ...errors import FabricationError
from ...registry import Registry

# the plan geometry and the solids are annotations here: a style lookup (a cut's web checks, a design's
# fabricability summary) loads neither
if TYPE_CHECKING:
    from ...pattern.model import Pattern
    from ..planrules import PlanRule
    from . import geometry as printgeom
    from . import pingeom
    from .checks import MeshReport
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


@dataclass(frozen=True, eq=False)
class PrintStyle:
    """One way of printing a closed state (a strategy object, chosen by name).

    ``build`` makes the job; ``clearances`` measures, on the realised solids,
    the clearances between bodies that may move apart, filling a
    :class:`~.meshchecks.MeshReport`. ``tiles`` gives the solid of the printed
    tiles, the height of the section the tile check takes, and what that check
    masks out (``None``: the style prints no tiles). ``advise`` adds to a refusal
    what would make the job print (then ``build`` names the scales itself). With
    ``body_per_material`` each bed holds one body per material (one STL each; their
    overlap is their intersection). ``checks`` are the style's own checks of a
    realised job (pinned: the sweep along the deployment path; tiles-and-strips: the
    layout verifier on the printed top faces). ``own_tile_thickness``: the tiles have
    their own preset thickness, which ``--tile-thickness`` sets. ``loose_strips``: the
    strips are printed on their own and glued on by hand (assembly pieces and map; the
    tiles may be laser-cut with the pads engraved, ``print --marks``). ``strip_hinges``:
    the hinges are printed strips (the bill of materials counts them; pinned: pins).
    ``has_layout``: the job's ``layout`` (recessed or stacked strips) is the style's and
    goes in the manifest. ``limits(printer)``: what ``design --printer --style`` asks of
    every tile for this style's hinges (mm, as :func:`~.design_limits.printer_limits`).
    ``plan``: how ``--scale auto``, ``design`` and ``info`` size it (:class:`~.planrules.PlanRule`:
    its plan check, closed-form bound and the preset fields they read).
    """

    name: str
    build: Callable[[Pattern, int, Printer], PrintJob]
    clearances: Callable[[Realised, MeshReport], None]
    tiles: Callable[..., tuple[Any, float, Any]] | None = None
    advise: Callable[[Pattern, int, Printer, float], str] | None = None
    body_per_material: bool = False
    checks: Callable[[Pattern, Realised, MeshReport], StyleChecks] | None = None
    own_tile_thickness: bool = False
    loose_strips: bool = False
    strip_hinges: bool = True
    has_layout: bool = False
    limits: Callable[[Printer], dict] | None = None
    plan: PlanRule | None = None


@dataclass
class StyleChecks:
    """What a print style's own checks found: ``problems`` refuse the print (one line each),
    ``verifier`` is the layout verifier's report if one ran, ``notes`` are said to the user."""

    problems: list[str] = field(default_factory=list)
    verifier: Any = None
    notes: list[str] = field(default_factory=list)


# built-in styles, imported when first asked for (their modules call register_style())
_STYLES: Registry[PrintStyle] = Registry(
    {
        "strips": "fabkiri.fabricate.print.styles.strips",
        "tiles-and-strips": "fabkiri.fabricate.print.styles.tiles_and_strips",
        "pinned": "fabkiri.fabricate.print.styles.pinned",
    }
)
STYLES = tuple(_STYLES.builtin)


def register_style(style: PrintStyle) -> PrintStyle:
    """Add a style to the registry (a style's module calls this when it is imported)."""
    return _STYLES.add(style.name, style)


def print_style(name: str) -> PrintStyle:
    """The registered style of this name, or :class:`FabricationError` naming the known ones."""
    found = _STYLES.find(name)
    if found is None:
        known = ", ".join(_STYLES.names())
        raise FabricationError(f"unknown print style {name!r}; choose one of {known}")
    return found
