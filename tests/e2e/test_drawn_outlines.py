"""Outlines drawn in Inkscape, Illustrator or a CAD tool as design targets (docs/bad-input.md, hard56).

An SVG or DXF target is read as the one closed curve it draws, whatever element draws it, at its
units; a drawing with several closed curves or none is refused with one line, never read as the first
curve that came.
"""

from __future__ import annotations

import ezdxf
import numpy as np
import pytest
from fabkiri.design.targets.lookup import load_target
from fabkiri.errors import InputError

SVG = '<svg xmlns="http://www.w3.org/2000/svg" width="100mm" height="100mm" viewBox="0 0 100 100">{}</svg>'

# name: (drawing, its outline's width x height in mm, area in mm²)
SVGS = {
    "rect": ("<rect x='10' y='10' width='40' height='30'/>", (40, 30), 1200.0),
    "polygon": ("<polygon points='10,10 50,10 50,40 10,40'/>", (40, 30), 1200.0),
    "circle": ("<circle cx='50' cy='50' r='30'/>", (60, 60), np.pi * 900),
    # 30 x 10 radii turned 30°: its box is 2 sqrt(30² cos² + 10² sin²) wide
    "ellipse": (
        "<ellipse cx='50' cy='50' rx='30' ry='10' transform='rotate(30 50 50)'/>",
        (2 * 700**0.5, 2 * 300**0.5),
        np.pi * 300,
    ),
    "hidden layer": (
        "<g style='display:none'><path d='M0 0H5V5H0Z'/></g><path d='M0 0H80V60H0Z'/>",
        (80, 60),
        4800.0,
    ),
}

# name: (drawing, words of the refusal)
BAD_SVGS = {
    "a speck before the outline": (
        "<path d='M45 45h2v2h-2z'/><path d='M0 0H80V60H0Z'/>",
        "2 closed curves",
    ),
    "a page background": (
        "<rect width='100' height='100' fill='white'/><path d='M10 10H90V70H10Z'/>",
        "which is the outline",
    ),
    "an outline with a hole": ("<path d='M0 0H80V60H0Z M20 20H40V40H20Z'/>", "2 closed curves"),
    "an open curve": ("<path d='M0 0H80V60'/>", "only open ones"),
}


@pytest.mark.parametrize("name", sorted(SVGS))
def test_an_svg_outline_is_the_closed_curve_it_draws(name, tmp_path):
    drawing, size, area = SVGS[name]
    (tmp_path / "t.svg").write_text(SVG.format(drawing))
    tgt = load_target(str(tmp_path / "t.svg"))  # rect, polygon, circle, ellipse were refused
    assert np.allclose(np.ptp(tgt.points, axis=0), size, rtol=1e-4)
    assert abs(tgt.area) == pytest.approx(area, rel=1e-3)


@pytest.mark.parametrize("name", sorted(BAD_SVGS))
def test_an_svg_with_no_one_outline_is_refused(name, tmp_path):
    drawing, words = BAD_SVGS[name]
    (tmp_path / "t.svg").write_text(SVG.format(drawing))
    with pytest.raises(InputError, match=words):  # was read as its first path
        load_target(str(tmp_path / "t.svg"))


def _dxf(draw, units: int = 4):
    doc = ezdxf.new()
    doc.header["$INSUNITS"] = units
    draw(doc, doc.modelspace())
    return doc


def _lines(doc, m):  # LibreCAD's way: loose segments meeting end to end, one of them an arc
    m.add_line((0, 0), (80, 0))
    m.add_arc((80, 30), 30, -90, 90)
    m.add_line((80, 60), (0, 60))
    m.add_line((0, 60), (0, 0))


def _block(doc, m):
    doc.blocks.new("B").add_lwpolyline([(0, 0), (10, 0), (10, 10), (0, 10)], close=True)
    m.add_blockref("B", (5, 5), dxfattribs={"xscale": 4, "yscale": 3})


RECT = [(0, 0), (80, 0), (80, 60), (0, 60)]
HALF_DISC = (
    4800 + np.pi * 900 / 2
)  # the 80 x 60 rectangle with a half disc of radius 30 on its right

DXFS = {
    "lwpolyline": (lambda d, m: m.add_lwpolyline(RECT, close=True), 4, (80, 60), 4800.0),
    "inches": (
        lambda d, m: m.add_lwpolyline(RECT, close=True),
        1,
        (80 * 25.4, 60 * 25.4),
        4800 * 645.16,
    ),
    "bulge": (
        lambda d, m: m.add_lwpolyline(
            [(0, 0, 0, 0, 0), (80, 0, 0, 0, 1), (80, 60, 0, 0, 0), (0, 60, 0, 0, 0)],
            format="xyseb",
            close=True,
        ),
        4,
        (110, 60),
        HALF_DISC,
    ),
    "lines and an arc": (_lines, 4, (110, 60), HALF_DISC),
    "block": (_block, 4, (40, 30), 1200.0),
    "circle": (lambda d, m: m.add_circle((10, 10), 30), 4, (60, 60), np.pi * 900),
}


@pytest.mark.parametrize("name", sorted(DXFS))
def test_a_dxf_outline_is_read_in_mm(name, tmp_path):
    draw, units, size, area = DXFS[name]
    _dxf(draw, units).saveas(tmp_path / "t.dxf")
    tgt = load_target(str(tmp_path / "t.dxf"))  # was: "line 1: 1 numbers, expected two (x,y)"
    assert np.allclose(np.ptp(tgt.points, axis=0), size, rtol=1e-4)
    assert abs(tgt.area) == pytest.approx(area, rel=1e-3)


@pytest.mark.parametrize(
    ("draw", "words"),
    [
        (lambda d, m: (m.add_lwpolyline(RECT, close=True), m.add_circle((40, 30), 5)), "2 closed"),
        (lambda d, m: m.add_line((0, 0), (80, 0)), "no closed outline"),
        (lambda d, m: None, "no lines or curves"),
    ],
    ids=["two outlines", "open", "empty"],
)
def test_a_dxf_with_no_one_outline_is_refused(draw, words, tmp_path):
    _dxf(draw).saveas(tmp_path / "t.dxf")
    with pytest.raises(InputError, match=words):
        load_target(str(tmp_path / "t.dxf"))
