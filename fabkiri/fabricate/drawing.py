"""The in-memory drawing of one sheet: polylines per layer, in millimetres, y up.

Writers (DXF, SVG, PNG) only translate this structure, so they all show the
same geometry. Coordinates are snapped to a 1e-6 mm grid once, here, so the
DXF and the SVG carry the same numbers.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

LAYERS = ("ENGRAVE", "SCORE", "CUT", "NOTES")  # also the cut order: engrave, score, cut; notes never cut
DECIMALS = 6

# layer -> (SVG stroke colour, DXF ACI colour)
COLORS = {
    "default": {"CUT": ("#FF0000", 1), "SCORE": ("#0000FF", 5), "ENGRAVE": ("#000000", 7), "NOTES": ("#00FF00", 3)},
    "boxes": {"CUT": ("#000000", 7), "SCORE": ("#0000FF", 5), "ENGRAVE": ("#00FF00", 3), "NOTES": ("#FF0000", 1)},
    "ponoko": {"CUT": ("#0000FF", 5), "SCORE": ("#FF0000", 1), "ENGRAVE": ("#000000", 7), "NOTES": ("#00FF00", 3)},
}


def snap(points: np.ndarray) -> np.ndarray:
    """Round to the output grid (and turn -0.0 into 0.0 so text output is stable)."""
    return np.round(np.asarray(points, dtype=float), DECIMALS) + 0.0


@dataclass
class SheetDrawing:
    """One sheet: ``layers[name]`` is a list of ``(points (n, 2), closed)`` polylines.

    A closed polyline does not repeat its first point.
    """

    index: int  # 1-based
    width: float
    height: float
    layers: dict[str, list[tuple[np.ndarray, bool]]] = field(default_factory=lambda: {k: [] for k in LAYERS})

    def add(self, layer: str, points: np.ndarray, closed: bool) -> None:
        pts = snap(points)
        if closed and len(pts) > 1 and np.array_equal(pts[0], pts[-1]):
            pts = pts[:-1]
        if len(pts) < 2:
            return
        self.layers[layer].append((pts, closed))

    def length(self, layer: str) -> float:
        total = 0.0
        for pts, closed in self.layers[layer]:
            p = np.vstack([pts, pts[:1]]) if closed else pts
            total += float(np.linalg.norm(np.diff(p, axis=0), axis=1).sum())
        return total

    def count(self, layer: str) -> int:
        return len(self.layers[layer])
