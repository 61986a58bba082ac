"""Cutting ligament hinges (:mod:`.ligament`): the tiles shrunk, the strips planned and drawn with
them as one outline, the strips' free spans declared for the verifier, and the pieces read back."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np
import shapely

from ....errors import FabricationError
from ....exchange.drawing import snap
from ....pattern import thinness as fab
from ... import fabricability as fb
from .. import hinges as hg
from .cutting import Cutting

if TYPE_CHECKING:
    from ....exchange.drawing import SheetDrawing
    from ....pattern.model import Pattern
    from ..materials import Material
    from . import HingeKind
    from .cutting import SheetCut, SheetRead

FEATURE_PAD_MM = (
    1e-4  # ligament spans listed in the manifest are this much wider than the free span
)
NOTCH_AREA_MM2 = (
    1e-6  # a notch the kerf toolpath fills counts from this area (float noise is far smaller)
)


def recover(kind: HingeKind, sheet: SheetRead) -> tuple[np.ndarray, np.ndarray]:
    # the verifier's reader, imported here: a cut without its read-back does not load it
    from ....verify.quads import UNDO_MITRE

    # the material (a ring inside another ring is a hole of that piece) less the declared strips
    rings = sheet.polys[~sheet.is_ref]
    ii, jj = shapely.STRtree(rings).query(rings, predicate="within")
    inside = (np.bincount(ii[ii != jj], minlength=len(rings)) % 2) == 1
    material = shapely.difference(
        shapely.union_all(rings[~inside]), shapely.union_all(rings[inside])
    )
    material = shapely.buffer(
        material, -sheet.manifest["kerf_offset_mm"], join_style="mitre", mitre_limit=UNDO_MITRE
    )
    feats = [
        shapely.Polygon(f["polygon"])
        for f in sheet.manifest["hinge_features"]
        if f["sheet"] == sheet.sheet
    ]
    cores = shapely.difference(material, shapely.union_all(feats)) if feats else material
    pieces = shapely.get_parts(cores)
    pieces = pieces[shapely.area(pieces) > 1e-6]
    holes = np.array(
        [shapely.Polygon(r) for g in shapely.get_parts(material) for r in g.interiors],
        dtype=object,
    )
    return pieces, holes


def prepare(
    kind: HingeKind,
    pattern: Pattern,
    corners: np.ndarray,
    tile_polys: np.ndarray,
    mat: Material,
    *,
    state: int,
    scale: float,
    options: Any,
) -> Cutting:
    shrink = mat.gap_mm / 2
    try:
        regions = hg.shrink_tiles(corners, shrink)
    except FabricationError as exc:
        lost = np.flatnonzero((fab.shrunk_edges(corners, shrink) <= fab.EDGE_EPS_MM).any(-1))
        raise fb.lost_edge(corners, mat, kind.name, scale, int(lost[0])) from exc
    lig = hg.ligament_design(
        pattern,
        regions,
        gap=mat.gap_mm,
        width_max=mat.ligament_width_mm,
        min_web=mat.min_web_mm,
        kerf=mat.kerf_mm,
        strain_limit=mat.strain_limit,
        turn_rad=np.radians(options.turn_deg),
        width=options.ligament_width,
    )
    strips = hg.ligament_strips(lig.apex, lig.width_mm, embed=max(0.5, lig.width_mm))
    return Cutting(
        corners,
        regions,
        shapely.polygons(corners),
        label_margin=0.5,
        offset=mat.kerf_offset_mm,
        shrink=shrink,
        ligament=lig,
        strips=strips,
        warnings=list(lig.warnings),
    )


def draw(kind: HingeKind, sd: SheetDrawing, sheet: SheetCut, cutting: Cutting) -> list[dict]:
    s, on, place = sheet.index, sheet.tiles, sheet.place
    assert cutting.strips is not None  # prepare() always plans the strips
    A, B = sheet.hinge_tiles.T
    same = np.flatnonzero((sheet.sheet_of[A] == s) & (sheet.sheet_of[B] == s))
    shift = place.shift[on[0]]
    small = shapely.polygons(sheet.regions[on])
    moved_strips = shapely.transform(cutting.strips[same], lambda c, d=shift: c + d)
    material = shapely.union_all(np.concatenate([small, moved_strips]), grid_size=hg.GRID)
    outline = hg.kerf_outset(material, cutting.offset)
    ext, inner = hg.rings_of(outline)
    for p in inner:
        sd.add("CUT", p, True)
    for p in ext:
        sd.add("CUT", p, True)
    return _spans(_left_by_laser(material, outline, cutting.offset), small, moved_strips, same, s)


def _left_by_laser(
    material: shapely.Geometry, outline: shapely.Geometry, offset: float
) -> shapely.Geometry:
    """The material the laser leaves: ``material`` and the notches narrower than the kerf that its
    offset toolpath fills (a strip meeting a small tile's edge at a shallow angle leaves one), so the
    declared spans cover them. ``material`` itself where the toolpath fills nothing (any quad sheet)."""
    from ....verify.quads import UNDO_MITRE

    if not offset:
        return material
    back = shapely.buffer(outline, -offset, join_style="mitre", mitre_limit=UNDO_MITRE)
    filled = shapely.get_parts(shapely.difference(back, material, grid_size=hg.GRID))
    if not (shapely.area(filled) > NOTCH_AREA_MM2).any():
        return material
    return shapely.union_all(
        np.concatenate([[material], filled[shapely.area(filled) > NOTCH_AREA_MM2]]),
        grid_size=hg.GRID,
    )


def _spans(
    material: shapely.Geometry,
    small: np.ndarray,
    moved_strips: np.ndarray,
    same: np.ndarray,
    s: int,
) -> list[dict]:
    """The free spans: material not in any tile, from the same snapped geometry as
    the cut, one manifest entry per polygon of each hinge's span."""
    tiles_here = shapely.union_all(small, grid_size=hg.GRID)
    tile_tree = shapely.STRtree(small)
    free = shapely.get_parts(shapely.difference(material, tiles_here, grid_size=hg.GRID))
    free = free[shapely.area(free) > 0]
    # a span may touch two strips (then it is listed for both)
    part_i, strip_i = shapely.STRtree(moved_strips).query(free, predicate="intersects")
    order = np.lexsort((part_i, strip_i))
    part_i, strip_i = part_i[order], strip_i[order]
    owners, first, counts = np.unique(strip_i, return_index=True, return_counts=True)
    spans = np.array(
        [
            free[part_i[f]]
            if c == 1
            else shapely.union_all(free[part_i[f : f + c]], grid_size=hg.GRID)
            for f, c in zip(first, counts)
        ],
        dtype=object,
    )
    # padded so rounding never leaves a hairline of material along the strip joining the
    # two tiles, then clipped by the tiles so no tile loses a corner
    spans = shapely.buffer(spans, FEATURE_PAD_MM, join_style="mitre")
    si, ti = tile_tree.query(spans, predicate="intersects")
    rank = np.zeros(len(si), dtype=np.int64)
    for r in range(1, len(si)):
        rank[r] = rank[r - 1] + 1 if si[r] == si[r - 1] else 0
    for r in range(int(rank.max(initial=-1)) + 1):
        sel = rank == r
        spans[si[sel]] = shapely.difference(spans[si[sel]], small[ti[sel]], grid_size=hg.GRID)
    spans = shapely.normalize(spans)
    feats = []
    for j, geom in zip(owners, spans):
        for g in shapely.get_parts(geom):  # one entry per polygon (a span may come in parts)
            if g.geom_type == "Polygon" and not g.is_empty:
                feats.append(
                    {
                        "hinge": int(same[j]),
                        "sheet": s + 1,
                        "polygon": snap(np.asarray(g.exterior.coords)[:-1]).tolist(),
                    }
                )
    return feats
