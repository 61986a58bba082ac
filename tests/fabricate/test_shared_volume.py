"""Bodies printed together: volume shared face to face is round-off; a real overlap is caught."""

from __future__ import annotations

import manifold3d as m3d
import pytest
from fabkiri.fabricate.print.checks import OVERLAP_MM3, shared_volume


def _box(x0: float, x1: float) -> m3d.Manifold:
    return m3d.Manifold.cube([x1 - x0, 10.0, 3.0]).translate([x0, 0.0, 0.0])


def test_boxes_that_meet_face_to_face_share_no_piece_of_volume():
    total, piece = shared_volume(_box(0.0, 10.0), _box(10.0, 20.0))
    assert total <= OVERLAP_MM3 and piece <= OVERLAP_MM3


@pytest.mark.parametrize("depth", [0.01, 1e-3])
def test_boxes_that_overlap_share_a_piece_the_check_catches(depth):
    total, piece = shared_volume(_box(0.0, 10.0), _box(10.0 - depth, 20.0))
    assert piece == pytest.approx(depth * 30.0, rel=1e-6) and piece > OVERLAP_MM3
    assert total == pytest.approx(piece)


def test_the_largest_piece_is_judged_not_the_sum_of_many():
    a = m3d.Manifold.batch_boolean(
        [_box(20.0 * k, 20.0 * k + 10.0) for k in range(3)], m3d.OpType.Add
    )
    b = m3d.Manifold.batch_boolean(
        [_box(20.0 * k + 10.0 - 1e-3, 20.0 * k + 15.0) for k in range(3)], m3d.OpType.Add
    )
    total, piece = shared_volume(a, b)
    assert total == pytest.approx(3 * piece) and piece == pytest.approx(0.03, rel=1e-6)
