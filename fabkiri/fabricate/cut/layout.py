"""Where parts go: in place, exploded or nested, on one or more sheets.

A placement gives every tile a sheet and a proper rigid motion
``x_sheet = Rot(θ) x + t`` (never a mirror: a mirrored chiral pattern would
also swap the tape faces). Sheet coordinates are millimetres with the origin
at the sheet's lower-left corner, y up, content inside the margin.
Also here: the 50 mm reference square and fitting text labels inside tiles.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import shapely

from ...errors import FabricationError
from ...pattern import geometry
from . import text as stroke_text

LAYOUTS = ("in-place", "exploded", "nested")


@dataclass
class Placement:
    """Per-tile sheet (0-based) and rigid motion; sheets count and size."""

    sheet: np.ndarray  # (T,)
    theta: np.ndarray  # (T,)
    shift: np.ndarray  # (T, 2)
    n_sheets: int
    layout: str

    def apply(self, tiles: np.ndarray, pts: np.ndarray) -> np.ndarray:
        """Move points ``(N, ..., 2)`` that belong to ``tiles`` (N,) onto their sheets."""
        th = self.theta[tiles].reshape((-1,) + (1,) * (pts.ndim - 2))
        sh = self.shift[tiles].reshape((-1,) + (1,) * (pts.ndim - 2) + (2,))
        return geometry.rotate(pts, th) + sh


def _check_fits(
    bounds: np.ndarray, inner_w: float, inner_h: float, sheet: tuple[float, float]
) -> None:
    w = bounds[:, 2] - bounds[:, 0]
    h = bounds[:, 3] - bounds[:, 1]
    bad = np.flatnonzero((w > inner_w + 1e-9) | (h > inner_h + 1e-9))
    if len(bad):
        t = int(bad[0])
        raise FabricationError(
            f"sheet {sheet[0]:g}x{sheet[1]:g} mm (inside the margin {inner_w:g}x{inner_h:g}) is smaller than "
            f"tile {t} ({w[t]:.1f}x{h[t]:.1f} mm)"
        )


def split_to_sheets(
    bounds: np.ndarray, sheet: tuple[float, float], margin: float
) -> tuple[np.ndarray, np.ndarray]:
    """Group parts (by their bounding boxes, in place) into sheet-sized groups of whole parts.

    Parts keep their relative positions inside a group. A part belongs to the
    grid cell holding its box centre; the cell is the sheet's inside less the
    largest part, so every group fits. Returns ``(group per part, shift per group)``.
    """
    inner_w, inner_h = sheet[0] - 2 * margin, sheet[1] - 2 * margin
    if inner_w <= 0 or inner_h <= 0:
        raise FabricationError(
            f"margin {margin:g} mm leaves nothing of a {sheet[0]:g}x{sheet[1]:g} mm sheet"
        )
    _check_fits(bounds, inner_w, inner_h, sheet)
    lo, hi = bounds[:, :2].min(0), bounds[:, 2:].max(0)
    if hi[0] - lo[0] <= inner_w + 1e-9 and hi[1] - lo[1] <= inner_h + 1e-9:
        return np.zeros(len(bounds), dtype=np.int64), np.array([[margin, margin] - lo])
    centre = 0.5 * (bounds[:, :2] + bounds[:, 2:])
    reach_lo = (centre - bounds[:, :2]).max(0)
    reach_hi = (bounds[:, 2:] - centre).max(0)
    cell = np.array([inner_w, inner_h]) - reach_lo - reach_hi
    if (cell <= 0).any():
        raise FabricationError(
            f"sheet {sheet[0]:g}x{sheet[1]:g} mm is too small to split the pattern into "
            "groups of whole tiles"
        )
    # distribute the grid evenly over the pattern so no sheet is nearly empty
    span = np.maximum(hi - lo - reach_lo - reach_hi, 0.0)
    n = np.maximum(np.ceil(span / cell - 1e-9), 1).astype(int)
    cell = np.maximum(span / n, 1e-9)
    cx = np.clip(((centre[:, 0] - lo[0] - reach_lo[0]) / cell[0]).astype(int), 0, n[0] - 1)
    cy = np.clip(((centre[:, 1] - lo[1] - reach_lo[1]) / cell[1]).astype(int), 0, n[1] - 1)
    key = (n[1] - 1 - cy) * n[0] + cx  # sheets numbered from the top-left, row by row
    uniq, group = np.unique(key, return_inverse=True)
    shifts = np.empty((len(uniq), 2))
    for g in range(len(uniq)):
        sel = group == g
        glo, ghi = bounds[sel, :2].min(0), bounds[sel, 2:].max(0)
        if (ghi - glo > np.array([inner_w, inner_h]) + 1e-6).any():  # cannot happen by construction
            raise FabricationError("internal: a sheet group does not fit its sheet")
        shifts[g] = margin - glo
    return group.astype(np.int64), shifts


def in_place(
    corners: np.ndarray, sheet: tuple[float, float], margin: float, extra: np.ndarray | None = None
) -> Placement:
    """Tiles where they are in the closed state, translated per sheet.

    ``extra`` (T, 4) optionally widens each tile's box (a kerf outset)."""
    T = len(corners)
    bounds = np.concatenate([corners.min(1), corners.max(1)], 1)
    if extra is not None:
        bounds = extra
    group, shifts = split_to_sheets(bounds, sheet, margin)
    return Placement(
        sheet=group, theta=np.zeros(T), shift=shifts[group], n_sheets=len(shifts), layout="in-place"
    )


