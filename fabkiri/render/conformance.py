"""Design preview: the tiles over their targets, the Hausdorff distance drawn where it is worst.

One panel for the deployed state over ``--target`` and one per closed state with an outline target
(the closed tiles placed on the target as :mod:`fabkiri.design.core.conformance` measured them). Deterministic
PNG bytes (no timestamps in the metadata).

Drawn with Pillow, not matplotlib: ``fabkiri design`` writes this picture by default, and importing
matplotlib and laying out its axes cost three times an 8x8 design's solve. The picture is
drawn at ``SUPERSAMPLE`` times its size and reduced, so edges come out anti-aliased; a scale bar stands in
for the axes.
"""

from __future__ import annotations

import io
import math
from typing import TYPE_CHECKING

import numpy as np

from ..design.core.conformance import target_polygon
from ..design.targets.lookup import target_from_dict
from ..fabricate.pngcanvas import Frame
from ..pattern.model import Pattern

if TYPE_CHECKING:  # Pillow is imported where a picture is drawn
    from PIL import ImageDraw, ImageFont

SUPERSAMPLE = 2
PANEL_PX = (560, 560)  # plot area per panel (final pixels)
TITLE_PX = 44  # two title lines above each panel
HEADER_PX = 26  # the pattern's name above the panels
MARGIN_PX = 12
FONT_PX = 12
COLOURS = {
    "tile": (209, 209, 209),
    "edge": (89, 89, 89),
    "target": (31, 119, 180),
    "tips": (255, 127, 14),
    "worst": (214, 39, 40),
    "text": (0, 0, 0),
    "legend": (120, 120, 120),
}
WIDTHS = {"edge": 0.5, "target": 2.0, "tips": 1.2, "worst": 3.0}  # final pixels


def _panels(pattern: Pattern, conformance: dict) -> list[tuple[str, str, np.ndarray, np.ndarray]]:
    """``(key, title, tiles (T, 4, 2), target polygon)`` per measured outline."""
    d = pattern.design or {}
    out = []
    if "deployed" in conformance and isinstance(d.get("target"), dict):
        out.append(
            (
                "deployed",
                "deployed",
                pattern.corners(),
                target_polygon(target_from_dict(d["target"])),
            )
        )
    for key, c in conformance.items():
        if not key.startswith("state_"):
            continue
        s = int(key.split("_")[1])
        tgt = (d.get("contracted_targets") or {}).get(str(s))
        if tgt is None or s not in pattern.contracted:
            continue
        pl = c.get("placement") or {}
        th = float(pl.get("rotation_rad", 0.0))
        R = np.array([[np.cos(th), -np.sin(th)], [np.sin(th), np.cos(th)]])
        tiles = pattern.contracted[s] @ R.T + np.asarray(pl.get("shift_mm", [0.0, 0.0]))
        out.append((key, f"closed state {s}", tiles, target_polygon(target_from_dict(tgt))))
    return out


class _Canvas(Frame):
    """One panel's frame on the supersampled image, with its pen and font."""

    def __init__(
        self,
        draw: ImageDraw.ImageDraw,
        font: ImageFont.FreeTypeFont | ImageFont.ImageFont,
        box: tuple[int, int, int, int],
        lo: np.ndarray,
        hi: np.ndarray,
    ):
        self.draw, self.font, self.box = draw, font, box
        x0, y0, x1, y1 = box
        super().__init__(x0, y1, x1 - x0, y1 - y0, lo, hi)

    def line(self, pts: np.ndarray, colour: str, width: float) -> None:
        w = max(1, round(width * SUPERSAMPLE))
        self.draw.line(
            [tuple(p) for p in self.px(pts).tolist()], fill=COLOURS[colour], width=w, joint="curve"
        )

    def dots(self, pts: np.ndarray, colour: str, radius: float) -> None:
        r = radius * SUPERSAMPLE
        for x, y in self.px(pts).tolist():
            self.draw.ellipse((x - r, y - r, x + r, y + r), fill=COLOURS[colour])

    def ring(self, centre: np.ndarray, colour: str, radius: float, width: float) -> None:
        (x, y), r = self.px(centre[None])[0], radius * SUPERSAMPLE
        self.draw.ellipse(
            (x - r, y - r, x + r, y + r), outline=COLOURS[colour], width=round(width * SUPERSAMPLE)
        )


def _tiles(cv: _Canvas, tiles: np.ndarray) -> None:
    """Grey tiles with dark edges (one polygon each; a 128x128 pattern is 16k calls)."""
    w = max(1, round(WIDTHS["edge"] * SUPERSAMPLE))
    for quad in cv.px(tiles.reshape(-1, 2)).reshape(tiles.shape).tolist():
        cv.draw.polygon(
            [tuple(p) for p in quad], fill=COLOURS["tile"], outline=COLOURS["edge"], width=w
        )


def _legend(cv: _Canvas, entries: list[tuple[str, str, str]]) -> None:
    """``(kind, colour, label)`` entries in the panel's top-right corner; kind ``line`` or ``ring``."""
    s = SUPERSAMPLE
    x1, y0 = cv.box[2] - 4 * s, cv.box[1] + 4 * s
    width = max(cv.draw.textlength(label, font=cv.font) for _, _, label in entries) + 34 * s
    step = (FONT_PX + 5) * s
    x0 = x1 - width
    cv.draw.rectangle(
        (x0, y0, x1, y0 + step * len(entries) + 4 * s),
        fill=(255, 255, 255),
        outline=COLOURS["legend"],
        width=s,
    )
    for k, (kind, colour, label) in enumerate(entries):
        y = y0 + 2 * s + step * (k + 0.5)
        if kind == "line":
            cv.draw.line(
                [(x0 + 6 * s, y), (x0 + 26 * s, y)],
                fill=COLOURS[colour],
                width=round(WIDTHS[colour] * s),
            )
        else:
            r = 6 * s
            cv.draw.ellipse(
                (x0 + 16 * s - r, y - r, x0 + 16 * s + r, y + r),
                outline=COLOURS[colour],
                width=2 * s,
            )
        cv.draw.text((x0 + 30 * s, y), label, fill=COLOURS["text"], font=cv.font, anchor="lm")


