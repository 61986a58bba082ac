"""SVG writer (svgwrite): millimetre-sized, 1 user unit = 1 mm, one group per layer.

The drawing is y-up; SVG is y-down, so every point is written as
``(x, H - y)``. Strokes are 0.1 mm (a kerf: visible in viewers), fills none, so laser software
reads every element as a vector path. No ``<text>``: labels are strokes.
"""

from __future__ import annotations

import numpy as np
import svgwrite

from .drawing import COLORS, DECIMALS, LAYERS, SheetDrawing

STROKE_MM = 0.1  # visible when rendered (0.01 exports from Inkscape as all white); colour, not width, says cut
INKSCAPE_NS = "http://www.inkscape.org/namespaces/inkscape"


def _num(v: float) -> str:
    s = f"{v:.{DECIMALS}f}".rstrip("0").rstrip(".")
    return "0" if s in ("-0", "") else s


def path_data(points: np.ndarray, closed: bool, height: float) -> str:
    """``M x,y L x,y ... [Z]`` with y flipped."""
    ys = np.round(height - points[:, 1], DECIMALS) + 0.0
    xy = [f"{_num(x)},{_num(y)}" for x, y in zip(points[:, 0].tolist(), ys.tolist())]
    return "M" + " L".join(xy) + (" Z" if closed else "")


def _nums(values: np.ndarray) -> list[str]:
    """:func:`_num` of many values."""
    return [
        "0" if t in ("-0", "") else t
        for t in (
            f.rstrip("0").rstrip(".") for f in map(f"{{:.{DECIMALS}f}}".format, values.tolist())
        )
    ]


def layer_paths(polylines, groups, height: float) -> list[str]:
    """The ``d`` of every path of a layer: :func:`path_data` of each polyline, the consecutive
    polylines of one group (>= 0) joined as subpaths of one path."""
    if not polylines:
        return []
    pts = np.concatenate([p for p, _ in polylines])
    xs = _nums(pts[:, 0])
    ys = _nums(np.round(height - pts[:, 1], DECIMALS) + 0.0)
    xy = [f"{x},{y}" for x, y in zip(xs, ys)]
    out: list[str] = []
    start = 0
    prev = None
    for (p, closed), g in zip(polylines, groups):
        d = "M" + " L".join(xy[start : start + len(p)]) + (" Z" if closed else "")
        start += len(p)
        if g >= 0 and g == prev:
            out[-1] += " " + d
        else:
            out.append(d)
        prev = g
    return out


def svg_bytes(sheet: SheetDrawing, colors: str = "default", stroke_mm: float = STROKE_MM) -> bytes:
    W, H = sheet.width, sheet.height
    dwg = svgwrite.Drawing(size=(f"{_num(W)}mm", f"{_num(H)}mm"), profile="full", debug=False)
    dwg.attribs["viewBox"] = f"0 0 {_num(W)} {_num(H)}"
    dwg.attribs["xmlns:inkscape"] = INKSCAPE_NS
    for name in LAYERS:
        stroke = COLORS[colors][name][0]
        g = dwg.g(id=name, fill="none", stroke=stroke, stroke_width=_num(stroke_mm))
        g.attribs["stroke-linejoin"] = "round"
        g.attribs["inkscape:groupmode"] = "layer"
        g.attribs["inkscape:label"] = name
        for d in layer_paths(sheet.layers[name], sheet.groups[name], H):
            g.add(dwg.path(d=d))
        dwg.add(g)
    return ('<?xml version="1.0" encoding="utf-8" ?>\n' + dwg.tostring() + "\n").encode("utf-8")
