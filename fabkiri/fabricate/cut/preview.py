"""PNG preview of the sheets (Pillow, ``pngcanvas.py``): each sheet cropped to its parts.

A preview is for a person: each sheet is cropped to what is cut and engraved
on it (plus a small border), sheets side by side, at a resolution where the
smallest label is ``LABEL_PX`` pixels tall (within ``max_px``), with a
millimetre scale bar and the sheet number. The laser files are untouched.
"""

from __future__ import annotations

import numpy as np

from ...exchange.drawing import COLORS, LAYERS, SheetDrawing

GAP_MM = 20.0
BORDER_MM = 4.0
LABEL_PX = 14.0  # the smallest label's height in pixels, when max_px allows
DRAWN = ("ENGRAVE", "SCORE", "CUT")  # NOTES (frame, caption) are not parts


def content_box(sheet: SheetDrawing) -> np.ndarray:
    """``[x0, y0, x1, y1]`` of the cut, scored and engraved linework (the whole sheet if empty)."""
    pts = [p for name in DRAWN for p, _ in sheet.layers[name]]
    if not pts:
        return np.array([0.0, 0.0, sheet.width, sheet.height])
    a = np.concatenate(pts)
    return np.r_[a.min(0) - BORDER_MM, a.max(0) + BORDER_MM]


def _bar_length(span_mm: float) -> float:
    """A round scale-bar length about a fifth of the span."""
    target = span_mm / 5
    for v in (1, 2, 5, 10, 20, 50, 100, 200, 500, 1000):
        if v >= target:
            return float(v)
    return 1000.0


def png_bytes(
    sheets: list[SheetDrawing],
    colors: str = "default",
    px_per_mm: float | None = None,
    max_px: int = 4000,
    label_mm: float | None = None,
) -> bytes:
    """The preview. ``px_per_mm`` fixed, or chosen so a ``label_mm`` label is LABEL_PX tall (at least 2)."""
    from ..pngcanvas import DPI, Canvas, rgb

    boxes = [content_box(s) for s in sheets]
    widths = [b[2] - b[0] for b in boxes]
    bar_band = 14.0  # mm below the parts for the scale bar and sheet number
    total_w = sum(widths) + GAP_MM * (len(sheets) - 1)
    total_h = max(b[3] - b[1] for b in boxes) + bar_band
    want = (
        px_per_mm if px_per_mm is not None else max(2.0, LABEL_PX / label_mm if label_mm else 4.0)
    )
    scale = min(want, max_px / max(total_w, total_h))
    cv = Canvas(total_w * scale, total_h * scale)
    ax = cv.axes((0, 0, 1, 1), (0, total_w), (-bar_band, total_h - bar_band))
    lw = max(0.4, 0.12 * scale * 72 / DPI)  # about a 0.12 mm kerf, never thinner than 0.4 pt
    x0 = 0.0
    font = max(6.0, min(24.0, 4.0 * scale * 72 / DPI))
    for s, b, w in zip(sheets, boxes, widths):
        shift = np.array([x0 - b[0], -b[1]])
        for name in LAYERS:
            if name not in DRAWN:
                continue
            segs = [
                (np.vstack([p, p[:1]]) if closed else p) + shift for p, closed in s.layers[name]
            ]
            ax.lines(segs, rgb(COLORS[colors][name][0]), lw)
        if len(sheets) > 1:
            ax.text(x0 + w / 2, -bar_band * 0.55, f"sheet {s.index}", font)
        x0 += w + GAP_MM
    L = _bar_length(total_w)
    ax.lines(
        [np.array([[BORDER_MM, -bar_band * 0.45], [BORDER_MM + L, -bar_band * 0.45]])],
        rgb("k"),
        2.5,
    )
    for x in (BORDER_MM, BORDER_MM + L):
        ax.lines([np.array([[x, -bar_band * 0.65], [x, -bar_band * 0.25]])], rgb("k"), 1.2)
    ax.text(BORDER_MM + L + 2.0, -bar_band * 0.45, f"{L:g} mm", font, anchor="lm")
    return cv.png()