def _scale_bar(cv: _Canvas) -> None:
    """A bar of a round length (1, 2 or 5 × 10^k mm) about a fifth of the plot wide, bottom left."""
    s = SUPERSAMPLE
    want = 0.2 * (cv.box[2] - cv.box[0]) / cv.scale
    k = 10.0 ** math.floor(math.log10(want))
    mm = max(m * k for m in (1, 2, 5) if m * k <= want)
    x0, y = cv.box[0] + 6 * s, cv.box[3] - 8 * s
    x1 = x0 + mm * cv.scale
    cv.draw.rectangle(
        (x0 - 4 * s, y - (FONT_PX + 10) * s, x1 + 4 * s, y + 6 * s), fill=(255, 255, 255)
    )
    cv.draw.line([(x0, y), (x1, y)], fill=COLOURS["text"], width=2 * s)
    for x in (x0, x1):
        cv.draw.line([(x, y - 4 * s), (x, y + 4 * s)], fill=COLOURS["text"], width=s)
    cv.draw.text(
        (0.5 * (x0 + x1), y - 6 * s), f"{mm:g} mm", fill=COLOURS["text"], font=cv.font, anchor="md"
    )


def _panel(
    cv: _Canvas, pattern: Pattern, key: str, tiles: np.ndarray, poly: np.ndarray, c: dict
) -> None:
    """Tiles, target, tip polygon (deployed), worst gap, legend and scale bar of one panel."""
    _tiles(cv, tiles)
    cv.line(np.vstack([poly, poly[:1]]), "target", WIDTHS["target"])
    legend = [("line", "target", "target")]
    if key == "deployed":
        tips = pattern.nodes[_tip_order(pattern)]
        cv.line(np.vstack([tips, tips[:1]]), "tips", WIDTHS["tips"])
        cv.dots(tips, "tips", 1.5)
        legend.append(("line", "tips", "tip polygon"))
    w = c["worst"]
    a, b = np.asarray(w["at"], float), np.asarray(w["nearest"], float)
    cv.line(np.vstack([a, b]), "worst", WIDTHS["worst"])
    cv.ring(a, "worst", 7.0, 1.6)
    legend.append(("ring", "worst", f"worst: {c['hausdorff_mm']:.3g} mm"))
    _legend(cv, legend)
    _scale_bar(cv)


def conformance_png(pattern: Pattern, conformance: dict, shape: dict | None = None) -> bytes:
    """PNG of every measured outline: tiles (grey), target (blue), worst Hausdorff gap (red)."""
    from PIL import Image, ImageDraw, ImageFont

    shape = shape or {}
    s = SUPERSAMPLE
    panels = _panels(pattern, conformance)
    n = max(1, len(panels))
    pw, ph = PANEL_PX[0] + 2 * MARGIN_PX, PANEL_PX[1] + TITLE_PX + 2 * MARGIN_PX
    img = Image.new("RGB", (n * pw * s, (HEADER_PX + ph) * s), "white")
    draw = ImageDraw.Draw(img)
    font = ImageFont.load_default(FONT_PX * s)
    draw.text(
        (n * pw * s / 2, HEADER_PX * s / 2),
        pattern.name or "design",
        fill=COLOURS["text"],
        font=ImageFont.load_default((FONT_PX + 1) * s),
        anchor="mm",
    )
    for k, (key, title, tiles, poly) in enumerate(panels):
        c = conformance[key]
        j = shape.get(key) or {}
        verdict = f", {j['status']} (tol {j['tol_mm']:.3g} mm)" if j else ""
        left, top = k * pw * s, HEADER_PX * s
        draw.multiline_text(
            (left + pw * s / 2, top + TITLE_PX * s / 2),
            f"{title}: Hausdorff {c['hausdorff_mm']:.3g} mm ({100 * c['hausdorff_rel']:.2f} %)"
            f"{verdict}\n1-IoU {c['one_minus_iou']:.3g}, spacing min/mean "
            f"{c['spacing_min_mm']:.3g}/{c['spacing_mean_mm']:.3g} mm",
            fill=COLOURS["text"],
            font=font,
            anchor="mm",
            align="center",
        )
        pts = np.vstack([tiles.reshape(-1, 2), poly])
        lo, hi = pts.min(0), pts.max(0)
        pad = 0.04 * float((hi - lo).max())
        box = (
            left + MARGIN_PX * s,
            top + (TITLE_PX + MARGIN_PX) * s,
            left + (pw - MARGIN_PX) * s,
            top + (ph - MARGIN_PX) * s,
        )
        _panel(_Canvas(draw, font, box, lo - pad, hi + pad), pattern, key, tiles, poly, c)
    if not panels:
        draw.text(
            (pw * s / 2, (HEADER_PX + ph / 2) * s),
            "no target curve",
            fill=COLOURS["text"],
            font=font,
            anchor="mm",
        )
    buf = io.BytesIO()
    img.reduce(s).save(buf, format="PNG")
    return buf.getvalue()


def _tip_order(pattern: Pattern) -> np.ndarray:
    from ..pattern.conformance import boundary_tip_order

    top = pattern.topology
    return boundary_tip_order(top.tiles, top.hole_nodes, top.hole_tiles, top.free_nodes)
