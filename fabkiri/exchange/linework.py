"""Polylines read from cut files, in millimetres with y up: the readers' common currency.

:class:`Linework` is what the verifier reads from a DXF or SVG (one list entry per polyline, with
its layer and colour); :class:`Polylines` keeps many polylines flat in numpy arrays for the
writer's read-back of large sheets.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import numpy.typing as npt

MM_PER_PX = 25.4 / 96.0
SNAP_MM = 1e-4  # endpoints closer than this are one node of the linework
JOIN_MM = 2e-3  # cut ends closer than this meet (rounding to 1 µm moves a point by 0.7 µm; a 10 µm bridge is not cut)
NON_CUT_LAYERS = {"NOTES", "ENGRAVE", "SCORE"}


@dataclass
class Linework:
    """Polylines (mm, y up) read from one cut file, and whether each is closed."""

    path: Path
    polylines: list[np.ndarray] = field(default_factory=list)
    closed: list[bool] = field(default_factory=list)
    layer_found: bool = True  # a CUT layer/group existed
    layers: list[str] = field(
        default_factory=list
    )  # per polyline: its layer or group name ("" if none)
    colours: list[str] = field(default_factory=list)  # per polyline: its stroke colour ("" if none)
    unread: list[str] = field(default_factory=list)  # what the file holds that is no polyline here

    def add(self, pts: np.ndarray, closed: bool, layer: str = "CUT", colour: str = "") -> None:
        pts = np.asarray(pts, dtype=float).reshape(-1, 2)
        if (
            len(pts) >= 3
            and abs(pts[0, 0] - pts[-1, 0]) <= 1e-9
            and abs(pts[0, 1] - pts[-1, 1]) <= 1e-9
        ):
            pts, closed = pts[:-1], True
        if len(pts) >= 2:
            self.polylines.append(pts)
            self.closed.append(bool(closed) and len(pts) >= 3)
            self.layers.append(str(layer))
            self.colours.append(str(colour))

    def subset(self, keep: Iterable[int]) -> Linework:
        keep = list(keep)
        return Linework(
            self.path,
            [self.polylines[i] for i in keep],
            [self.closed[i] for i in keep],
            self.layer_found,
            [self.layers[i] for i in keep],
            [self.colours[i] for i in keep],
            self.unread
            + [
                f"{self.layers[i]}-layer curve"
                for i in sorted(set(range(len(self.layers))) - set(keep))
            ],
        )

    def cut_classes(self) -> list[Linework]:
        """The candidate cut linework: the CUT layer if there is one, else every colour class outside the
        annotation layers (one candidate per colour: a colour-only file keeps its layers as colours)."""
        if self.layer_found or not self.polylines:
            return [self]
        rest = [i for i, name in enumerate(self.layers) if name.upper() not in NON_CUT_LAYERS]
        colours = sorted({self.colours[i] for i in rest})
        if len(colours) <= 1:
            return [self.subset(rest)]
        return [self.subset([i for i in rest if self.colours[i] == c]) for c in colours]


class Polylines(Sequence[tuple[np.ndarray, bool]]):
    """``(points, closed)`` pairs kept flat (points ``(P, 2)``, counts, closed flags); items made on demand."""

    def __init__(self, pts: npt.ArrayLike, counts: npt.ArrayLike, closed: npt.ArrayLike):
        self.pts = np.asarray(pts, dtype=float).reshape(-1, 2)
        self.counts = np.asarray(counts, dtype=np.int64)
        self.closed = np.asarray(closed, dtype=bool)
        self._items: list | None = None

    @classmethod
    def of(cls, items: Sequence[tuple[np.ndarray, bool]]) -> Polylines:
        return cls(*flat_polylines(items))

    def _list(self) -> list:
        if self._items is None:
            parts = np.split(self.pts, np.cumsum(self.counts)[:-1]) if len(self.counts) else []
            self._items = list(zip(parts, self.closed.tolist()))
        return self._items

    def __len__(self) -> int:
        return len(self.counts)

    def __getitem__(self, i):
        return self._list()[i]

    def __iter__(self):
        return iter(self._list())


def flat_polylines(
    polylines: Sequence[tuple[np.ndarray, bool]],
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(points (P, 2), counts, closed)`` of a list of ``(points, closed)``."""
    if isinstance(polylines, Polylines):
        return polylines.pts, polylines.counts, polylines.closed
    if not polylines:
        return np.zeros((0, 2)), np.zeros(0, dtype=np.int64), np.zeros(0, dtype=bool)
    return (
        np.concatenate([np.asarray(p, dtype=float).reshape(-1, 2) for p, _ in polylines]),
        np.array([len(p) for p, _ in polylines]),
        np.array([bool(c) for _, c in polylines]),
    )


def _segments(polylines: Sequence[tuple[np.ndarray, bool]]) -> np.ndarray:
    """Every segment ``(S, 2, 2)`` of the polylines (closing segments included), polyline by polyline."""
    pts, n, closed = flat_polylines(polylines)
    if len(pts) == 0:
        return np.zeros((0, 2, 2))
    end = np.cumsum(n)
    first = end - n
    nxt = np.arange(1, len(pts) + 1)
    nxt[end - 1] = np.where(closed, first, -1)  # the last point goes back to the first, or nowhere
    keep = nxt >= 0
    return np.stack([pts[keep], pts[nxt[keep]]], 1)


def duplicate_segments(polylines: Sequence[tuple[np.ndarray, bool]], decimals: int = 6) -> int:
    """Segments that appear twice (either direction) — they would be cut twice."""
    s = np.round(_segments(polylines), decimals)
    if len(s) == 0:
        return 0
    a, b = s[:, 0], s[:, 1]
    swap = (a[:, 0] > b[:, 0]) | ((a[:, 0] == b[:, 0]) & (a[:, 1] > b[:, 1]))
    lo = np.where(swap[:, None], b, a)
    hi = np.where(swap[:, None], a, b)
    key = np.concatenate([lo, hi], 1)
    return int(len(key) - len(np.unique(key, axis=0)))
