"""A stretch of outline turning enough for two corners holds two (``strip_split.turn_corners``): a crescent's
rounded tips are a bent strip's ends, where main found one corner each and so never tried a strip."""

from __future__ import annotations

import numpy as np
from fabkiri.design.quad.strip_split import strip_splits, turn_corners
from fabkiri.design.targets.curve import Target
from shapely.geometry import Point


def _crescent() -> Target:
    # a disc of radius 50 less one of radius 40 moved 28 to the right; tips rounded by 3 mm
    moon = Point(0, 0).buffer(50, 256).difference(Point(28, 0).buffer(40, 256))
    ring = moon.buffer(3).buffer(-6).buffer(3).exterior
    pts = [ring.interpolate(s).coords[0] for s in np.linspace(0, ring.length, 120, endpoint=False)]
    return Target("moon", "spline", np.array(pts))


def test_each_tip_of_a_crescent_holds_two_corners_either_side_of_it():
    tgt = _crescent()
    found = tgt.point(turn_corners(tgt))
    assert len(found) == 4  # main: 2, one per tip
    tips = np.array(
        [[23.0, 42.0], [23.0, -42.0]]
    )  # where the circles cross (30, +-40), rounded off
    near = np.linalg.norm(found[:, None] - tips[None], axis=2).argmin(1)
    assert sorted(near.tolist()) == [0, 0, 1, 1]
    # either side of its tip: one on the outer arc (radius 50), one on the inner (40 about x = 28)
    for k in (0, 1):
        pair = found[near == k]
        outer = np.abs(np.linalg.norm(pair, axis=1) - 50.0)
        inner = np.abs(np.linalg.norm(pair - [28.0, 0.0], axis=1) - 40.0)
        assert sorted(np.argmin([outer, inner], axis=0).tolist()) == [0, 1]


def test_a_crescent_whose_start_folds_is_offered_its_strip():
    # its one strip scores a hair above the own split's folding start; main offered only strips scoring below
    splits = strip_splits(_crescent(), 16, 16)
    assert len(splits) == 1
    tgt, (rows, cols) = splits[0]
    assert min(rows, cols) >= 4 and abs(rows * cols - 256) <= max(rows, cols)
    ends = tgt.point(tgt.corners)
    assert (np.abs(ends[:, 0] - 23.0) < 2.0).all()  # all four corners at the two tips


def test_a_sharp_tip_turning_for_two_corners_holds_one():
    # a lightning bolt's acute vertices turn >= 120 degrees at one sample: its two quarter points were the
    # same parameter, and the split through both refused the user's outline ("corners ... CCW order", exit 2)
    pts = np.array([(40, 100), (85, 100), (60, 62), (80, 62), (30, 0), (42, 45), (20, 45)], float)
    tgt = Target("bolt", "polyline", pts[::-1])
    found = turn_corners(tgt)
    assert len(found) >= 4 and (np.diff(found) > 0).all()
    for split, _ in strip_splits(tgt, 16, 16):
        assert (np.diff(split.corners) > 0).all()
