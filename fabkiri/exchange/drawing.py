"""The in-memory drawing of one sheet: polylines per layer, in millimetres, y up.

Writers (DXF, SVG, PNG) only translate this structure, so they all show the
same geometry. Coordinates are snapped to a 1e-6 mm grid once, here, so the
DXF and the SVG carry the same numbers.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

LAYERS = (
    "ENGRAVE",
    "SCORE",
    "CUT",
    "NOTES",
)  # also the cut order: engrave, score, cut; notes never cut
DECIMALS = 6

# layer -> (SVG stroke colour, DXF ACI colour)
COLORS = {
    "default": {
        "CUT": ("#FF0000", 1),
        "SCORE": ("#0000FF", 5),
        "ENGRAVE": ("#000000", 7),
        "NOTES": ("#00FF00", 3),
    },
    "boxes": {
        "CUT": ("#000000", 7),
        "SCORE": ("#0000FF", 5),
        "ENGRAVE": ("#00FF00", 3),
        "NOTES": ("#FF0000", 1),
    },
    "ponoko": {
        "CUT": ("#0000FF", 5),
        "SCORE": ("#FF0000", 1),
        "ENGRAVE": ("#000000", 7),
        "NOTES": ("#00FF00", 3),
    },
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
    layers: dict[str, list[tuple[np.ndarray, bool]]] = field(
        default_factory=lambda: {k: [] for k in LAYERS}
    )
    # per polyline, the tile whose label/mark it draws (-1: none); the SVG writes the consecutive
    # strokes of one tile as one <path>
    groups: dict[str, list[int]] = field(default_factory=lambda: {k: [] for k in LAYERS})

    def add(self, layer: str, points: np.ndarray, closed: bool, group: int = -1) -> None:
        pts = snap(points)
        if closed and len(pts) > 1 and np.array_equal(pts[0], pts[-1]):
            pts = pts[:-1]
        if len(pts) < 2:
            return
        self.layers[layer].append((pts, closed))
        self.groups[layer].append(int(group))

    def add_many(
        self, layer: str, points: np.ndarray, counts: np.ndarray, groups: np.ndarray | None = None
    ) -> None:
        """Open polylines ``points[sum(counts[:j]):][:counts[j]]``, in order: :meth:`add` for each, at once."""
        pts = snap(points)
        g = np.full(len(counts), -1) if groups is None else np.asarray(groups)
        keep = [
            (p, int(k))
            for p, k in zip(np.split(pts, np.cumsum(counts)[:-1]), g.tolist())
            if len(p) >= 2
        ]
        self.layers[layer].extend((p, False) for p, _ in keep)
        self.groups[layer].extend(k for _, k in keep)

    def __repr__(self) -> str:  # the polylines are arrays: counted, not printed
        drawn = ", ".join(f"{k} {len(v)}" for k, v in self.layers.items() if v)
        return (
            f"SheetDrawing({self.index}, {self.width:g} x {self.height:g} mm: {drawn or 'empty'})"
        )

    def sort_by_group(self, layer: str) -> None:
        """Order the layer's polylines by group (stable): each tile's strokes together, tiles in order."""
        order = np.argsort(np.asarray(self.groups[layer], dtype=np.int64), kind="stable").tolist()
        self.layers[layer] = [self.layers[layer][i] for i in order]
        self.groups[layer] = [self.groups[layer][i] for i in order]

    def length(self, layer: str) -> float:
        polylines = self.layers[layer]
        if not polylines:
            return 0.0
        # all segments at once: each polyline's points, then its closing segment where closed
        pts = np.concatenate([p for p, _ in polylines])
        n = np.array([len(p) for p, _ in polylines])
        end = np.cumsum(n)
        last = np.zeros(len(pts), dtype=bool)
        last[end - 1] = True
        d = np.linalg.norm(pts[1:] - pts[:-1], axis=1)[~last[:-1]].sum()
        closed = np.array([c for _, c in polylines])
        d += np.linalg.norm(pts[end - 1][closed] - pts[end - n][closed], axis=1).sum()
        return float(d)

    def count(self, layer: str) -> int:
        return len(self.layers[layer])
