"""Compactness of a closed state: no overlaps, union area = sum of tile areas, no interior gaps, one outline."""

from __future__ import annotations

import numpy as np
import shapely

from ..pattern import geometry
from . import geom
from .report import Check, measured
from .tolerances import Tolerances, largest


def state_check_id(state: int | str, what: str) -> str:
    """The stable :attr:`Check.id` of a closed-state check, e.g. ``state1.loop-closure``."""
    return f"state{state}.{what}"


def compactness_checks(
    Y: np.ndarray,
    tol: Tolerances,
    g: str,
    blame: dict[int, int] | None = None,
    state: int | str | None = None,
) -> list[Check]:
    """No overlaps, union area = sum of tile areas, no interior gaps, one outline.

    ``blame`` maps tiles to the self-intersecting tile they are (or are hinged
    to), so overlaps caused by a crossed tile are named as such. Given a
    ``state``, the checks carry its stable ids (``state1.no-overlaps``, ...).
    """
    ids = {
        w: "" if state is None else state_check_id(state, w)
        for w in ("no-overlaps", "union-area", "no-interior-gaps", "one-outline")
    }
    depths, order, pair = _depths(Y, tol)
    union = geom.tiles_union(Y, max(tol.length, 1e-12 * tol.tile_size), coverage=not len(order))
    return [
        _overlap_check(depths, order, pair, blame, tol, g, ids["no-overlaps"]),
        _union_area_check(Y, union, tol, g, pair if len(order) else None, ids["union-area"]),
        _interior_gap_check(union, tol, g, ids["no-interior-gaps"]),
        _one_outline_check(union, tol, g, ids["one-outline"]),
    ]


def overlap_check(Y: np.ndarray, tol: Tolerances, g: str, id: str = "") -> Check:
    """``{g}: no overlaps`` alone, for a state that is not compact (the deployed one, whose holes are open)."""
    depths, order, pair = _depths(Y, tol)
    return _overlap_check(depths, order, pair, None, tol, g, id)


def _depths(Y: np.ndarray, tol: Tolerances) -> tuple[tuple, np.ndarray, str | None]:
    """Every candidate pair's overlap depth, the pairs over the tolerance (deepest first), the deepest pair."""
    i, j, inter = geom.overlap_depths(Y)
    bad = np.flatnonzero(inter > tol.length)
    order = bad[np.argsort(-inter[bad])]
    k = int(np.argmax(inter)) if len(inter) else None
    return (i, j, inter), order, f"tiles {i[k]}/{j[k]}" if k is not None else None


def _overlap_check(
    depths: tuple,
    order: np.ndarray,
    pair: str | None,
    blame: dict[int, int] | None,
    tol: Tolerances,
    g: str,
    id: str,
) -> Check:
    """The deepest overlap; pairs over the tolerance listed (``order``: deepest first) with their cause."""
    i, j, inter = depths
    listed = ", ".join(f"tiles {i[k]}/{j[k]}: {inter[k]:.3g} mm" for k in order[:10])
    if len(order) > 10:
        listed += f", … ({len(order)} pairs)"
    cause = ""
    if len(order) and blame:
        culprits = [blame.get(int(i[m]), blame.get(int(j[m]))) for m in order]
        found = [c for c in culprits if c is not None]
        if len(found) == len(culprits):
            cause = f"; all caused by self-intersecting tile(s) {sorted(set(found))}"
        else:
            cause = f"; {len(found)} of {len(order)} caused by self-intersecting tiles"
    return measured(
        f"{g}: no overlaps",
        largest(inter),
        tol.length,
        "mm",
        worst=pair,
        group=g,
        detail=(
            f"overlapping pairs (penetration depth): {listed}{cause}"
            if len(order)
            else "largest penetration depth between any two tiles"
        ),
        id=id,
    )


def _union_area_check(
    Y: np.ndarray, union: shapely.Geometry, tol: Tolerances, g: str, pair: str | None, id: str
) -> Check:
    """Union area = sum of tile areas, within a strip of the length tolerance along every edge."""
    polys, _ = geom.tile_polygons(Y)
    areas = shapely.area(polys)
    total = float(areas.sum())
    deficit = abs(total - float(union.area))
    # a strip of the length tolerance along every tile edge, counted once
    half_perimeter = 0.5 * float(geometry.edge_lengths(Y).sum())
    return measured(
        f"{g}: union area = sum of tile areas",
        deficit,
        max(tol.length * half_perimeter, 1e-9 * total),
        "mm²",
        worst=pair,
        group=g,
        detail=f"sum {total:.6g} mm², union {float(union.area):.6g} mm²",
        id=id,
    )


def _interior_gap_check(union: shapely.Geometry, tol: Tolerances, g: str, id: str) -> Check:
    """The widest gap enclosed by the tiles, as an equivalent width 2|area|/perimeter."""
    gaps = [(2 * g.area / max(g.length, 1e-300), g.area, g) for g in enclosed_gaps(union)]
    big = [x for x in gaps if x[0] > tol.length]
    worst_gap = max(gaps, key=lambda x: x[0]) if gaps else None
    where = None
    if worst_gap is not None:
        c = worst_gap[2].representative_point()
        where = f"at ({c.x:.4g}, {c.y:.4g}) mm"
    return measured(
        f"{g}: no interior gaps",
        worst_gap[0] if worst_gap else 0.0,
        tol.length,
        "mm",
        worst=where,
        group=g,
        detail=(
            f"{len(big)} enclosed gaps wider than the tolerance (largest {worst_gap[1]:.3g} mm²)"
            if big and worst_gap
            else "equivalent width 2|area|/perimeter of enclosed gaps"
        ),
        id=id,
    )


def _one_outline_check(union: shapely.Geometry, tol: Tolerances, g: str, id: str) -> Check:
    """One outline: components after closing cracks narrower than the tolerance."""
    eps = max(tol.length, 1e-12 * tol.tile_size)
    closed = union.buffer(eps, join_style="mitre").buffer(-eps, join_style="mitre")
    n_parts = len(getattr(closed, "geoms", [closed])) if not closed.is_empty else 0
    return Check(
        f"{g}: one outline",
        ok=n_parts == 1,
        value=n_parts,
        tol=1,
        unit="count",
        group=g,
        op="==",
        detail="" if n_parts == 1 else f"the tiles form {n_parts} separate pieces",
        id=id,
    )


def enclosed_gaps(union: shapely.Geometry) -> list[shapely.Polygon]:
    """The uncovered regions enclosed by a tile union, as polygons.

    A hole ring of the union may enclose islands of tiles (a crack of rounding
    width around a block of tiles, as T-junctions of parallelogram holes
    leave): the gap is the ring minus the tiles inside it, not the ring.
    """
    parts = list(getattr(union, "geoms", [union]))
    rings = [shapely.Polygon(r) for part in parts for r in part.interiors]
    if not rings:
        return []
    if len(parts) > 1:  # islands exist: take them out of the rings they sit in
        rings = shapely.get_parts(shapely.difference(np.array(rings, dtype=object), union)).tolist()
    return [g for g in rings if not g.is_empty and g.area > 0]
