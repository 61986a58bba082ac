"""How much a pattern opens: the deployed hole area, the area change and the largest tile turn.

A design that fits its outline can still barely deploy (a star whose holes are slits: its deployed state
looks like a closed one). Three figures say how much it opens, on plain geometry (no mechanics):

* **hole fraction**: the deployed holes' area over the deployed sheet's area, the region inside the
  sheet's outer boundary (its tiles and holes; the notches between boundary tips are outside the sheet).
  ``--min-opening`` of ``fabkiri design`` is a floor on this figure.
* **area ratio** per closed state: the deployed sheet's area over the area inside that closed state's
  outline (1 / (1 - hole fraction) when the closed state is compact).
* **largest tile turn** per closed state, in degrees: how far a tile rotates from the closed state to the
  deployed one, relative to the pattern's own rotation (the area-weighted circular mean of the tiles'
  turns, so a closed state stored at any placement reads the same).

For the standard rotating-squares pattern of M x N tiles of edge a at deployment angle ψ every hole is a
rhombus of angle 2ψ, so the hole fraction is (M-1)(N-1) sin 2ψ / (MN + (M-1)(N-1) sin 2ψ) and the tiles
turn by ψ from state 1 and by 90° - ψ from state 2 (``tests/design/test_opening.py``).
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, field

import numpy as np
import shapely

from . import geometry
from .model import Pattern

OPENS_LITTLE = 0.10  # below this hole fraction a design "opens little": design and info warn


@dataclass(frozen=True)
class Opening:
    """The opening figures of a pattern (areas in mm², turns in degrees; states keyed by number)."""

    sheet_area_mm2: float  # deployed: tiles and holes, inside the sheet's outer boundary
    tile_area_mm2: float
    hole_area_mm2: float
    hole_fraction: float
    closed_area_mm2: dict[int, float] = field(default_factory=dict)
    area_ratio: dict[int, float] = field(default_factory=dict)  # deployed sheet / closed outline
    turn_deg: dict[int, float] = field(default_factory=dict)  # largest tile turn from each state

    @property
    def max_turn_deg(self) -> float:
        return max(self.turn_deg.values(), default=0.0)

    @property
    def opens_little(self) -> bool:
        return self.hole_fraction < OPENS_LITTLE

    def to_dict(self) -> dict:
        d = asdict(self)
        for k in ("closed_area_mm2", "area_ratio", "turn_deg"):
            d[k] = {str(s): v for s, v in d[k].items()}
        d["max_turn_deg"] = self.max_turn_deg
        d["opens_little_below"] = OPENS_LITTLE
        return d

    @classmethod
    def from_dict(cls, d: dict) -> Opening:
        """The figures back from their :meth:`to_dict` form (a report's)."""

        def states(k: str) -> dict[int, float]:
            return {int(s): float(v) for s, v in (d.get(k) or {}).items()}

        return cls(
            sheet_area_mm2=float(d["sheet_area_mm2"]),
            tile_area_mm2=float(d["tile_area_mm2"]),
            hole_area_mm2=float(d["hole_area_mm2"]),
            hole_fraction=float(d["hole_fraction"]),
            closed_area_mm2=states("closed_area_mm2"),
            area_ratio=states("area_ratio"),
            turn_deg=states("turn_deg"),
        )

    def line(self) -> str:
        """One line for ``design`` and ``info``."""
        per = ", ".join(
            f"state {s}: area x{self.area_ratio[s]:.3f}, turn {self.turn_deg[s]:.1f}°"
            for s in sorted(self.area_ratio)
        )
        return (
            f"opening: holes {100 * self.hole_fraction:.1f} % of the deployed sheet "
            f"({self.hole_area_mm2:.4g} of {self.sheet_area_mm2:.4g} mm²)"
            + (f"; {per}" if per else "")
        )

    def warning(self) -> str | None:
        """The one-line warning of a design that opens little, or None."""
        if not self.opens_little:
            return None
        return (
            f"fabkiri: warning: the design opens little: holes are {100 * self.hole_fraction:.1f} % of "
            f"the deployed sheet (< {100 * OPENS_LITTLE:.0f} %), its deployed state looks almost closed"
        )


def hole_polygons(pattern: Pattern) -> np.ndarray:
    """The deployed holes' corners ``(H, k, 2)`` (empty ``(0, k, 2)`` without holes)."""
    hn = pattern.topology.hole_nodes
    if not len(hn):
        return np.zeros((0, 4, 2))
    return pattern.nodes[hn]


def _turn_deg(closed: np.ndarray, deployed: np.ndarray) -> float:
    """Largest tile turn from ``closed`` to ``deployed`` (both ``(T, n, 2)``) about the mean turn."""
    a = geometry.kabsch_angles(closed, deployed)
    w = np.abs(geometry.signed_areas(deployed))
    mean = np.arctan2((w * np.sin(a)).sum(), (w * np.cos(a)).sum())
    return float(np.degrees(np.abs(geometry.wrap_angle(a - mean)).max(initial=0.0)))


def _closed_area(corners: np.ndarray) -> float:
    """Area inside a closed state's outline: its tiles and any gap they enclose, pieces that meet only at
    corners summed. The union is taken on a grid of 1e-7 of the extent, which closes round-off cracks
    (a buffer out and back in, as ``closed_outline`` closes them, came back empty on a 8x8 star); where
    GEOS refuses the union (an imported pattern's closed state) without the grid, then the tiles' own area."""
    c = np.asarray(corners, float)
    pts = c.reshape(-1, 2)
    grid = 1e-7 * float((pts.max(0) - pts.min(0)).max())
    area = _coverage_area(c, grid)
    if area is not None:
        return area
    polys = shapely.make_valid(shapely.polygons(c))
    for size in (grid, 0.0):
        try:
            u = shapely.union_all(polys, grid_size=size or None)
        except shapely.errors.GEOSException:
            continue
        area = _outline_area(u)
        if area > 0:
            return area
    return float(np.abs(geometry.signed_areas(c)).sum())


def _coverage_area(c: np.ndarray, grid: float) -> float | None:
    """The outline's area by a coverage union of the quads ``c`` snapped to ``grid`` (GEOS's precision model), or
    None: tiles other than quads, or snapped tiles that are not a coverage (they overlap, or a shared
    edge's ends fell in different grid cells, also half a cell further on).

    A quad pattern's closed state meets edge to edge, end to end (its edge pairs), so once the shared
    corners round to the same grid point the tiles form a coverage and GEOS joins them along their shared
    edges, a tenth of the general union's time at 128x128 tiles, the same outline (its area within
    a few ulps). Kagome triangles also touch where the general union's snap-rounding nodes a corner onto
    an edge (1e-8 of the area apart on a 5x19 ellipse): they keep the general union."""
    if c.ndim != 3 or c.shape[1] != 4 or not grid > 0 or not np.isfinite(c).all():
        return None
    # pointwise: each corner rounded to the grid as union_all(grid_size=grid) rounds its input, nothing else;
    # where the copies of a shared corner (round-off apart) straddle a cell's edge, the tiles shifted by half a
    # cell (the area is the same) round them together
    for shift in (0.0, 0.5 * grid):
        polys = shapely.set_precision(
            shapely.polygons(c + shift if shift else c), grid, mode="pointwise"
        )
        try:
            if not (shapely.is_valid(polys).all() and shapely.coverage_is_valid(polys)):
                continue
            area = _outline_area(shapely.coverage_union_all(polys))
        except shapely.errors.GEOSException:
            continue
        return area if area > 0 else None
    return None


def _outline_area(u) -> float:
    """The area inside the exterior rings of a union's polygons."""
    return float(sum(shapely.Polygon(g.exterior).area for g in _pieces(u)))


def _pieces(u) -> list:
    """The polygons of a union (a polygon, or the polygons of a collection)."""
    if u.geom_type == "Polygon":
        return [u]
    return [g for g in getattr(u, "geoms", []) if g.geom_type == "Polygon"]


def opening(pattern: Pattern, closed: dict[int, np.ndarray] | None = None) -> Opening:
    """The opening figures of ``pattern``; ``closed`` gives closed-state corners ``(T, n, 2)`` per state
    (default: the states the pattern stores)."""
    closed = dict(pattern.contracted if closed is None else closed)
    deployed = pattern.corners()
    tiles = float(np.abs(geometry.signed_areas(deployed)).sum())
    holes_c = hole_polygons(pattern)
    holes = float(abs(geometry.signed_areas(holes_c)).sum()) if len(holes_c) else 0.0
    sheet = tiles + holes
    areas = {int(s): _closed_area(c) for s, c in sorted(closed.items())}
    return Opening(
        sheet_area_mm2=sheet,
        tile_area_mm2=tiles,
        hole_area_mm2=holes,
        hole_fraction=holes / sheet if sheet > 0 else 0.0,
        closed_area_mm2=areas,
        area_ratio={s: sheet / a for s, a in areas.items() if a > 0},
        turn_deg={int(s): _turn_deg(np.asarray(c, float), deployed) for s, c in closed.items()},
    )
