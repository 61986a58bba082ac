"""A small single-stroke font: text as open polylines for the laser.

Lasers score single lines fast and need no font on the laser PC
(docs/fabrication.md#labels). Glyphs are drawn in a cell 0.6 wide and 1 tall (cap height), with
as few strokes as possible — most digits are one stroke — because every stroke
is one entity in the DXF. No stroke retraces another, so no segment is
engraved twice. Lower-case input is drawn in capitals.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

CELL_W = 0.6
ADVANCE = 0.85  # cell width + letter spacing, in units of the text height

_G: dict[str, list[list[tuple[float, float]]]] = {
    "0": [[(0, 0), (0.6, 0), (0.6, 1), (0, 1), (0, 0), (0.6, 1)]],
    "1": [[(0.05, 0.75), (0.3, 1), (0.3, 0)], [(0.05, 0), (0.55, 0)]],  # flag and foot: never an I
    "2": [[(0, 1), (0.6, 1), (0.6, 0.5), (0, 0.5), (0, 0), (0.6, 0)]],
    "3": [[(0, 1), (0.6, 1), (0.6, 0), (0, 0)], [(0.1, 0.5), (0.6, 0.5)]],
    "4": [[(0.45, 0), (0.45, 1), (0, 0.3), (0.6, 0.3)]],
    "5": [[(0.6, 1), (0, 1), (0, 0.55), (0.6, 0.55), (0.6, 0), (0, 0)]],
    "6": [[(0.6, 1), (0, 1), (0, 0), (0.6, 0), (0.6, 0.5), (0, 0.5)]],
    "7": [[(0, 1), (0.6, 1), (0.2, 0)]],
    "8": [
        [
            (0.3, 0.5),
            (0.05, 0.75),
            (0.3, 1),
            (0.55, 0.75),
            (0.3, 0.5),
            (0.6, 0.25),
            (0.3, 0),
            (0, 0.25),
            (0.3, 0.5),
        ]
    ],  # two stacked loops meeting in the middle: never a B (straight spine)
    "9": [[(0.6, 0.5), (0, 0.5), (0, 1), (0.6, 1), (0.6, 0), (0, 0)]],
    "A": [[(0, 0), (0.3, 1), (0.6, 0)], [(0.1, 0.35), (0.5, 0.35)]],
    "B": [
        [
            (0, 0.5),
            (0.5, 0.5),
            (0.6, 0.4),
            (0.6, 0.1),
            (0.5, 0),
            (0, 0),
            (0, 1),
            (0.45, 1),
            (0.55, 0.9),
            (0.55, 0.6),
            (0.45, 0.5),
        ]
    ],
    "C": [[(0.6, 1), (0, 1), (0, 0), (0.6, 0)]],
    "D": [[(0, 0), (0, 1), (0.35, 1), (0.6, 0.7), (0.6, 0.3), (0.35, 0), (0, 0)]],
    "E": [[(0.6, 1), (0, 1), (0, 0), (0.6, 0)], [(0, 0.5), (0.45, 0.5)]],
    "F": [[(0.6, 1), (0, 1), (0, 0)], [(0, 0.5), (0.45, 0.5)]],
    "G": [[(0.6, 0.8), (0.6, 1), (0, 1), (0, 0), (0.6, 0), (0.6, 0.4), (0.35, 0.4)]],
    "H": [[(0, 0), (0, 1)], [(0.6, 0), (0.6, 1)], [(0, 0.5), (0.6, 0.5)]],
    "I": [[(0.3, 0), (0.3, 1)]],
    "J": [[(0.6, 1), (0.6, 0), (0, 0), (0, 0.3)]],
    "K": [[(0, 0), (0, 1)], [(0.6, 1), (0, 0.4)], [(0.2, 0.55), (0.6, 0)]],
    "L": [[(0, 1), (0, 0), (0.6, 0)]],
    "M": [[(0, 0), (0, 1), (0.3, 0.5), (0.6, 1), (0.6, 0)]],
    "N": [[(0, 0), (0, 1), (0.6, 0), (0.6, 1)]],
    "O": [[(0, 0), (0.6, 0), (0.6, 1), (0, 1), (0, 0)]],
    "P": [[(0, 0), (0, 1), (0.6, 1), (0.6, 0.5), (0, 0.5)]],
    "Q": [[(0, 0), (0.6, 0), (0.6, 1), (0, 1), (0, 0)], [(0.35, 0.3), (0.6, 0.05)]],
    "R": [[(0, 0), (0, 1), (0.6, 1), (0.6, 0.5), (0, 0.5), (0.6, 0)]],
    "S": [
        [
            (0.6, 0.85),
            (0.45, 1),
            (0.15, 1),
            (0, 0.85),
            (0, 0.65),
            (0.6, 0.35),
            (0.6, 0.15),
            (0.45, 0),
            (0.15, 0),
            (0, 0.15),
        ]
    ],  # rounded ends and a slanted spine: never a 5
    "T": [[(0, 1), (0.6, 1)], [(0.3, 1), (0.3, 0)]],
    "U": [[(0, 1), (0, 0), (0.6, 0), (0.6, 1)]],
    "V": [[(0, 1), (0.3, 0), (0.6, 1)]],
    "W": [[(0, 1), (0.15, 0), (0.3, 0.6), (0.45, 0), (0.6, 1)]],
    "X": [[(0, 0), (0.6, 1)], [(0, 1), (0.6, 0)]],
    "Y": [[(0, 1), (0.3, 0.6), (0.6, 1)], [(0.3, 0.6), (0.3, 0)]],
    "Z": [[(0, 1), (0.6, 1), (0, 0), (0.6, 0)]],
    "-": [[(0.1, 0.5), (0.5, 0.5)]],
    ".": [[(0.25, 0), (0.35, 0), (0.35, 0.1), (0.25, 0.1), (0.25, 0)]],
    "/": [[(0, 0), (0.6, 1)]],
    ":": [[(0.3, 0.2), (0.3, 0.3)], [(0.3, 0.7), (0.3, 0.8)]],
    "=": [[(0.05, 0.35), (0.55, 0.35)], [(0.05, 0.65), (0.55, 0.65)]],
    "+": [[(0.05, 0.5), (0.55, 0.5)], [(0.3, 0.25), (0.3, 0.75)]],
    "_": [[(0, 0), (0.6, 0)]],
    " ": [],
}
GLYPHS = {k: [np.asarray(s, dtype=float) for s in v] for k, v in _G.items()}


def supported(text: str) -> bool:
    return all(ch.upper() in GLYPHS for ch in text)


def text_width(text: str) -> float:
    """Width of ``text`` at height 1 (from the left of the first cell to the right of the last)."""
    n = len(text)
    return 0.0 if n == 0 else ADVANCE * (n - 1) + CELL_W


def text_strokes(
    text: str, height: float, centre: tuple[float, float] | np.ndarray
) -> list[np.ndarray]:
    """Polylines of ``text`` at cap ``height`` mm, its box centred on ``centre``.

    Characters outside the glyph table raise ``KeyError`` naming the character.
    """
    cx, cy = float(centre[0]), float(centre[1])
    x0 = cx - 0.5 * height * text_width(text)
    y0 = cy - 0.5 * height
    out = []
    for i, ch in enumerate(text):
        glyph = GLYPHS.get(ch.upper())
        if glyph is None:
            raise KeyError(f"no glyph for {ch!r} in the single-stroke font")
        ox = x0 + i * ADVANCE * height
        for s in glyph:
            out.append(np.column_stack([ox + height * s[:, 0], y0 + height * s[:, 1]]))
    return out


_IDS: dict[str, list[int]] = {}
_UNIT: list[np.ndarray] = []
for _ch, _strokes in GLYPHS.items():
    _IDS[_ch] = list(range(len(_UNIT), len(_UNIT) + len(_strokes)))
    _UNIT.extend(_strokes)
_UNIT_N = np.array([len(s) for s in _UNIT])
_UNIT_START = np.concatenate([[0], np.cumsum(_UNIT_N)[:-1]])
_UNIT_PTS = np.concatenate(_UNIT)


def text_strokes_many(
    texts: list[str], heights: np.ndarray, centres: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The strokes of many labels at once: ``(points (P, 2), counts (S,), label (S,))``.

    Stroke ``j`` is ``points[sum(counts[:j]):][:counts[j]]`` and belongs to
    ``texts[label[j]]``; labels with a height <= 0 have none. The same numbers
    as :func:`text_strokes` label by label (the same float operations, in order).
    """
    lab: list[int] = []
    pos: list[int] = []
    sid: list[int] = []
    for k, (text, h) in enumerate(zip(texts, np.asarray(heights, dtype=float).tolist())):
        if not h > 0:
            continue
        for i, ch in enumerate(text):
            ids = _IDS.get(ch.upper())
            if ids is None:
                raise KeyError(f"no glyph for {ch!r} in the single-stroke font")
            for s in ids:
                lab.append(k)
                pos.append(i)
                sid.append(s)
    if not sid:
        return np.zeros((0, 2)), np.zeros(0, dtype=np.int64), np.zeros(0, dtype=np.int64)
    lab_a, sid_a = np.array(lab), np.array(sid)
    h = np.asarray(heights, dtype=float)[lab_a]
    c = np.asarray(centres, dtype=float)[lab_a]
    width = np.array([text_width(t) for t in texts])[lab_a]
    x0 = c[:, 0] - 0.5 * h * width
    y0 = c[:, 1] - 0.5 * h
    ox = x0 + np.array(pos, dtype=float) * ADVANCE * h
    counts = _UNIT_N[sid_a]
    rep = np.repeat(np.arange(len(sid_a)), counts)
    first = np.cumsum(counts) - counts
    unit = _UNIT_PTS[_UNIT_START[sid_a][rep] + np.arange(int(counts.sum())) - first[rep]]
    pts = np.column_stack([ox[rep] + h[rep] * unit[:, 0], y0[rep] + h[rep] * unit[:, 1]])
    return pts, counts, lab_a


def text_box(
    height: float, centre: Sequence[float] | np.ndarray, text: str
) -> tuple[float, float, float, float]:
    """(xmin, ymin, xmax, ymax) of the text's cells; every glyph stays inside."""
    w = height * text_width(text)
    return (centre[0] - w / 2, centre[1] - height / 2, centre[0] + w / 2, centre[1] + height / 2)
