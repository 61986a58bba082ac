"""Cut hinge kinds as strategy objects, chosen by name.

A hinge kind decides what the laser cuts of a closed state: the parts placed on
the sheet, the region of each tile a label may use, the kerf offset of the cut
outlines, the cut linework of one sheet, and which corner labels and tape marks
tell the maker how the tiles join. The kinds are one module each (``tape``,
``ligament``, ``separate``), loaded on first use as trimesh loads its file-format
handlers; a new kind is one module that calls :func:`register` and one line in
the built-in table of :data:`_KINDS` (and, in :mod:`..materials`, the name in ``HINGE_KINDS``).

A built-in kind's module holds its rules (sizing, layouts, labels, assembly steps); its cutting
(``prepare``, ``draw``, ``recover``) is a sibling module named by :attr:`HingeKind.cutter`, loaded
when a cut or a read-back first asks: a design sizes every kind for its summary and loads none of
the cut geometry. A kind may instead define the three methods itself.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

from ....errors import InputError
from ....registry import Registry

if TYPE_CHECKING:
    import numpy as np

    from ....exchange.drawing import SheetDrawing
    from ....pattern.model import Pattern
    from ..materials import Material
    from .cutting import Cutting, SheetCut, SheetRead


class HingeKind:
    """The interface every hinge kind implements (see the module docstring)."""

    name = ""
    default_layout = "in-place"
    both_corner_labels = (
        False  # every hinge's two corners carry the partner tile's ID and face letter
    )
    face_letter_corners = False  # tile A's corner of each same-sheet hinge carries its face letter
    tape_marks = (
        False  # tile B's corner of each same-sheet hinge carries a chord where the tape ends
    )
    shrinks = (
        False  # every tile is shrunk by half the gap before it is cut (a sheet joined by ligaments)
    )
    one_piece = False  # the sheet comes out as one piece joined by itself: no tape, nothing to join
    cut_apart = False  # every tile is cut on its own: a tape piece spans one corner pair, tiles are placed by ID
    cutter = ""  # the module with this kind's prepare, draw and recover (functions taking the kind first)

    def shrink(self, material: Material) -> float:
        """How far ``cut`` shrinks every tile (mm)."""
        return 0.5 * material.gap_mm if self.shrinks else 0.0

    def never(self, material: Material) -> str:
        """Why this kind cannot be cut from ``material`` at any scale ('' if it can)."""
        return ""

    def min_width(self, material: Material) -> float:
        """The thinnest tile ``design`` allows for this kind (mm): what stays of it holds a web."""
        return material.min_web_mm

    def hinge_spacing(self, material: Material) -> float:
        """How far apart two hinges of one tile must be (mm): a tape piece reaches about half a web
        along each edge from its corner."""
        return material.min_web_mm

    def coupon_variants(self, material: Material) -> tuple[str, str, list[dict[str, float]]]:
        """The material field the coupon's hinge pieces sweep, its engraved prefix, and each piece's
        settings (``tile`` size, the swept ``value``, and any ``cut`` option it overrides)."""
        sizes = [s for s in (12.0, 9.0, 7.0, 5.0, 4.0) if s > 1.2 * material.min_web_mm] or [12.0]
        return "min_web_mm", "S", [{"tile": s, "value": s} for s in sizes]

    def assembly_steps(self, n_top: int, n_bottom: int) -> list[str]:
        """The maker's steps, for ``n_top`` tape pieces on the top face and ``n_bottom`` below."""
        steps = [
            f"1. top face: lay the cut tiles as cut (engraved face up) and tape pieces 1-{n_top} in order, "
            "each across its hinge corner from the face letter to the chord"
        ]
        if n_bottom:
            steps.append(
                f"2. turn the whole piece over (left-right) and tape pieces {n_top + 1}-{n_top + n_bottom} "
                "on the bottom face the same way (the map's bottom panel is seen from above, through the "
                "sheet)"
            )
        return steps

    def recover(self, sheet: SheetRead) -> tuple[np.ndarray, np.ndarray]:
        """The read-back's pieces the laser leaves on one written sheet, and the holes in them
        (shapely polygons, mm)."""
        return self._cuts().recover(self, sheet)

    def _cuts(self) -> Any:
        """The kind's cutting module, imported at a cut's or read-back's first call (a design never
        makes one)."""
        if not self.cutter:
            raise NotImplementedError(f"hinge kind {self.name!r} names no cutter")
        return importlib.import_module(self.cutter)

    def check_layout(self, layout: str) -> None:
        """Refuse a layout this kind cannot be cut in, with one line saying what to use."""
        if layout != "in-place":
            raise InputError(
                f"{self.name} hinges are cut in place; --layout {layout} is for --hinge separate"
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
        """The parts, label regions and offsets of the closed state ``corners`` (mm)."""
        return self._cuts().prepare(
            self, pattern, corners, tile_polys, mat, state=state, scale=scale, options=options
        )

    def draw(self, sd: SheetDrawing, sheet: SheetCut, cutting: Cutting) -> list[dict]:
        """Add one sheet's cut linework to ``sd``; returns the hinge features the
        manifest declares for the verifier (ligament spans)."""
        return self._cuts().draw(self, sd, sheet, cutting)


# built-in kinds, imported when first asked for (their modules call register())
_KINDS: Registry[HingeKind] = Registry(
    {
        "tape": "fabkiri.fabricate.cut.hingekinds.tape",
        "ligament": "fabkiri.fabricate.cut.hingekinds.ligament",
        "separate": "fabkiri.fabricate.cut.hingekinds.separate",
    }
)


def register(kind: HingeKind) -> HingeKind:
    """Add a kind to the registry (a kind's module calls this when it is imported)."""
    return _KINDS.add(kind.name, kind)


def hinge_kind(name: str) -> HingeKind:
    """The registered kind of this name, or :class:`InputError` naming the known ones."""
    found = _KINDS.find(name)
    if found is None:
        from ..materials import HINGE_KINDS

        raise InputError(f"hinge kind must be one of {', '.join(HINGE_KINDS)}, got {name!r}")
    return found
