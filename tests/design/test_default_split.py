"""The default four-arc split of an outline that is not star-shaped about its box's centre (a comb, an E):
the rays from the centre may meet it out of order, and the split then falls back to the hull's diagonal
extremes (main refused such outlines: "corners BL, BR, TR, TL must be in CCW order", corners the user never
gave)."""

from __future__ import annotations

import numpy as np
from fabkiri.design.targets.curve import Target
from hypothesis import given, settings
from hypothesis import strategies as hst
from shapely.geometry import box
from shapely.ops import unary_union


def _comb(arms: list[tuple[float, float, float]], samples: int = 0) -> np.ndarray:
    """A back 20 x 100 mm with arms (bottom y, thickness, length) to the right, corners rounded by 3 mm;
    `samples` points evenly along it, or its vertices."""
    parts = [box(0, 0, 20, 100)] + [box(0, y, 20 + a, y + h) for y, h, a in arms]
    ring = unary_union(parts).buffer(3.0, join_style=2).buffer(-6.0).buffer(3.0).exterior
    if not samples:
        return np.asarray(ring.coords)[:-1]
    return np.array(
        [ring.interpolate(s).coords[0] for s in np.linspace(0, ring.length, samples, False)]
    )


E = [(0.0, 22.0, 50.0), (41.0, 18.0, 25.0), (80.0, 20.0, 40.0)]


def test_an_e_gets_a_split_in_ccw_order_at_its_diagonal_extremes():
    tgt = Target("e", "polyline", _comb(E, samples=120))  # main: its BL ray met the back's inside
    assert (np.diff(tgt.corners) > 0).all() and tgt.corners[3] - tgt.corners[0] < 1.0
    # BL the back's foot, BR the bottom arm's lower tip, TR the top arm's upper tip, TL the back's top
    got = tgt.point(tgt.corners)
    np.testing.assert_allclose(
        got, [[0, 0], [70, 0], [60, 100], [0, 100]], atol=2.5
    )  # samples 3.2 mm apart


def test_a_star_shaped_outline_keeps_the_ray_split():
    pts = np.array([[0, 0], [10, -1], [11, 5], [9, 10], [1, 11], [-1, 4]], float)
    tgt = Target("hex", "polyline", pts)
    np.testing.assert_array_equal(tgt.corners, tgt._ray_corners())


@settings(max_examples=30, deadline=None)
@given(
    hst.lists(hst.tuples(hst.floats(12.0, 25.0), hst.floats(10.0, 80.0)), min_size=2, max_size=3)
)
def test_every_comb_builds_with_four_ordered_arcs(arms):
    # arms spread over the back's height, a gap of at least 8 mm between them
    ys = np.linspace(0.0, 100.0 - arms[-1][0], len(arms))
    spec = [(y, h, a) for y, (h, a) in zip(ys, arms, strict=True)]
    if any(y1 - (y0 + h0) < 8.0 for (y0, h0, _), (y1, _, _) in zip(spec, spec[1:])):
        return
    tgt = Target("comb", "polyline", _comb(spec))
    assert (np.diff(tgt.corners) > 0).all() and tgt.corners[3] - tgt.corners[0] < 1.0
