"""Separate tiles: each tile cut on its own, offset by half the kerf, laid out
exploded or nested; both corners of every hinge carry the partner tile's ID and
the face letter, so the maker finds which corners join."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np
import shapely

from ....errors import InputError
from .. import hinges as hg
from . import Cutting, HingeKind, register

if TYPE_CHECKING:
    from ....exchange.drawing import SheetDrawing
    from ....pattern.model import Pattern
    from ..materials import Material
    from . import SheetCut, SheetRead


class Separate(HingeKind):
    name = "separate"
    default_layout = "exploded"
    both_corner_labels = True
    cut_apart = True

    def check_layout(self, layout: str) -> None:
        if layout == "in-place":
            raise InputError(
                "separate tiles are offset by half the kerf and would overlap in place; "
                "use --layout exploded or nested"
            )

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
        offset = mat.kerf_offset_mm
        return Cutting(
            corners, corners, hg.kerf_outset(tile_polys, offset), label_margin=0.5, offset=offset
        )

    def draw(self, sd: SheetDrawing, sheet: SheetCut, cutting: Cutting) -> list[dict]:
        for t in sheet.tiles:  # each part turned and moved as placed
            ring = np.asarray(cutting.parts[t].exterior.coords)[:-1]
            sd.add("CUT", sheet.place.apply(np.array([t]), ring[None])[0], True)
        return []

    def recover(self, sheet: SheetRead) -> tuple[np.ndarray, np.ndarray]:
        # every closed outline but the reference square, less the kerf offset
        off = sheet.manifest["kerf_offset_mm"]
        pieces = shapely.buffer(
            sheet.polys[~sheet.is_ref], -off, join_style="mitre", mitre_limit=hg.MITRE_LIMIT
        )
        return pieces, np.array([])

    def hinge_spacing(self, material: Material) -> float:
        return 0.0  # tiles cut apart: nothing on the tile between two hinges

    def coupon_variants(self, material: Material) -> tuple[str, str, list[dict[str, float]]]:
        ks = sorted(
            {round(max(0.01, material.kerf_mm * f), 3) for f in (0.5, 0.75, 1.0, 1.25, 1.5)}
        )
        return "kerf_mm", "K", [{"tile": 10.0, "kerf": k, "value": k} for k in ks]

    def assembly_steps(self, n_top: int, n_bottom: int) -> list[str]:
        return [
            "0. place each tile by its ID next to its partners: a corner label '12T' joins this corner "
            "to tile 12 on the top face (B: bottom)",
            *super().assembly_steps(n_top, n_bottom),
        ]


SEPARATE = register(Separate())
