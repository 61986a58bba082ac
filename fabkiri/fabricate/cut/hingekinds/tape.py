"""Tape hinges: the tiles cut in place, side by side, and joined with tape after cutting.

Coincident tile corners are one node of the linework, so the laser cuts each
shared edge once; tile A's corner of a hinge carries its face letter and tile
B's a chord where the tape ends.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np
import shapely

from .. import hinges as hg
from . import Cutting, HingeKind, register

if TYPE_CHECKING:
    from ....exchange.drawing import SheetDrawing
    from ....pattern.model import Pattern
    from ..materials import Material
    from . import SheetCut, SheetRead


class Tape(HingeKind):
    name = "tape"
    face_letter_corners = True
    tape_marks = True

    def prepare(
        self,
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
        corners = hg.snap_corners(
            hg.snap_to_edges(corners, eps), eps, hg.closure_pairs(pattern, state)
        )
        return Cutting(
            corners, corners, shapely.polygons(corners), label_margin=0.5 + mat.kerf_mm / 2
        )

    def draw(self, sd: SheetDrawing, sheet: SheetCut, cutting: Cutting) -> list[dict]:
        rings, lines = hg.tape_linework(sheet.corners[sheet.tiles])
        for p in lines:
            sd.add("CUT", p, False)
        for p in rings:
            sd.add("CUT", p, True)
        return []

    def recover(self, sheet: SheetRead) -> tuple[np.ndarray, np.ndarray]:
        # the faces of the noded linework, less the reference square
        sq = sheet.square
        lines = [
            shapely.LineString(np.vstack([p, p[:1]]) if c else p)
            for p, c in sheet.cut
            if not (c and sq is not None and p.shape == sq.shape and np.allclose(p, sq, atol=1e-9))
        ]
        noded = shapely.union_all(lines) if lines else shapely.GeometryCollection()
        pieces = (
            shapely.get_parts(shapely.polygonize(shapely.get_parts(noded)))
            if lines
            else np.array([])
        )
        return pieces, np.array([])


TAPE = register(Tape())
