"""The kagome (rotating-triangles) kind: lattice, topology, both closed states by contraction."""

from __future__ import annotations

import numpy as np
import pytest
import shapely
from fabkiri.errors import InputError, PatternError
from fabkiri.mechanics.contract import contract
from fabkiri.pattern import geometry
from fabkiri.pattern.kinds.kagome.lattice import kagome_corners, standard_kagome
from fabkiri.pattern.kinds.tessellation import kinds, tessellation
from fabkiri.pattern.model import Pattern
from fabkiri.pattern.topology import derive_topology
from fabkiri.verify.geom import overlap_depths

SIZES = [(4, 4), (7, 5), (16, 16)]


def _counts(rows: int, cols: int) -> tuple[int, int, int]:
    """Tiles, hinges and holes of the R x C kagome, counted on the brick-wall tile graph."""
    links = [len(range(r % 2, cols, 2)) for r in range(rows - 1)]  # up (r, c) joins (r+1, c)
    hinges = rows * (cols - 1) + sum(links)
    holes = sum(max(n - 1, 0) for n in links)
    return rows * cols, hinges, holes


def test_kagome_is_registered_with_triangle_tiles_and_hexagonal_holes():
    k = tessellation("kagome")
    assert (k.kind, k.arity, k.hole_arity, k.states) == ("kagome", 3, 6, (1, 2))
    assert "kagome" in kinds() and not k.rigid_family
    p = standard_kagome(3, 4)
    assert p.kind == "kagome" and p.topology.arity == 3


@pytest.mark.parametrize("rows, cols", SIZES)
def test_topology_is_a_honeycomb_of_up_and_down_triangles(rows, cols):
    p = standard_kagome(rows, cols, angle_deg=40.0)
    top = p.topology
    assert (top.n_tiles, top.n_hinges, top.n_holes) == _counts(rows, cols)
    r, c = np.divmod(np.arange(top.n_tiles), cols)
    np.testing.assert_array_equal(top.tile_color, (r + c) % 2)  # up tiles are the even colour
    assert np.bincount(top.hinge_tiles.ravel(), minlength=top.n_tiles).max() == 3
    assert top.hole_nodes.shape == (top.n_holes, 6)
    assert (geometry.signed_areas(p.corners()) > 0).all()  # CCW triangles


@pytest.mark.parametrize("rows, cols", SIZES)
def test_standard_kagome_closes_in_both_states(rows, cols):
    s = 10.0
    p = standard_kagome(rows, cols, tile_size=s, angle_deg=50.0)
    closed = {
        1: kagome_corners(rows, cols, 0.0, s),
        2: kagome_corners(rows, cols, np.radians(120), s),
    }
    states = {}
    for state in (1, 2):
        c = contract(p, state)
        Y = c.corners
        assert c.max_closure <= 1e-12 * s
        # the closed state is the lattice at psi = 0 (state 1) or 120 degrees (state 2)
        assert geometry.aligned_distance(Y, closed[state]) <= 1e-12 * s
        # congruent equilateral tiles of side s
        assert np.abs(geometry.edge_lengths(Y) - s).max() <= 1e-12 * s
        # compact: no overlaps, and the tiles cover their union exactly
        polys = shapely.polygons(Y)
        union = shapely.union_all(polys)
        area = geometry.signed_areas(Y)
        assert abs(union.area - area.sum()) <= 1e-9 * s * s
        # and no pair overlaps (separating-axis depth; GEOS's pairwise intersection of two
        # triangles sharing an edge to 1e-15 is not robust, so it is not used per pair)
        _, _, depth = overlap_depths(Y)
        assert depth.max(initial=0.0) <= 1e-12 * s
        # each hole folds at three alternate corners; the six edges coincide in pairs
        fold = p.topology.fold(state)
        assert (fold.hole_folds.sum(1) == 3).all()
        states[state] = Y
    # the two closed states are different layouts, not one state twice
    assert geometry.aligned_distance(states[1], states[2]) > 0.5 * s
    f1, f2 = p.topology.fold(1), p.topology.fold(2)
    assert (f1.hole_folds != f2.hole_folds).all() and (f1.fold_gap != f2.fold_gap).all()


def test_closed_state_pairs_hole_edges_shifted_by_one():
    p = standard_kagome(5, 6, angle_deg=35.0)
    top = p.topology
    for state in (1, 2):
        fold = top.fold(state)
        Y = contract(p, state).corners
        # position of every hole corner in the closed state, from the tile owning edge c -> c+1
        for k in range(top.n_holes):
            nodes = top.hole_nodes[k]
            t = top.hole_tiles[k]
            where = [np.flatnonzero(top.tiles[t[c]] == nodes[c])[0] for c in range(6)]
            pts = np.array([Y[t[c], where[c]] for c in range(6)])
            merge = np.flatnonzero(~fold.hole_folds[k])
            # the three merge corners meet at one point
            assert np.ptp(pts[merge], axis=0).max() <= 1e-12 * p.tile_size


def test_rxc_and_angle_are_checked():
    with pytest.raises(InputError, match="at least 1x1"):
        standard_kagome(0, 3)
    with pytest.raises(InputError, match=r"\[0, 120\] degrees"):
        standard_kagome(2, 2, angle_deg=130.0)


def test_tiles_of_another_arity_are_rejected_naming_the_kagome_tile():
    p = standard_kagome(2, 3)
    with pytest.raises(PatternError, match="tiles must be kagome tiles"):
        derive_topology(np.c_[p.tiles, p.tiles[:, :1]], len(p.nodes), kind="kagome")
    with pytest.raises(PatternError, match="kagome tile of 3 node indices"):
        Pattern(nodes=p.nodes, tiles=np.c_[p.tiles, p.tiles[:, :1]], kind="kagome")
