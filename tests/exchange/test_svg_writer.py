"""The SVG writer gives the bytes svgwrite wrote (issue #36: it no longer imports svgwrite)."""

from __future__ import annotations

import numpy as np
import pytest
import svgwrite
from fabkiri.exchange.drawing import COLORS, LAYERS, SheetDrawing
from fabkiri.exchange.svg import _num, layer_paths, svg_bytes


def _with_svgwrite(sheet: SheetDrawing, colors: str, stroke_mm: float) -> bytes:
    """The writer as it was, through svgwrite."""
    W, H = sheet.width, sheet.height
    dwg = svgwrite.Drawing(size=(f"{_num(W)}mm", f"{_num(H)}mm"), profile="full", debug=False)
    dwg.attribs["viewBox"] = f"0 0 {_num(W)} {_num(H)}"
    dwg.attribs["xmlns:inkscape"] = "http://www.inkscape.org/namespaces/inkscape"
    for name in LAYERS:
        g = dwg.g(
            id=name, fill="none", stroke=COLORS[colors][name][0], stroke_width=_num(stroke_mm)
        )
        g.attribs["stroke-linejoin"] = "round"
        g.attribs["inkscape:groupmode"] = "layer"
        g.attribs["inkscape:label"] = name
        for d in layer_paths(sheet.layers[name], sheet.groups[name], H):
            g.add(dwg.path(d=d))
        dwg.add(g)
    return ('<?xml version="1.0" encoding="utf-8" ?>\n' + dwg.tostring() + "\n").encode("utf-8")


@pytest.mark.parametrize("colors", sorted(COLORS))
@pytest.mark.parametrize("size", [(600.0, 400.0), (100.5, 33.25), (0.001, 7.0)])
def test_svg_bytes_are_svgwrites(colors, size):
    rng = np.random.default_rng(int(size[0] * 10))
    sheet = SheetDrawing(index=1, width=size[0], height=size[1])
    for name in LAYERS:
        for _ in range(4):
            k = int(rng.integers(2, 7))
            sheet.layers[name].append((rng.uniform(-5.0, size[0], (k, 2)), bool(rng.integers(2))))
            sheet.groups[name].append(int(rng.integers(-1, 2)))
    for stroke in (0.1, 0.025, 1.0):
        assert svg_bytes(sheet, colors, stroke) == _with_svgwrite(sheet, colors, stroke)
    empty = SheetDrawing(index=2, width=size[0], height=size[1])
    assert svg_bytes(empty, colors) == _with_svgwrite(empty, colors, 0.1)
