"""Numbers on a map that never print over one another: each keeps its place if it can, else shrinks, else
moves to the nearest free spot with a leader line back to what it names.

Boxes are the text's cell box (``text_width`` × height, in mm) grown by a margin; a label is accepted only
where its box meets no box already placed, so no two labels' boxes intersect by construction (labels are
placed in the order given: the map's join order, so low numbers keep their places).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .cut.text import text_strokes_many, text_width

SHRINK = (1.0, 0.8, 0.65)  # heights tried in place before a label moves (at the last one)
MARGIN = (
    0.35,
    0.15,
)  # of the height, left/right and above/below: neighbours never read as one number
DIRECTIONS = 16  # candidate spots per ring around the anchor
MAX_RINGS = 400


@dataclass(frozen=True)
class LabelLayout:
    """Where each label is drawn: ``centres`` (n, 2) mm, ``heights`` (n,) mm, ``moved`` (n,) whether it
    left its anchor (then a leader line joins ``anchors`` to it)."""

    anchors: np.ndarray
    centres: np.ndarray
    heights: np.ndarray
    moved: np.ndarray


def _box(c: np.ndarray, w: float, h: float) -> np.ndarray:
    mx, my = MARGIN[0] * h, MARGIN[1] * h
    return np.array(
        [c[0] - 0.5 * w * h - mx, c[1] - 0.5 * h - my, c[0] + 0.5 * w * h + mx, c[1] + 0.5 * h + my]
    )


def _free(box: np.ndarray, placed: np.ndarray) -> bool:
    if not len(placed):
        return True
    return bool(
        (
            (box[0] >= placed[:, 2])
            | (box[2] <= placed[:, 0])
            | (box[1] >= placed[:, 3])
            | (box[3] <= placed[:, 1])
        ).all()
    )


def place_labels(anchors: np.ndarray, texts: list[str], height: float) -> LabelLayout:
    """Place ``texts`` (height ``height`` mm) at or near ``anchors`` (n, 2) with no two boxes meeting."""
    anchors = np.asarray(anchors, dtype=float).reshape(-1, 2)
    n = len(texts)
    centres, heights = anchors.copy(), np.full(n, float(height))
    moved = np.zeros(n, dtype=bool)
    placed = np.zeros((n, 4))
    angles = np.linspace(0.0, 2 * np.pi, DIRECTIONS, endpoint=False)
    ring = np.column_stack([np.cos(angles), np.sin(angles)])
    for i, text in enumerate(texts):
        w = text_width(text)
        for s in SHRINK:
            box = _box(anchors[i], w, height * s)
            if _free(box, placed[:i]):
                heights[i] = height * s
                break
        else:
            h = height * SHRINK[-1]
            heights[i], moved[i] = h, True
            step = 0.5 * h * (1 + 2 * MARGIN[1])
            box = None
            for k in range(1, MAX_RINGS + 1):
                for c in anchors[i] + k * step * ring:
                    b = _box(c, w, h)
                    if _free(b, placed[:i]):
                        centres[i], box = c, b
                        break
                if box is not None:
                    break
            if box is None:  # nowhere near: beyond every placed label (always free)
                centres[i] = [placed[:i, 2].max() + w * h, anchors[i][1]]
                box = _box(centres[i], w, h)
        placed[i] = box
    return LabelLayout(anchors=anchors, centres=centres, heights=heights, moved=moved)


def stroke_boxes(texts: list[str], layout: LabelLayout) -> np.ndarray:
    """The bounding box (n, 4) of each label's drawn strokes: what a reader sees, not what was planned."""
    xy, counts, label = text_strokes_many(texts, layout.heights, layout.centres)
    out = np.full((len(texts), 4), np.nan)
    owner = np.repeat(label, counts)
    for k in range(len(texts)):
        p = xy[owner == k]
        if len(p):
            out[k] = [*p.min(0), *p.max(0)]
    return out


def overlapping_pairs(boxes: np.ndarray, grow: float = 0.0) -> list[tuple[int, int]]:
    """Pairs of boxes (n, 4) whose interiors intersect once each is grown by ``grow`` mm on every side."""
    b = boxes[~np.isnan(boxes).any(1)] + np.array([-grow, -grow, grow, grow])
    idx = np.flatnonzero(~np.isnan(boxes).any(1))
    hit = (
        (b[:, None, 0] < b[None, :, 2])
        & (b[None, :, 0] < b[:, None, 2])
        & (b[:, None, 1] < b[None, :, 3])
        & (b[None, :, 1] < b[:, None, 3])
    )
    i, j = np.nonzero(np.triu(hit, 1))
    return [(int(idx[a]), int(idx[c])) for a, c in zip(i, j)]
