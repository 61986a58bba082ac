"""A small picture of tile sets side by side: what a notebook shows for a pattern.

Drawn with Pillow in the pattern layer (the lowest), so that a :class:`~.model.Pattern` can show
itself without importing the render or fabricate layers above it. The richer pictures (a design
over its target, a cut sheet, a print bed) are the upper layers' own.
"""

from __future__ import annotations

import io
from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from .model import Pattern

PANEL_PX = 300  # each panel's drawing area, square (final pixels)
TITLE_PX = 22
MARGIN_PX = 10
SUPERSAMPLE = 2  # drawn at twice the size and reduced: anti-aliased edges
TILE = (209, 209, 209)
EDGE = (89, 89, 89)
TEXT = (0, 0, 0)


def tiles_png(panels: Sequence[tuple[str, np.ndarray]], title: str = "") -> bytes:
    """PNG bytes of each ``(caption, tile corners (T, n, 2) in mm)`` panel, left to right, all at
    one scale (y up: a closed state looks as much smaller as it is), with ``title`` above them."""
    from PIL import Image, ImageDraw, ImageFont

    s = SUPERSAMPLE
    n = max(1, len(panels))
    head = TITLE_PX if title else 0
    pw, ph = PANEL_PX + 2 * MARGIN_PX, PANEL_PX + TITLE_PX + 2 * MARGIN_PX
    img = Image.new("RGB", (n * pw * s, (head + ph) * s), "white")
    draw = ImageDraw.Draw(img)
    font = ImageFont.load_default(12 * s)
    k_px = PANEL_PX * s / _largest_span(panels)  # one scale in x and y, each drawing centred
    if title:
        draw.text((n * pw * s / 2, head * s / 2), title, fill=TEXT, font=font, anchor="mm")
    for k, (caption, tiles) in enumerate(panels):
        left, top = k * pw * s, head * s
        draw.text(
            (left + pw * s / 2, top + TITLE_PX * s / 2), caption, fill=TEXT, font=font, anchor="mm"
        )
        corners = np.asarray(tiles, dtype=float)
        if corners.size == 0 or not np.isfinite(corners).all():
            continue
        lo, hi = corners.reshape(-1, 2).min(0), corners.reshape(-1, 2).max(0)
        centre = 0.5 * (lo + hi)
        cx, cy = left + pw * s / 2, top + (TITLE_PX + MARGIN_PX + PANEL_PX / 2) * s
        px = np.empty_like(corners)
        px[..., 0] = cx + (corners[..., 0] - centre[0]) * k_px
        px[..., 1] = cy - (corners[..., 1] - centre[1]) * k_px
        for poly in px.tolist():
            draw.polygon([tuple(p) for p in poly], fill=TILE, outline=EDGE, width=s)
    buf = io.BytesIO()
    img.reduce(s).save(buf, format="PNG")
    return buf.getvalue()


def _largest_span(panels: Sequence[tuple[str, np.ndarray]]) -> float:
    """The widest extent (mm) over every panel's tiles, in x or y."""
    spans = [1e-12]
    for _, tiles in panels:
        pts = np.asarray(tiles, dtype=float).reshape(-1, 2)
        if len(pts) and np.isfinite(pts).all():
            spans.append(float((pts.max(0) - pts.min(0)).max()))
    return max(spans)


def pattern_png(pattern: Pattern) -> bytes:
    """The deployed state and each stored closed state of ``pattern``."""
    panels = [("deployed", pattern.corners())]
    panels += [(f"closed state {s}", pattern.contracted[s]) for s in sorted(pattern.contracted)]
    return tiles_png(panels, pattern.name)
