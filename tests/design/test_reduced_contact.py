"""Closed-state contact rows of the rigid-family solver (design/quad/rigid/contact.py)."""

from __future__ import annotations

import numpy as np
from fabkiri.design.quad import constraints as C
from fabkiri.design.quad.rigid.contact import CONTACT_MARGIN, ClosedContact
from fabkiri.design.quad.rigid.family import RigidFamily
from fabkiri.pattern import standard_pattern


def _contact(rows, cols):
    std = standard_pattern(rows, cols, tile_size=1.0)
    st = C.Stencils.from_pattern(std)
    fam = RigidFamily.build(st, std.topology.spanning_tree(0))
    S, _ = fam.fit(std.nodes, np.pi / 4)
    return fam, ClosedContact(fam, st), S


def test_a_corner_inside_a_far_tile_is_a_violated_row():
    """The standard closed states keep every far pair apart; a grid vertex moved into a tile three columns
    away gives negative rows whose stencil holds that vertex (and only the ring's far pairs are rows)."""
    fam, cc, S = _contact(8, 8)
    for s, x in enumerate(cc.configs(S)):
        g, nodes, _ = cc.measure(x, s + 1)
        assert len(g) and g.min() > 0.5  # at least half a tile apart
    c = cc.configs(S)[0]
    cell = c[[0, 1, 9, 10]].mean(
        0
    )  # the centre of grid cell (0, 0): vertices (0,0), (0,1), (1,0), (1,1)
    moved = c.copy()
    moved[3] = cell  # grid vertex (row 0, column 3), a corner of tiles (0, 2) and (0, 3)
    g, nodes, _ = cc.measure(moved, 1)
    bad = np.flatnonzero(g < -CONTACT_MARGIN)
    assert len(bad) and (nodes[bad, 0] == 3).any()


def test_contact_rows_jacobian_matches_finite_differences():
    """∂r/∂p of every row (all made active by a large margin) through Z (state 1) and Y (state 2)."""
    fam, cc, S = _contact(6, 8)
    S = S + 0.05 * np.random.default_rng(3).normal(size=S.shape)
    nf = fam.n_seeds
    p = np.r_[S[:, 0], S[:, 1], 0.6]

    def rows(p):
        S = np.stack([p[:nf], p[nf : 2 * nf]], -1)
        return cc.active(cc.configs(S), 1e4, 2.0)

    r, J = rows(p)
    assert len(r) > 100 and J.shape == (len(r), 2 * nf + 1) and not J[:, -1].any()
    h = 1e-6
    fd = np.empty_like(J)
    for i in range(len(p)):
        e = np.zeros_like(p)
        e[i] = h
        rp, rm = rows(p + e)[0], rows(p - e)[0]
        assert len(rp) == len(rm) == len(r)
        fd[:, i] = (rp - rm) / (2 * h)
    assert np.abs(J - fd).max() <= 1e-6 * max(1.0, np.abs(J).max())


def test_a_large_tile_over_a_tile_far_from_its_centre_is_a_violated_row():
    """A tile stretched many edges long (the 64x64 drop's state-1 corner tile) lies over a ring tile whose
    centre is far from its own: the pair is a row, and a violated one (a reach between centres alone missed it:
    the design's closed state overlapped and the solver's contact rows saw nothing)."""
    fam, cc, S = _contact(8, 12)
    c = cc.configs(S)[0]
    # grid vertex (0, 0), the outer corner of tile (0, 0), dragged along the bottom row into grid cell (0, 8)
    moved = c.copy()
    moved[0] = c[[8, 9, 21, 22]].mean(0)
    q = moved[cc.blocks[0][1][cc.ring]]
    cen, edge = q.mean(1), float(np.median(np.linalg.norm(q[:, 1] - q[:, 0], axis=1)))
    far_centre = np.linalg.norm(cen[0] - cen[int(np.flatnonzero((cc.r == 0) & (cc.c == 8))[0])])
    assert far_centre > 3 * edge  # beyond REACH edges between centres
    g, nodes, _ = cc.measure(moved, 1)
    bad = np.flatnonzero(g < -CONTACT_MARGIN)
    assert len(bad) and (nodes[bad, 0] == 0).any()


def test_rows_below_the_margin_come_from_the_pairs_that_may_touch_alone():
    """``measure(..., below)`` leaves out only pairs whose every row is above ``below``: the rows below it are
    the whole measure's, in the same order, on closed states pushed far from the standard ones."""
    fam, cc, S = _contact(12, 12)
    rng = np.random.default_rng(5)
    fewer = 0
    for noise in (0.0, 0.3, 0.6):
        for s, x in enumerate(cc.configs(S + noise * rng.normal(size=S.shape))):
            whole, some = cc.measure(x, s + 1), cc.measure(x, s + 1, CONTACT_MARGIN)
            fewer += len(some[0]) < len(whole[0])
            for m in (0.5 * CONTACT_MARGIN, CONTACT_MARGIN):
                a, b = np.flatnonzero(whole[0] < m), np.flatnonzero(some[0] < m)
                assert all(np.array_equal(u[a], v[b]) for u, v in zip(whole, some))
    assert fewer == 6
    # the merit's rows: below the margin only, with their values the whole measure's
    x = cc.configs(S + 0.6 * rng.normal(size=S.shape))
    r, J = cc.active(x, 1.0, 1.0)
    g = np.concatenate([cc.measure(c, s + 1)[0] for s, c in enumerate(x)])
    assert len(r) and np.array_equal(r, g[g < CONTACT_MARGIN] - CONTACT_MARGIN)
