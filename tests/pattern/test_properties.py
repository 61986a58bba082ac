"""Property-based tests of the lattice, contraction and file round trip."""

from __future__ import annotations

import numpy as np
from fabkiri.exchange.pattern_json import dumps, loads
from fabkiri.mechanics import contract_both, with_contracted_states
from fabkiri.pattern import Pattern, geometry, standard_pattern
from hypothesis import given, settings
from hypothesis import strategies as st

sizes = st.integers(min_value=1, max_value=9)
angles = st.floats(min_value=0.0, max_value=90.0, allow_nan=False)


@settings(max_examples=40, deadline=None)
@given(sizes, sizes, angles, st.floats(min_value=0.5, max_value=50.0))
def test_random_lattices_close_and_stay_congruent(rows, cols, angle, size):
    p = standard_pattern(rows, cols, tile_size=size, angle_deg=angle)
    deployed = p.corners()
    for c in contract_both(p).values():
        assert c.max_closure <= 1e-12 * size * max(rows, cols)
        assert (
            np.abs(geometry.edge_lengths(c.corners) - geometry.edge_lengths(deployed)).max()
            <= 1e-12 * size * 10
        )


@settings(max_examples=25, deadline=None)
@given(sizes, sizes, angles, st.integers(0, 2**31 - 1))
def test_json_round_trip_exact_with_random_numbering(rows, cols, angle, seed):
    p = standard_pattern(rows, cols, angle_deg=angle)
    rng = np.random.default_rng(seed)
    perm = rng.permutation(len(p.nodes))  # arbitrary node numbering
    inv = np.argsort(perm)
    shift = rng.integers(0, 4, size=p.n_tiles)  # arbitrary starting corner
    tiles = np.take_along_axis(inv[p.tiles], (np.arange(4)[None] + shift[:, None]) % 4, 1)
    q = Pattern(nodes=p.nodes[perm], tiles=tiles)
    q = with_contracted_states(q)
    assert all(c.max_closure <= 1e-12 * p.tile_size * 10 for c in contract_both(q).values())
    text = dumps(q)
    r = loads(text)
    assert np.array_equal(r.nodes, q.nodes) and np.array_equal(r.tiles, q.tiles)
    assert all(np.array_equal(r.contracted[s], q.contracted[s]) for s in (1, 2))
    assert dumps(r) == text
