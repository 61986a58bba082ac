"""The cut pictures' canvas (sheet preview, assembly map), drawn with Pillow.

Not matplotlib: ``cut`` writes both pictures by default, and importing matplotlib and laying out its figure
cost half of a small cut's process. The figures keep matplotlib's geometry: a figure of
so many pixels, axes boxes as fractions of it, data limits shown at one scale in x and y (centred in the
box, as ``set_aspect("equal")`` does), line widths and font sizes in points at ``DPI``. Drawn at
``SUPERSAMPLE`` times the size and reduced, so edges come out anti-aliased (1x above ``SUPERSAMPLE_MAX_PX``).
"""

from __future__ import annotations

import io
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:  # Pillow is imported where a picture is drawn
    from PIL import Image, ImageDraw

DPI = 100.0  # pixels per inch: a point is DPI / 72 pixels
SUPERSAMPLE = 2
SUPERSAMPLE_MAX_PX = 8e6  # final pixels above which a picture is drawn at its own size (memory)

Colour = tuple[int, ...]


def rgb(spec: str, alpha: float | None = None) -> Colour:
    """A matplotlib-style colour: ``#RRGGBB``, a grey level ``"0.35"`` or ``"k"``; with ``alpha``, RGBA."""
    if spec.startswith("#"):
        c = tuple(int(spec[i : i + 2], 16) for i in (1, 3, 5))
    elif spec == "k":
        c = (0, 0, 0)
    else:
        c = (round(255 * float(spec)),) * 3
    return c if alpha is None else (*c, round(255 * alpha))


class Canvas:
    """A white picture of ``width`` x ``height`` final pixels."""

    def __init__(self, width: float, height: float):
        from PIL import Image, ImageDraw

        # truncated, as matplotlib's Agg canvas sized its pictures
        self.size = (max(1, int(width)), max(1, int(height)))
        self.s = SUPERSAMPLE if self.size[0] * self.size[1] <= SUPERSAMPLE_MAX_PX else 1
        self.img: Image.Image = Image.new(
            "RGB", (self.size[0] * self.s, self.size[1] * self.s), "white"
        )
        self.draw: ImageDraw.ImageDraw = ImageDraw.Draw(self.img, "RGBA")
        self._fonts: dict[int, object] = {}

    def axes(self, box: tuple[float, float, float, float], xlim: tuple, ylim: tuple) -> Axes:
        """Axes in ``box`` = (left, bottom, width, height), fractions of the picture (y up)."""
        return Axes(self, box, xlim, ylim)

    def font(self, points: float):
        from PIL import ImageFont

        px = max(1, round(points * DPI / 72 * self.s))
        if px not in self._fonts:
            self._fonts[px] = ImageFont.load_default(px)
        return self._fonts[px]

    def width(self, points: float) -> int:
        """A line width in points as supersampled pixels (at least one)."""
        return max(1, round(points * DPI / 72 * self.s))

    def png(self) -> bytes:
        img = self.img if self.s == 1 else self.img.reduce(self.s)  # the mean of each s x s block
        buf = io.BytesIO()
        img.save(buf, format="PNG", dpi=(DPI, DPI))
        return buf.getvalue()


class Frame:
    """Data (mm, y up) to pixels (y down): ``lo``..``hi`` at one scale, centred in a box of the picture.

    The box is given by its lower-left corner ``(x0, y1)`` in pixels and its size ``(bw, bh)``.
    """

    def __init__(self, x0: float, y1: float, bw: float, bh: float, lo, hi):
        self.lo = np.asarray(lo, dtype=float)
        self.span = span = np.maximum(np.asarray(hi, dtype=float) - self.lo, 1e-9)
        self.scale = min(bw / span[0], bh / span[1])
        self.pad = 0.5 * (np.array([bw, bh]) - span * self.scale)
        self.origin = np.array([x0 + self.pad[0], y1 - self.pad[1]])

    def px(self, pts) -> np.ndarray:
        q = (np.asarray(pts, dtype=float) - self.lo) * self.scale
        return self.origin + q * np.array([1.0, -1.0])


class Axes(Frame):
    """A frame in a box of the canvas given as fractions of the picture, with matplotlib-like drawing."""

    def __init__(self, cv: Canvas, box: tuple[float, float, float, float], xlim, ylim):
        self.cv = cv
        W, H = cv.size[0] * cv.s, cv.size[1] * cv.s
        left, bottom, w, h = box
        x0, y1 = left * W, (1 - bottom) * H  # the box's lower-left corner in pixels (y down)
        bw, bh = w * W, h * H
        super().__init__(x0, y1, bw, bh, (xlim[0], ylim[0]), (xlim[1], ylim[1]))
        # the drawn area's top edge and horizontal centre (pixels)
        self.top = y1 - bh + self.pad[1]
        self.xmid = self.origin[0] + 0.5 * self.span[0] * self.scale

    def lines(self, segs, colour: Colour, points: float) -> None:
        """Open polylines (each ``(n, 2)``)."""
        w = self.cv.width(points)
        for s in segs:
            self.cv.draw.line([tuple(p) for p in self.px(s).tolist()], fill=colour, width=w)

    def polygons(self, polys, fill: Colour, edge: Colour, points: float) -> None:
        """Closed polygons, filled (RGBA fills blend over what is drawn) and outlined."""
        w = self.cv.width(points)
        for poly in polys:
            xy = [tuple(p) for p in self.px(poly).tolist()]
            self.cv.draw.polygon(xy, fill=fill)
            self.cv.draw.line([*xy, xy[0]], fill=edge, width=w)

    def dots(self, pts, colour: Colour, diameter_points: float) -> None:
        r = 0.5 * diameter_points * DPI / 72 * self.cv.s
        for x, y in self.px(np.reshape(pts, (-1, 2))).tolist():
            self.cv.draw.ellipse((x - r, y - r, x + r, y + r), fill=colour)

    def text(self, x: float, y: float, s: str, points: float, anchor: str = "mm") -> None:
        """``s`` at data ``(x, y)``; ``anchor`` as Pillow's (``mm`` centred, ``lm`` left-middle)."""
        (px, py) = self.px([x, y]).tolist()
        self.cv.draw.text((px, py), s, fill=(0, 0, 0), font=self.cv.font(points), anchor=anchor)

    def title(self, s: str, points: float) -> None:
        """``s`` centred above the drawn area, 6 points clear of it (matplotlib's title pad)."""
        y = self.top - 6 * DPI / 72 * self.cv.s
        self.cv.draw.text((self.xmid, y), s, fill=(0, 0, 0), font=self.cv.font(points), anchor="md")
