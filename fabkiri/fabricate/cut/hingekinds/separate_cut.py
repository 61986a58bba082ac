"""Cutting separate tiles (:mod:`.separate`): every tile's outline offset by half the kerf, drawn
turned and moved as placed, and read back less that offset."""

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
    offset = mat.kerf_offset_mm
    return Cutting(
        corners, corners, hg.kerf_outset(tile_polys, offset), label_margin=0.5, offset=offset
    )


def draw(kind: HingeKind, sd: SheetDrawing, sheet: SheetCut, cutting: Cutting) -> list[dict]:
    for t in sheet.tiles:  # each part turned and moved as placed
        ring = np.asarray(cutting.parts[t].exterior.coords)[:-1]
        sd.add("CUT", sheet.place.apply(np.array([t]), ring[None])[0], True)
    return []


def recover(kind: HingeKind, sheet: SheetRead) -> tuple[np.ndarray, np.ndarray]:
    # every closed outline but the reference square, less the kerf offset
    off = sheet.manifest["kerf_offset_mm"]
    pieces = shapely.buffer(
        sheet.polys[~sheet.is_ref], -off, join_style="mitre", mitre_limit=hg.MITRE_LIMIT
    )
    return pieces, np.array([])
