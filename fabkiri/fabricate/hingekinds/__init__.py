"""Cut hinge kinds as strategy objects, chosen by name.

A hinge kind decides what the laser cuts of a closed state: the parts placed on
the sheet, the region of each tile a label may use, the kerf offset of the cut
outlines, the cut linework of one sheet, and which corner labels and tape marks
tell the maker how the tiles join. The kinds are one module each (``tape``,
``ligament``, ``separate``), loaded on first use as trimesh loads its file-format
handlers; a new kind is one module that calls :func:`register` and one line in
:data:`_BUILTIN` (and, in :mod:`..materials`, the name in ``HINGE_KINDS``).
"""

from __future__ import annotations

import importlib
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from ...errors import InputError

if TYPE_CHECKING:
    from ...pattern.model import Pattern
    from ..drawing import SheetDrawing
    from ..hinges import LigamentDesign
    from ..layout import Placement
    from ..materials import Material


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


class HingeKind:
    """The interface every hinge kind implements (see the module docstring)."""

    name = ""
    default_layout = "in-place"
    both_corner_labels = False  # every hinge's two corners carry the partner tile's ID and face letter
    face_letter_corners = False  # tile A's corner of each same-sheet hinge carries its face letter
    tape_marks = False  # tile B's corner of each same-sheet hinge carries a chord where the tape ends

    def check_layout(self, layout: str) -> None:
        """Refuse a layout this kind cannot be cut in, with one line saying what to use."""
        if layout != "in-place":
            raise InputError(f"{self.name} hinges are cut in place; --layout {layout} is for --hinge separate")

    def prepare(self, pattern: Pattern, corners: np.ndarray, tile_polys: np.ndarray, mat: Material, *,
                state: int, scale: float, options: Any) -> Cutting:
        """The parts, label regions and offsets of the closed state ``corners`` (mm)."""
        raise NotImplementedError

    def draw(self, sd: SheetDrawing, sheet: SheetCut, cutting: Cutting) -> list[dict]:
        """Add one sheet's cut linework to ``sd``; returns the hinge features the
        manifest declares for the verifier (ligament spans)."""
        raise NotImplementedError


# built-in kinds, imported when first asked for (their modules call register())
_BUILTIN = {"tape": "fabkiri.fabricate.hingekinds.tape", "ligament": "fabkiri.fabricate.hingekinds.ligament",
            "separate": "fabkiri.fabricate.hingekinds.separate"}
_REGISTRY: dict[str, HingeKind] = {}


def register(kind: HingeKind) -> HingeKind:
    """Add a kind to the registry (a kind's module calls this when it is imported)."""
    _REGISTRY[kind.name] = kind
    return kind


def hinge_kind(name: str) -> HingeKind:
    """The registered kind of this name, or :class:`InputError` naming the known ones."""
    found = _REGISTRY.get(name)
    if found is None and name in _BUILTIN:
        importlib.import_module(_BUILTIN[name])
        found = _REGISTRY.get(name)
    if found is None:
        from ..materials import HINGE_KINDS

        raise InputError(f"hinge kind must be one of {', '.join(HINGE_KINDS)}, got {name!r}")
    return found
