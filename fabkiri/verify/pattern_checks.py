"""Geometric proof that a pattern closes into both compact states.

The method: docs/algorithm.md#contraction and docs/algorithm.md#verifier-checks.

:func:`verify_pattern` measures, with named tolerances:

* every tile simple (GEOS-valid, interior angles summing to 2π), CCW and not
  degenerate;
* per closed state: loop closure per hole, tiles congruent to the deployed
  tiles, holes of zero area, every folded gap closed (endpoints coincident for
  rhombus holes, or collinear with a T-junction for parallelogram holes),
  compactness (no overlaps, union area = sum of tile areas, no interior gaps,
  one outline), and agreement with a stored closed state;
* design residuals: edge pairs (or the parallelogram conditions) and rings per
  state, hinge sums when rigid deployability is claimed;
* the rigid deployment path, sampled at ``path_steps`` + 1 angles, when claimed;
* the shape of the outline against each recorded target curve (Hausdorff distance over the whole outline,
  deployed and closed states, against ``shape_tol``).

Closed states come from :func:`fabkiri.mechanics.contract.contract` (never
averaged); stored closed states are checked against them.

The checks live by concern in :mod:`.tolerances`, :mod:`.closed_checks`, :mod:`.compactness` and
:mod:`.residual_checks`; this module is the entry point and re-exports the names callers import.
"""

from __future__ import annotations

import numpy as np
import shapely

from ..mechanics.contract import contract
from ..pattern import geometry
from ..pattern.lattice_counts import topology_count
from ..pattern.model import Pattern
from ..pattern.topology import STATES
from .closed_checks import closed_state_checks
from .compactness import compactness_checks, enclosed_gaps, overlap_check, state_check_id
from .outlines import target_checks
from .report import Check, Report, measured
from .residual_checks import residual_checks, rigid_claimed, rigid_path, rigid_path_checks
from .tolerances import (
    DEFAULT_PATH_STEPS,
    MIN_ANGLE_RAD,
    MIN_EDGE_REL,
    TIER_EXPORTED,
    TIER_OPTIMISED,
    Tolerances,
    angle_check,
    fabrication_tolerances,
    tolerances,
    worst_at,
)

__all__ = [
    "DEFAULT_PATH_STEPS",
    "TIER_EXPORTED",
    "TIER_OPTIMISED",
    "Tolerances",
    "angle_check",
    "closed_state_checks",
    "compactness_checks",
    "enclosed_gaps",
    "fabrication_tolerances",
    "residual_checks",
    "rigid_claimed",
    "rigid_path",
    "rigid_path_checks",
    "state_check_id",
    "tile_checks",
    "tolerances",
    "topology_checks",
    "verify_pattern",
]


def tile_checks(pattern: Pattern, tol: Tolerances) -> list[Check]:
    corners = pattern.corners()
    angles = geometry.corner_angles(corners)
    simple_sum = (corners.shape[1] - 2) * np.pi  # a simple CCW n-gon's angle sum
    angle_sum_off = np.abs(angles.sum(axis=1) - simple_sum)
    invalid = ~shapely.is_valid(shapely.polygons(corners))
    crossed = np.flatnonzero(invalid | (angle_sum_off > 1e-6))
    out = []
    detail = ""
    if len(crossed):
        sums = ", ".join(
            f"tile {t}: angle sum {np.degrees(angles[t].sum()):.0f}°" for t in crossed[:8]
        )
        detail = f"self-intersecting tiles {crossed.tolist()} ({sums})"
    out.append(
        Check(
            "tiles simple",
            ok=not len(crossed),
            value=int(len(crossed)),
            tol=0,
            unit="count",
            worst=f"tile {int(crossed[0])}" if len(crossed) else None,
            detail=detail,
            group="tiles",
        )
    )
    area = geometry.signed_areas(corners)
    out.append(
        measured(
            "tiles counter-clockwise",
            float(area.min()),
            0.0,
            "mm²",
            op=">=",
            worst=worst_at("tile", -area),
            group="tiles",
            detail=f"clockwise or flat tiles: {np.flatnonzero(area <= 0).tolist()[:20]}",
        )
    )
    out.append(
        overlap_check(corners, tol, "deployed", id="deployed.no-overlaps")
    )  # hinged tiles touch only
    edges = geometry.edge_lengths(corners)
    out.append(
        measured(
            "tiles min edge",
            float(edges.min()),
            MIN_EDGE_REL * tol.tile_size,
            "mm",
            op=">=",
            worst=worst_at("tile", -edges.min(axis=1)),
            group="tiles",
        )
    )
    inner = np.minimum(angles, geometry.TWO_PI - angles)  # distance from a flat or folded corner
    out.append(
        measured(
            "tiles min angle",
            float(inner.min()),
            MIN_ANGLE_RAD,
            "rad",
            op=">=",
            worst=worst_at("tile", -inner.min(axis=1)),
            group="tiles",
        )
    )
    return out