def exploded(
    corners: np.ndarray,
    parts: np.ndarray,
    spacing: float,
    sheet: tuple[float, float],
    margin: float,
) -> Placement:
    """Tile centroids spread from the pattern centre (factor ≥ 1.25) until parts are ``spacing`` apart."""
    T = len(corners)
    cent = shapely.get_coordinates(shapely.centroid(shapely.polygons(corners)))
    c0 = 0.5 * (cent.min(0) + cent.max(0))
    factor = 1.25
    for _ in range(60):
        moves = (factor - 1.0) * (cent - c0)
        moved = _translate(parts, moves)
        tree = shapely.STRtree(moved)
        a, b = tree.query(moved, predicate="dwithin", distance=spacing)
        if not np.any(a < b):
            break
        factor *= 1.1
    else:
        raise FabricationError("could not spread the tiles apart for an exploded layout")
    bounds = shapely.bounds(moved)
    group, shifts = split_to_sheets(bounds, sheet, margin)
    return Placement(
        sheet=group,
        theta=np.zeros(T),
        shift=moves + shifts[group],
        n_sheets=len(shifts),
        layout="exploded",
    )


def _translate(parts: np.ndarray, moves: np.ndarray) -> np.ndarray:
    """Copies of ``parts`` moved by one vector each."""
    _, idx = shapely.get_coordinates(parts, return_index=True)
    return shapely.transform(parts, lambda c: c + moves[idx])


