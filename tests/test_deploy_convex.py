"""The convexity term of the quad elastic path (:func:`fabkiri.mechanics.contact.corner_term`):
every tile's interior angles held above a part of their design, so a spring tile cannot fold
into a bow-tie across its hinged neighbour."""

from __future__ import annotations

import numpy as np
from fabkiri.mechanics.contact import corner_gaps, corner_term

from .designs import reconfigurable_design
from .test_kagome_contact import _fd_check


def _design():
    return reconfigurable_design(4, 4, seed=2, amplitude=0.3, waves=3)


def test_corner_angles_are_the_interior_angles_of_every_tile():
    p = _design()
    corners = corner_gaps(p)
    k = p.tiles.shape[1]
    angles = corners.deployed.reshape(-1, k)
    assert (angles > 0).all() and (angles < np.pi).all()
    assert np.allclose(angles.sum(axis=1), 2 * np.pi)  # a convex quad's angles add up to 2π
    assert np.allclose(corners.angles(p.nodes.ravel()), corners.deployed)
    # a rigid motion keeps them: the term is zero at every state
    term = corner_term(p, weight=1.0, kappa=0.5)
    c, s = np.cos(0.7), np.sin(0.7)
    moved = p.nodes @ np.array([[c, s], [-s, c]]) + 3.0
    assert term.energy(p.nodes.ravel()) == 0.0 and term.energy(moved.ravel()) == 0.0


def test_corner_term_penalises_a_bow_tie():
    p = _design()
    term = corner_term(p, weight=1.0, kappa=0.5)
    x = p.nodes.copy()
    a, b = p.tiles[5, 0], p.tiles[5, 1]
    x[[a, b]] = x[[b, a]]  # two corners of tile 5 swapped: it crosses itself
    assert term.energy(x.ravel()) > 0.5  # at least one corner angle below zero: φ ≥ 1


def test_corner_term_matches_finite_differences():
    p = _design()
    corners = corner_gaps(p)
    rng = np.random.default_rng(3)
    x = p.nodes.ravel() + 0.08 * p.tile_size * rng.standard_normal(p.nodes.size)
    ang = corners.angles(x)
    # clearances above every corner angle by different margins: every corner active, none at its kink
    term = corner_term(p, weight=1.3, kappa=0.5)
    term = type(term)(
        corners, term.rows, ang[term.rows] + np.linspace(0.01, 0.3, len(term.rows)), 1.3, 0.5
    )
    assert term.energy(x) > 0
    grad_err, hess_err = _fd_check(term, x)
    assert grad_err <= 1e-6 and hess_err <= 1e-6