def topology_checks(pattern: Pattern) -> list[Check]:
    """Counts (topology in docs/algorithm.md#verifier-checks): one hole per independent cycle of the tile graph,
    every hinge a corner of one or two holes (or as many hole-less hinges as the kind's lattice has)."""
    count = topology_count(pattern)
    return [
        Check(
            "topology",
            ok=count.bad == 0,
            value=count.bad,
            tol=0,
            unit="count",
            group="tiles",
            worst=f"hinge {int(count.orphan[0])}" if len(count.orphan) else None,
            detail=count.detail,
        )
    ]


def verify_pattern(
    pattern: Pattern,
    tol_mm: float | None = None,
    tol_rad: float = 1e-6,
    *,
    rigid: bool | None = None,
    path_steps: int = DEFAULT_PATH_STEPS,
    shape_tol: str | tuple = "2%",
) -> Report:
    """Verify that ``pattern`` closes into both compact states.

    ``tol_mm`` None uses the relative tier (docs/algorithm.md#tolerance-tiers: 1e-9 of the mean
    tile edge for exported data, 1e-5 for optimiser output). ``rigid`` overrides
    whether rigid deployability is claimed (default: :func:`rigid_claimed`);
    when claimed, the rigid path is sampled at ``path_steps`` + 1 angles. ``shape_tol``: the largest
    Hausdorff distance of an outline to its stored target (:func:`target_checks`).
    """
    tol = tolerances(pattern, tol_mm, tol_rad)
    claimed = rigid_claimed(pattern) if rigid is None else bool(rigid)
    rep = Report(
        subject=pattern.name or "(unnamed pattern)",
        kind="pattern",
        meta={
            "tol_mm": tol.length,
            "tol_rad": tol.angle,
            "tile_size_mm": tol.tile_size,
            "tier": tol.tier,
            "tolerance": tol.describe(),
            "tiles": pattern.n_tiles,
            "holes": pattern.topology.n_holes,
            "rigid_claimed": claimed,
        },
    )
    for chk in topology_checks(pattern) + tile_checks(pattern, tol):
        rep.add(chk)
    states: dict[int, np.ndarray] = {}
    for s in STATES:
        c = contract(pattern, s)
        Y = pattern.contracted.get(s, c.corners)
        states[s] = Y
        for chk in closed_state_checks(pattern, Y, s, tol, closure=c.hole_closure):
            rep.add(chk)
        if s in pattern.contracted:
            d = geometry.aligned_distance(c.corners, Y)
            rep.add(
                measured(
                    f"state {s}: stored state matches computed",
                    d,
                    tol.length * np.sqrt(pattern.n_tiles),
                    "mm",
                    group=f"state {s}",
                    detail="after one proper rigid alignment",
                )
            )
    for chk in residual_checks(pattern, tol, claimed):
        rep.add(chk)
    if claimed:
        for chk in rigid_path_checks(pattern, states[1], states[2], tol, path_steps):
            rep.add(chk)
    for chk in target_checks(pattern, states, shape_tol):
        rep.add(chk)
    from .outlines import contracted_outline_checks
    from .seam import seam_checks

    for chk in contracted_outline_checks(pattern, states, tol) + seam_checks(pattern, states, tol):
        rep.add(chk)
    return rep
