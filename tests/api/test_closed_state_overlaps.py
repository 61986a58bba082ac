"""The closed-state overlap check on neighbouring tiles: measured in the pair's own pose, not the placement's."""

import numpy as np
from fabkiri.api.closed_states import overlapping_tiles
from fabkiri.mechanics.contract import contract, placed_through_hinge
from fabkiri.pattern import geometry
from fabkiri.pattern.kinds.quad.lattice import standard_pattern


def _nudged(state: int, shift: float):
    """The 4x4 standard pattern's closed ``state`` with tile 1 moved by ``shift`` tile sizes onto tile 0, its
    neighbour: what the spanning tree's accumulated loop closures do to two tiles on different branches (the
    rigid 128x128 bean: 1.1e-9 tile sizes)."""
    p = standard_pattern(4, 4, angle_deg=30.0)
    corners = contract(p, state).corners.copy()
    towards = corners[0].mean(axis=0) - corners[1].mean(axis=0)
    corners[1] += shift * p.tile_size * towards / np.linalg.norm(towards)
    return p, corners


def test_a_neighbour_pair_apart_but_for_the_placement_is_not_an_overlap():
    for state in (1, 2):
        p, corners = _nudged(state, 3e-9)
        tol = 1e-9 * p.tile_size
        assert (0, 1) in overlapping_tiles(corners, tol)  # the placement's reading alone
        assert overlapping_tiles(corners, tol, p, state) == []


def test_a_tile_over_a_tile_not_its_neighbour_is_still_an_overlap():
    p, corners = _nudged(1, 0.0)
    far = np.argmax(np.linalg.norm(corners.mean(axis=1) - corners[0].mean(axis=0), axis=1))
    corners[far] = corners[0] + [0.3 * p.tile_size, 0.0]
    found = overlapping_tiles(corners, 1e-9 * p.tile_size, p, 1)
    assert (min(0, far), max(0, far)) in found


def test_the_tile_through_a_hinge_is_where_the_contraction_puts_it_relative_to_the_other():
    p = standard_pattern(4, 4, angle_deg=30.0)
    for state in (1, 2):
        c = contract(p, state).corners
        hinges = np.arange(p.topology.n_hinges)
        for frm_side in (0, 1):
            frm = p.topology.hinge_tiles[:, frm_side]
            other = p.topology.hinge_tiles[:, 1 - frm_side]
            placed = placed_through_hinge(p, state, hinges, frm)
            # the contracted pair moved rigidly so that ``frm`` sits where it is deployed
            x = p.corners()
            for k, (a, b) in enumerate(zip(frm, other)):
                theta, shift = geometry.kabsch(c[a], x[a])
                assert np.allclose(geometry.rotate(c[b], theta) + shift, placed[k], atol=1e-9)
