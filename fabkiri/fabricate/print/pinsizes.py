"""The sizes of print-in-place pinned hinges from the printer preset: how many hinges stack at a pivot,
their ear levels and the radii of one pin joint, or why the preset refuses pins.

The rules :mod:`.pingeom`'s plans are built on, apart from them: ``design`` and ``info`` size the
pinned style by these (:data:`~..planrules.PIN_PLAN`) and load none of the plan geometry.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from ...errors import FabricationError
from ...pattern.kinds.tessellation import tessellation

if TYPE_CHECKING:
    from ...pattern.model import Pattern
    from .printers import Printer


def pin_stack(pattern: Pattern) -> int:
    """Hinges stacked coaxially at one pivot: as many as a closed state of the pattern's kind joins
    at a point (``hole_arity / 2``: two for quads, three for kagome), two ear levels each."""
    return max(2, tessellation(pattern.kind).hole_arity // 2)


@dataclass(frozen=True)
class PinLevels:
    """Z layout of the ear levels of a pinned print (mm): two per stacked hinge."""

    thickness: float
    ear: float
    axial: float
    count: int = 4  # ear levels, 2 × the hinges stacked at a pivot

    def level(self, k: int) -> tuple[float, float]:
        z0 = k * (self.ear + self.axial)
        return z0, z0 + self.ear

    def gaps(self) -> list[float]:
        """The middle of every axial gap between two ear levels (mm)."""
        return [self.level(k)[1] + 0.5 * self.axial for k in range(self.count - 1)]


def pin_levels(printer: Printer, stack: int = 2) -> PinLevels:
    """The ear levels of ``stack`` coaxial hinges in the preset's pinned tile thickness, or
    :class:`FabricationError` if an ear would be under three layers."""
    T = printer.pin.tile_thickness_mm
    az = printer.axial_clearance_mm
    n = 2 * stack
    ear = (T - (n - 1) * az) / n
    if ear < 3 * printer.layer_mm - 1e-9:
        raise FabricationError(
            f"pinned hinges need {n} stacked ears ({stack} hinges at a pivot): a {T:g} mm tile leaves "
            f"{ear:.2f} mm per ear after {n - 1} {az:g} mm axial clearances, under three layers "
            f"({3 * printer.layer_mm:g} mm); raise the preset's pin.tile_thickness_mm (--tile-thickness "
            f"{ceil_mm(n * 3 * printer.layer_mm + (n - 1) * az):g})"
        )
    return PinLevels(thickness=T, ear=ear, axial=az, count=n)


def ceil_mm(v: float) -> float:
    """``v`` rounded up to 0.1 mm (a thickness to suggest)."""
    return float(np.ceil(v * 10 - 1e-9) / 10)


@dataclass(frozen=True)
class PinGeometry:
    """Radii of one pin joint (mm). The pin flares upward (retains the ring)."""

    ear: float  # ear disc radius
    hollow: float  # the other tiles are cleared to this radius around the pivot
    pin_bottom: float
    pin_top: float
    hole_bottom: float  # ring hole, horizontal radius
    hole_top: float


def pin_geometry(printer: Printer, levels: PinLevels) -> PinGeometry:
    c = printer.radial_clearance_mm
    r = printer.pin.ear_radius_mm
    rp = printer.pin.pin_radius_mm
    flare = 2.0 * c  # the ring's narrowest hole is smaller than the pin's widest point
    slope = flare / levels.ear
    ch = float(c * np.sqrt(1.0 + slope * slope))  # horizontal clearance giving c normal to the cone
    g = PinGeometry(
        ear=r,
        hollow=r + c,
        pin_bottom=rp,
        pin_top=rp + flare,
        hole_bottom=rp + ch,
        hole_top=rp + flare + ch,
    )
    wall = r - g.hole_top
    if wall < 2 * printer.nozzle_mm - 1e-9:
        raise FabricationError(
            f"pinned hinges: the ear ring wall is {wall:.2f} mm (ear radius {r:g} mm, pin {rp:g} mm, clearance "
            f"{c:g} mm, ears {levels.ear:.2f} mm thick), under two nozzle widths ({2 * printer.nozzle_mm:g} mm); "
            "raise pin.ear_radius_mm, or the tile thickness (--tile-thickness: thicker ears flare the pin "
            "less)"
        )
    if rp < printer.nozzle_mm:
        raise FabricationError(
            f"pin radius {rp:g} mm is under one nozzle width ({printer.nozzle_mm:g} mm)"
        )
    return g
