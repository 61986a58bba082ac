"""The standard rotating-squares lattice and its two closed states."""

from __future__ import annotations

import numpy as np
import pytest
from fabkiri.mechanics import contract_both
from fabkiri.pattern import geometry, standard_pattern
from fabkiri.pattern.kinds.quad.lattice import quad_corners
from fabkiri.pattern.residuals import hinge_sums, state_residuals


def tile_rotations(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Angle turning each tile's first edge in ``a`` onto the same edge in ``b``."""
    ea = a[:, 1] - a[:, 0]
    eb = b[:, 1] - b[:, 0]
    return geometry.signed_angle(ea, eb)


def check_standard(rows: int, cols: int, angle: float = 45.0, size: float = 10.0) -> None:
    p = standard_pattern(rows, cols, tile_size=size, angle_deg=angle)
    top = p.topology
    assert top.n_hinges == rows * (cols - 1) + (rows - 1) * cols
    assert len(top.free_nodes) == 2 * (rows + cols)
    assert top.n_holes == (rows - 1) * (cols - 1)
    both = contract_both(p)
    deployed = p.corners()
    for s in (1, 2):
        assert both[s].max_closure <= 1e-12 * size
        r = state_residuals(p, s)
        assert r.edge_pairs.max(initial=0) <= 1e-12 * size
        assert np.abs(r.rings).max(initial=0) <= 1e-12
        # every tile congruent to its deployed copy: equal edges and angles
        assert (
            np.abs(geometry.edge_lengths(both[s].corners) - geometry.edge_lengths(deployed)).max()
            <= 1e-12 * size
        )
        ang = geometry.wrap_angle(
            geometry.corner_angles(both[s].corners) - geometry.corner_angles(deployed)
        )
        assert np.abs(ang).max() <= 1e-12
    assert np.abs(hinge_sums(p)).max(initial=0) <= 1e-12
    # state 1 is the ψ=0 grid, state 2 the ψ=π/2 grid (up to one rigid motion)
    assert (
        geometry.aligned_distance(both[1].corners, quad_corners(rows, cols, 0.0, size))
        <= 1e-9 * size
    )
    assert (
        geometry.aligned_distance(both[2].corners, quad_corners(rows, cols, np.pi / 2, size))
        <= 1e-9 * size
    )
    # state 2 = state 1 with every tile turned by ±90° in a checkerboard, after aligning the tile centres
    s1, s2 = both[1].corners, both[2].corners
    theta, t = geometry.kabsch(s2.mean(1), s1.mean(1))
    s2 = geometry.rotate(s2, theta) + t
    assert np.abs(s2.mean(1) - s1.mean(1)).max() <= 1e-9 * size
    rot = tile_rotations(s1, s2)
    r, c = np.divmod(np.arange(rows * cols), cols)
    checker = np.where((r + c) % 2 == 0, 1.0, -1.0)
    sign = np.sign(rot[0])
    assert np.abs(rot - sign * checker * np.pi / 2).max() <= 1e-9


@pytest.mark.parametrize("rows,cols", [(1, 1), (1, 5), (5, 1), (2, 2), (7, 5), (8, 8), (50, 50)])
def test_standard_patterns_close_in_both_states(rows, cols):
    check_standard(rows, cols)


def test_fold_rule_matches_spec_for_lattice_holes():
    # hole (i, j) with i+j even folds at W and E in state 1, else at S and N
    # (docs/algorithm.md#holes-and-fold-rules)
    rows, cols = 4, 5
    p = standard_pattern(rows, cols)
    top = p.topology
    nodes = p.nodes
    fold1 = top.fold(1).hole_folds
    for k in range(top.n_holes):
        corners = nodes[top.hole_nodes[k]]
        centre = corners.mean(0)
        # which corners are left/right (W/E) of the hole in the deployed square-hole state
        horizontal = np.abs(corners[:, 0] - centre[0]) > np.abs(corners[:, 1] - centre[1])
        i = int(np.floor((centre[1] - nodes[:, 1].min()) / (p.tile_size * np.sqrt(2)) - 0.5))
        j = int(np.floor((centre[0] - nodes[:, 0].min()) / (p.tile_size * np.sqrt(2)) - 0.5))
        expect = horizontal if (i + j) % 2 == 0 else ~horizontal
        assert (fold1[k] == expect).all(), k


def test_pattern_at_zero_angle_is_already_closed():
    p = standard_pattern(3, 4, angle_deg=0.0)
    both = contract_both(p)
    assert geometry.aligned_distance(both[1].corners, p.corners()) <= 1e-12 * p.tile_size
