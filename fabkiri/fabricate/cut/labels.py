"""What the laser engraves beside the cut: tile IDs, corner labels, tape marks, and the notes.

Labels are fitted inside their tile (or, for corner labels, inside the triangle
the tape covers) and left out, and counted, where no legible text fits.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import shapely

from ...exchange.drawing import SheetDrawing
from ...verify.physical import tape_mark_chords, tape_reach
from . import layout as lay
from .hingekinds import HingeKind
from .text import supported, text_strokes, text_strokes_many, text_width

MIN_LABEL_MM = 0.8  # below this a label is not legible; it is left out (and counted)
ID_FRAC = 0.45  # tile IDs fit the tile scaled by this about its centroid


def _incentre(tri: np.ndarray) -> np.ndarray:
    """Incentres of triangles ``(N, 3, 2)``: the anchor that leaves the most room for a label."""
    a = np.linalg.norm(tri[:, 1] - tri[:, 2], axis=1)
    b = np.linalg.norm(tri[:, 2] - tri[:, 0], axis=1)
    c = np.linalg.norm(tri[:, 0] - tri[:, 1], axis=1)
    w = np.stack([a, b, c], 1)
    return (w[:, :, None] * tri).sum(1) / np.maximum(w.sum(1), 1e-300)[:, None]


def _add_labels(
    sheets: list[SheetDrawing],
    sheet_of_label: np.ndarray,
    tile_of_label: np.ndarray,
    pts: np.ndarray,
    counts: np.ndarray,
    label: np.ndarray,
) -> None:
    """Open strokes (``pts`` split by ``counts``, stroke j of label ``label[j]``) onto their labels'
    sheets, in order, grouped by tile."""
    if not len(counts):
        return
    on = np.asarray(sheet_of_label)[label]
    tile = np.asarray(tile_of_label)[label]
    point_sheet = np.repeat(on, counts)
    for s in np.unique(on).tolist():
        sheets[s].add_many("ENGRAVE", pts[point_sheet == s], counts[on == s], tile[on == s])


def _fit_labels(Q, tiles, texts, anchors, region, hmax, margin):
    """Fit text boxes; re-check containment in the tile with shapely (non-convex tiles) and shrink."""
    ratio = np.array([text_width(t) for t in texts])
    h = lay.fit_heights(anchors, ratio, np.full(len(texts), hmax), region, margin)
    h = np.where(h >= MIN_LABEL_MM, h, 0.0)
    if len(h):
        tile_polys = shapely.buffer(shapely.polygons(Q[tiles]), -margin + 1e-9, join_style="mitre")
        for _ in range(8):
            w = ratio * h
            boxes = shapely.box(
                anchors[:, 0] - w / 2,
                anchors[:, 1] - h / 2,
                anchors[:, 0] + w / 2,
                anchors[:, 1] + h / 2,
            )
            bad = (h > 0) & ~shapely.covers(tile_polys, boxes)
            if not bad.any():
                break
            h[bad] *= 0.7
            h[bad & (h < MIN_LABEL_MM)] = 0.0
    return h


def engrave_labels(
    sheets: list[SheetDrawing],
    Q: np.ndarray,
    sheet_of: np.ndarray,
    hinge_tiles: np.ndarray,
    hinge_corner: np.ndarray,
    letters: list[str],
    kind: HingeKind,
    label_h: float,
    label_margin: float,
) -> tuple[int, np.ndarray, np.ndarray | None]:
    """Engrave tile IDs, the corner labels the hinge kind asks for and its tape marks
    onto the sheets (``Q``: every tile's label region as placed). Returns how many
    labels were left out, the tile IDs' heights and the corner labels' heights."""
    T = len(Q)
    tidx = np.arange(T)
    cent = shapely.get_coordinates(shapely.centroid(shapely.polygons(Q)))
    id_region = cent[:, None, :] + ID_FRAC * (Q - cent[:, None, :])
    ids = [str(t) for t in range(T)]
    hid = _fit_labels(Q, tidx, ids, cent, id_region, label_h, 0.0)
    omitted = int((hid <= 0).sum())
    _add_labels(sheets, sheet_of, tidx, *text_strokes_many(ids, hid, cent))
    A, B = hinge_tiles.T
    cA, cB = hinge_corner.T
    cross = sheet_of[A] != sheet_of[B]
    hc_all = None
    ct, ck, c_text = _corner_labels(A, B, cA, cB, letters, cross, kind)
    if len(ct):
        q = Q[ct, ck]
        n = Q.shape[1]  # the tile arity
        q1, q0 = Q[ct, (ck + 1) % n], Q[ct, (ck - 1) % n]
        # corner labels fit the triangle the tape covers (its chord is the tape mark's)
        tri = np.stack(
            [
                q,
                q + tape_reach(q, q1)[:, None] * (q1 - q),
                q + tape_reach(q, q0)[:, None] * (q0 - q),
            ],
            1,
        )
        anchor = _incentre(tri)
        hc = _fit_labels(Q, ct, c_text, anchor, tri, 0.6 * label_h, label_margin)
        hc_all = hc
        omitted += int((hc <= 0).sum())
        _add_labels(sheets, sheet_of[ct], ct, *text_strokes_many(c_text, hc, anchor))
    if kind.tape_marks and len(A):
        # tile A's corner carries the face letter, tile B's a chord where the tape ends: one
        # mark per tile keeps the stroke count (DXF entities) down on large patterns
        same = ~cross
        mt, mk = B[same], cB[same]
        marks = tape_mark_chords(Q, mt, mk, label_margin)
        ok = np.isfinite(marks).all(axis=(1, 2))
        _add_labels(
            sheets,
            sheet_of[mt[ok]],
            mt[ok],
            marks[ok].reshape(-1, 2),
            np.full(int(ok.sum()), 2),
            np.arange(int(ok.sum())),
        )
    for sd in sheets:  # each tile's engraving together: one SVG path per tile, less head travel
        sd.sort_by_group("ENGRAVE")
    return omitted, hid, hc_all


def _corner_labels(
    A: np.ndarray,
    B: np.ndarray,
    cA: np.ndarray,
    cB: np.ndarray,
    letters: list[str],
    cross: np.ndarray,
    kind: HingeKind,
) -> tuple[np.ndarray, np.ndarray, list[str]]:
    """Tiles, corners and texts of the corner labels: both corners of a hinge whose
    tiles lie on different sheets (or of every hinge, for kinds that ask), else the
    face letter on tile A's corner (for kinds that ask)."""
    c_tiles: list[int] = []
    c_k: list[int] = []
    c_text: list[str] = []
    for h in range(len(A)):
        f = letters[h]
        if kind.both_corner_labels or cross[h]:
            c_tiles += [A[h], B[h]]
            c_k += [cA[h], cB[h]]
            c_text += [f"{B[h]}{f}", f"{A[h]}{f}"]
        elif kind.face_letter_corners:
            c_tiles.append(A[h])
            c_k.append(cA[h])
            c_text.append(f)
    return np.array(c_tiles, dtype=int), np.array(c_k, dtype=int), c_text


def add_notes(
    sheets: list[SheetDrawing], caption: Callable[[int, int], str], margin: float
) -> None:
    """The NOTES layer of every sheet: its frame and a caption in the bottom margin
    (never cut; left out where the margin is too thin for legible text).
    ``caption(index, count)`` is the caption of sheet ``index`` of ``count``."""
    for sd in sheets:
        sd.add(
            "NOTES",
            np.array([[0, 0], [sd.width, 0], [sd.width, sd.height], [0, sd.height]], float),
            True,
        )
        cap = caption(sd.index, len(sheets))
        cap = "".join(ch if supported(ch) else "-" for ch in cap)
        ch_h = min(2.5, 0.5 * margin)
        if ch_h >= 1.0:
            w = ch_h * text_width(cap)
            if w > sd.width - 2 * margin:
                ch_h *= (sd.width - 2 * margin) / w
                w = ch_h * text_width(cap)
            if ch_h > 0.3:
                for p in text_strokes(cap, ch_h, (margin + w / 2, margin / 2)):
                    sd.add("NOTES", p, False)