def nested(
    parts: np.ndarray, spacing: float, sheet: tuple[float, float], margin: float
) -> Placement:
    """Shelf packing: each part turned so its minimum rotated rectangle is upright, tallest first."""
    T = len(parts)
    inner_w, inner_h = sheet[0] - 2 * margin, sheet[1] - 2 * margin
    theta = np.zeros(T)
    for i, p in enumerate(parts):
        r = np.asarray(shapely.minimum_rotated_rectangle(p).exterior.coords)
        e = r[1] - r[0]
        a = -np.arctan2(e[1], e[0])
        # the long side horizontal packs shelves tighter
        if np.linalg.norm(r[2] - r[1]) > np.linalg.norm(e):
            a += np.pi / 2
        theta[i] = np.round(a, 12)
    coords, idx = shapely.get_coordinates(parts, return_index=True)
    rot = geometry.rotate(coords, theta[idx])
    lo = np.full((T, 2), np.inf)
    hi = np.full((T, 2), -np.inf)
    np.minimum.at(lo, idx, rot)
    np.maximum.at(hi, idx, rot)
    size = hi - lo
    bounds = np.concatenate([lo, hi], 1)
    _check_fits(bounds, inner_w, inner_h, sheet)
    order = np.lexsort((np.arange(T), -np.round(size[:, 1], 6)))
    sheet_of = np.zeros(T, dtype=np.int64)
    shift = np.zeros((T, 2))
    s, x, y, shelf_h = 0, 0.0, 0.0, 0.0
    for i in order:
        w, h = size[i]
        if x > 0 and x + w > inner_w + 1e-9:  # next shelf
            x, y, shelf_h = 0.0, y + shelf_h + spacing, 0.0
        if y + h > inner_h + 1e-9:  # next sheet
            s, x, y, shelf_h = s + 1, 0.0, 0.0, 0.0
        sheet_of[i] = s
        shift[i] = np.array([margin + x, margin + y]) - lo[i]
        x += w + spacing
        shelf_h = max(shelf_h, h)
    return Placement(sheet=sheet_of, theta=theta, shift=shift, n_sheets=s + 1, layout="nested")


def place_reference(
    content: Sequence[np.ndarray | None],
    size: float,
    sheet: tuple[float, float],
    margin: float,
    gap: float,
) -> tuple[int, np.ndarray]:
    """Where the reference square goes: beside or above a sheet's content, else on a new sheet.

    ``content`` holds each sheet's bounding box ``[xmin, ymin, xmax, ymax]``.
    Returns ``(sheet index, lower-left corner)``; the index may equal
    ``len(content)`` (a new sheet).
    """
    W, H = sheet
    if size + 2 * margin > min(W, H):
        raise FabricationError(
            f"the {size:g} mm reference square does not fit a {W:g}x{H:g} mm sheet "
            "(use --reference 0 to leave it out)"
        )
    for k, box in enumerate(content):
        if box is None:
            return k, np.array([margin, margin])
        x = box[2] + gap
        if x + size <= W - margin and margin + size <= H - margin:
            return k, np.array([x, margin])
        y = box[3] + gap
        if y + size <= H - margin and margin + size <= W - margin:
            return k, np.array([margin, y])
    return len(content), np.array([margin, margin])


def fit_heights(
    anchor: np.ndarray,
    ratio: np.ndarray,
    hmax: np.ndarray,
    region: np.ndarray,
    margin: np.ndarray | float,
) -> np.ndarray:
    """Largest text height ≤ ``hmax`` whose box (width = ratio·h) centred on ``anchor`` fits ``region``.

    ``region`` is ``(N, k, 2)`` convex CCW polygons; the box keeps ``margin``
    from every edge. Solved in closed form from the half-planes of the edges;
    a non-positive result means the label does not fit at all.
    """
    v = region
    e = np.roll(v, -1, axis=1) - v
    n = np.stack([-e[..., 1], e[..., 0]], -1)
    n = n / np.maximum(np.linalg.norm(n, axis=-1, keepdims=True), 1e-300)
    slack = (
        geometry.dot2(n, anchor[:, None, :] - v)
        - np.broadcast_to(np.asarray(margin, float), (len(v),))[:, None]
    )
    h = np.asarray(hmax, dtype=float).copy()
    for sx in (-0.5, 0.5):
        for sy in (-0.5, 0.5):
            c = np.stack([sx * ratio, np.full_like(ratio, sy)], -1)  # (N, 2)
            nc = geometry.dot2(n, c[:, None, :])
            lim = np.where(
                nc < 0, slack / np.where(nc < 0, -nc, 1.0), np.where(slack < 0, -1.0, np.inf)
            )
            h = np.minimum(h, lim.min(axis=1))
    return h


def label_strokes(
    texts: list[str], heights: np.ndarray, anchors: np.ndarray
) -> list[list[np.ndarray]]:
    """Stroke polylines of every label (empty where the height is not positive)."""
    return [
        stroke_text.text_strokes(t, float(h), a) if h > 0 else []
        for t, h, a in zip(texts, heights, anchors)
    ]
