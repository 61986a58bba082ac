"""Pockets of a target: where its outline turns inward (reflex corners, a crescent's hollow).

A pocket is a piece of the target's convex hull outside the target. The deployed outline of a quad lattice
has to run into every pocket and out again along one of its four sides; a design that misses the shape
with its outline over most of a pocket cut across it (an L's inner corner, a crescent's hollow), which no
initial guess of the solver avoided there (``fabkiri design`` says so instead of advice already tried).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import shapely

from ..core.conformance import target_polygon
from .lookup import Target

# pockets below this share of the hull are ignored (a star's notches are above it)
MIN_POCKET_AREA = 0.01
COVERED = 0.5  # an outline covering this share of a pocket ran across it
ON_POCKET = 1e-6  # of the hull's size: a point this near a pocket lies in it or on its sides


@dataclass(frozen=True)
class Pocket:
    """A piece of the hull outside the target: its area (mm²), depth (mm: the farthest its target
    boundary lies from the hull's edge) and deepest target point."""

    area_mm2: float
    depth_mm: float
    deepest: tuple[float, float]
    polygon: shapely.Polygon

    def to_dict(self) -> dict:
        return {"area_mm2": self.area_mm2, "depth_mm": self.depth_mm, "deepest": list(self.deepest)}


def pockets(target: Target) -> list[Pocket]:
    """The target's pockets of at least ``MIN_POCKET_AREA`` of its hull, deepest first."""
    poly = shapely.Polygon(target_polygon(target))
    if not poly.is_valid:
        poly = shapely.make_valid(poly)
    hull = poly.convex_hull
    rest = hull.difference(poly)
    edge = hull.exterior
    out = []
    for piece in getattr(rest, "geoms", [rest]):
        if piece.geom_type != "Polygon" or piece.area < MIN_POCKET_AREA * hull.area:
            continue
        pts = np.asarray(piece.exterior.coords)
        d = shapely.distance(shapely.points(pts), edge)
        k = int(np.argmax(d))
        out.append(
            Pocket(float(piece.area), float(d[k]), (float(pts[k, 0]), float(pts[k, 1])), piece)
        )
    return sorted(out, key=lambda p: -p.depth_mm)


def pocket_covered(
    target: Target, outline: np.ndarray, worst: tuple[float, float] | None = None
) -> tuple[Pocket, float] | None:
    """The deepest pocket the closed ``outline`` polygon (the deployed tips, mm) covers at least
    ``COVERED`` of, or whose sides carry the miss's ``worst`` point (mm), with the share it covers: the
    outline ran across it, or partly into it and out short of its sides. None: no such pocket."""
    poly = shapely.Polygon(np.asarray(outline, float))
    if not poly.is_valid:
        poly = shapely.make_valid(poly)
    at = None if worst is None else shapely.Point(worst)
    for k in pockets(target):
        share = float(k.polygon.intersection(poly).area / k.polygon.area)
        near = at is not None and k.polygon.distance(at) <= ON_POCKET * np.sqrt(
            k.polygon.convex_hull.area
        )
        if share >= COVERED or near:
            return k, share
    return None
