"""Separate tiles: each tile cut on its own, offset by half the kerf, laid out
exploded or nested; both corners of every hinge carry the partner tile's ID and
the face letter, so the maker finds which corners join."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np

from ...errors import InputError
from .. import hinges as hg
from . import Cutting, HingeKind, register

if TYPE_CHECKING:
    from ...pattern.model import Pattern
    from ..drawing import SheetDrawing
    from ..materials import Material
    from . import SheetCut


class Separate(HingeKind):
    name = "separate"
    default_layout = "exploded"
    both_corner_labels = True

    def check_layout(self, layout: str) -> None:
        if layout == "in-place":
            raise InputError("separate tiles are offset by half the kerf and would overlap in place; "
                             "use --layout exploded or nested")

    def prepare(self, pattern: Pattern, corners: np.ndarray, tile_polys: np.ndarray, mat: Material, *,
                state: int, scale: float, options: Any) -> Cutting:
        offset = mat.kerf_offset_mm
        return Cutting(corners, corners, hg.kerf_outset(tile_polys, offset), label_margin=0.5, offset=offset)

    def draw(self, sd: SheetDrawing, sheet: SheetCut, cutting: Cutting) -> list[dict]:
        for t in sheet.tiles:  # each part turned and moved as placed
            ring = np.asarray(cutting.parts[t].exterior.coords)[:-1]
            sd.add("CUT", sheet.place.apply(np.array([t]), ring[None])[0], True)
        return []


SEPARATE = register(Separate())
