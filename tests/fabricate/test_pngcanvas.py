"""The cut pictures' Pillow canvas keeps matplotlib's geometry: one scale in x and y, centred in its box."""

from __future__ import annotations

from io import BytesIO

import numpy as np
from fabkiri.fabricate.pngcanvas import Canvas, rgb
from PIL import Image


def _dark(png: bytes) -> np.ndarray:
    return np.asarray(Image.open(BytesIO(png)).convert("L")) < 128


def test_a_length_in_mm_is_drawn_at_the_axes_scale_in_x_and_y():
    # 200 x 100 px picture, data 0..50 x 0..50 mm in a box as wide as the picture: 2 px/mm, centred
    def drawn(seg):
        cv = Canvas(200, 100)
        ax = cv.axes((0, 0, 1, 1), (0, 50), (0, 50))
        assert ax.scale == 2.0 * cv.s
        ax.lines([np.array(seg, dtype=float)], rgb("k"), 2.0)
        return _dark(cv.png())

    cols = np.flatnonzero(drawn([[10, 25], [40, 25]]).any(0))  # 30 mm across, from 50 + 20 px
    assert abs((cols.max() - cols.min()) - 60) <= 3 and abs(cols.min() - 70) <= 2
    rows = np.flatnonzero(drawn([[5, 5], [5, 45]]).any(1))  # 40 mm up, from 10 px above the bottom
    assert abs((rows.max() - rows.min()) - 80) <= 3 and abs(rows.max() - 90) <= 2


def test_colours_and_alpha_fills():
    assert (
        rgb("#1f77b4") == (31, 119, 180) and rgb("0.35") == (89, 89, 89) and rgb("k") == (0, 0, 0)
    )
    assert rgb("#d62728", 0.35) == (214, 39, 40, 89)
    cv = Canvas(40, 40)
    ax = cv.axes((0, 0, 1, 1), (0, 10), (0, 10))
    ax.polygons(
        [np.array([[0, 0], [10, 0], [10, 10], [0, 10]], float)], rgb("#d62728", 0.35), rgb("k"), 0.4
    )
    px = np.asarray(Image.open(BytesIO(cv.png())).convert("RGB"))[20, 20]
    # 35 % red over white
    assert (
        np.abs(px.astype(int) - [round(255 - 0.35 * (255 - c)) for c in (214, 39, 40)]).max() <= 2
    )
