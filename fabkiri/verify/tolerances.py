"""The verifier's tolerances: the relative tiers or one fabrication tolerance in mm.

The tiers: docs/algorithm.md#tolerance-tiers.

Every pattern check compares a measured figure with a :class:`Tolerances`; angle residuals go through
:func:`angle_check`, in rad (exact tiers) or as the displacement they cause at the tile size.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..pattern.model import Pattern
from .report import Check, measured

TIER_EXPORTED = 1e-9  # analytic or exported data, relative to the mean tile edge (the tiers above)
TIER_OPTIMISED = 1e-5  # optimiser output
MIN_EDGE_REL = 1e-3
MIN_ANGLE_RAD = 1e-3
DEFAULT_PATH_STEPS = 32


@dataclass(frozen=True)
class Tolerances:
    length: float  # mm
    angle: float  # rad
    tile_size: float  # mm (mean tile edge)
    tier: str
    mm_angles: bool = (
        False  # angle residuals compared as their displacement (rad x tile size) with ``length``
    )

    @property
    def area(self) -> float:  # mm²: a length tolerance times the tile size
        return self.length * self.tile_size

    def describe(self) -> str:
        if self.mm_angles:
            return (
                f"{self.tier}: {self.length:.3g} mm for lengths, and for angles as their displacement at "
                f"the tile size"
            )
        return f"exact ({self.tier}): {self.length:.3g} mm, {self.angle:.3g} rad"


def fabrication_tolerances(
    tol_mm: float, tile_size: float, tier: str = "fabrication"
) -> Tolerances:
    """One tolerance in mm: lengths compare with it, angles by the displacement they cause at ``tile_size``."""
    return Tolerances(
        float(tol_mm), float(tol_mm) / float(tile_size), float(tile_size), tier, mm_angles=True
    )


def angle_check(
    name: str,
    rad: np.ndarray,
    sizes: np.ndarray | float,
    tol: Tolerances,
    worst: str,
    *,
    group: str,
    detail: str = "",
    applies: bool = True,
    id: str = "",
) -> Check:
    """An angle residual check: in rad (exact tier) or as mm of displacement at each item's tile size."""
    rad = np.asarray(rad, dtype=float)
    if not tol.mm_angles:
        return measured(
            name,
            largest(rad),
            tol.angle,
            "rad",
            worst=worst_at(worst, rad),
            group=group,
            detail=detail,
            applies=applies,
            id=id,
        )
    mm = rad * np.broadcast_to(np.asarray(sizes, dtype=float), rad.shape)
    note = f"angle residual x tile size (largest angle {largest(rad):.3g} rad)"
    return measured(
        name,
        largest(mm),
        tol.length,
        "mm",
        worst=worst_at(worst, mm),
        group=group,
        detail=f"{detail}; {note}" if detail else note,
        applies=applies,
        id=id,
    )


def tolerances(pattern: Pattern, tol_mm: float | None = None, tol_rad: float = 1e-6) -> Tolerances:
    """Resolve the tolerances: explicit mm (angles as displacement at the tile size), or a relative tier."""
    size = pattern.tile_size
    if tol_mm is not None:
        return fabrication_tolerances(float(tol_mm), size)
    design = pattern.design or {}
    source = design.get("source")
    optimised = any(k in design for k in ("solver", "solve", "residuals", "report")) or (
        isinstance(source, dict) and source.get("tier") == tier_name(optimised=True)
    )  # fabkiri's solver, or files that close to an optimiser's precision (recorded at import)
    rel = TIER_OPTIMISED if optimised else TIER_EXPORTED
    return Tolerances(rel * size, float(tol_rad), size, tier_name(optimised))


def tier_name(optimised: bool) -> str:
    """The relative tier's name: optimiser output (1e-5) or exported data (1e-9)."""
    return "optimiser output" if optimised else "exported data"


def worst_at(prefix: str, values: np.ndarray) -> str | None:
    """The item with the largest value, as ``"<prefix> <index>"`` (None when there are none)."""
    return f"{prefix} {int(np.argmax(values))}" if len(values) else None


def largest(values: np.ndarray) -> float:
    """The largest value, 0 when there are none."""
    return float(np.max(values, initial=0.0)) if len(values) else 0.0
