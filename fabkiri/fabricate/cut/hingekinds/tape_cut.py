"""Cutting tape hinges (:mod:`.tape`): corners a solver left apart by less than the tolerance
snapped to one node, the noded linework drawn, and its faces read back."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np
import shapely

from .. import hinges as hg
from .cutting import Cutting

if TYPE_CHECKING:
    from ....exchange.drawing import SheetDrawing
    from ....pattern.model import Pattern
    from ..materials import Material
    from . import HingeKind
    from .cutting import SheetCut, SheetRead


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
    # corners a solver left apart by less than the tolerance are one node of the linework
    eps = 0.5 * mat.tolerance_mm
    corners = hg.snap_corners(corners, eps, hg.closure_pairs(pattern, state))
    corners = hg.snap_corners(hg.snap_to_edges(corners, eps), eps, hg.closure_pairs(pattern, state))
    return Cutting(corners, corners, shapely.polygons(corners), label_margin=0.5 + mat.kerf_mm / 2)


def draw(kind: HingeKind, sd: SheetDrawing, sheet: SheetCut, cutting: Cutting) -> list[dict]:
    rings, lines = hg.tape_linework(sheet.corners[sheet.tiles])
    for p in lines:
        sd.add("CUT", p, False)
    for p in rings:
        sd.add("CUT", p, True)
    return []


def recover(kind: HingeKind, sheet: SheetRead) -> tuple[np.ndarray, np.ndarray]:
    # the faces of the noded linework, less the reference square
    sq = sheet.square
    lines = [
        shapely.LineString(np.vstack([p, p[:1]]) if c else p)
        for p, c in sheet.cut
        if not (c and sq is not None and p.shape == sq.shape and np.allclose(p, sq, atol=1e-9))
    ]
    noded = shapely.union_all(lines) if lines else shapely.GeometryCollection()
    pieces = (
        shapely.get_parts(shapely.polygonize(shapely.get_parts(noded))) if lines else np.array([])
    )
    return pieces, np.array([])
