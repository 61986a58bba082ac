"""What a hinge kind's cutting makes and reads: a closed state's parts (:class:`Cutting`), one sheet's
share of a cut (:class:`SheetCut`) and one written sheet as the read-back sees it (:class:`SheetRead`).

Apart from the kinds' rules (:mod:`fabkiri.fabricate.cut.hingekinds`): a design's sizing asks the rules
and never loads these.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from ..hinges import LigamentDesign
    from ..layout import Placement


@dataclass
class Cutting:
    """What a hinge kind makes of a closed state before the parts are placed (mm).

    ``corners`` are the tile corners as cut (a kind may snap them), ``regions``
    each tile's label region (its core, for shrunk tiles), ``parts`` the shapely
    polygons the layout places, ``offset`` the kerf offset of the cut outlines and
    ``shrink`` how far each tile was shrunk.
    """

    corners: np.ndarray
    regions: np.ndarray
    parts: np.ndarray
    label_margin: float
    offset: float = 0.0
    shrink: float = 0.0
    ligament: LigamentDesign | None = None
    strips: np.ndarray | None = None  # ligament strips, closed-state coordinates
    warnings: list[str] = field(default_factory=list)


@dataclass(frozen=True)
class SheetCut:
    """One sheet's share of a cut, handed to :meth:`HingeKind.draw`."""

    index: int  # 0-based sheet
    tiles: np.ndarray  # the tiles placed on it
    place: Placement
    sheet_of: np.ndarray  # (T,) sheet of every tile
    hinge_tiles: np.ndarray  # (H, 2) tiles A, B of every hinge
    corners: np.ndarray  # (T, 4, 2) every tile's corners as placed
    regions: np.ndarray  # (T, 4, 2) every tile's label region as placed


@dataclass(frozen=True)
class SheetRead:
    """One written sheet as the read-back sees it, handed to :meth:`HingeKind.recover`."""

    cut: Sequence[tuple[np.ndarray, bool]]  # the CUT polylines as read, ``(points, closed)``
    polys: np.ndarray  # a shapely polygon per closed CUT polyline
    is_ref: np.ndarray  # which closed polylines are the reference square
    square: np.ndarray | None  # the reference square's corners, if it is on this sheet
    sheet: int  # 1-based
    manifest: dict  # the cut's manifest (kerf offset, hinge features)
