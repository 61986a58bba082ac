"""The least-squares assembly of cut tiles (verify/assemble.py): analytic Jacobian against finite
differences; 1 µm noise stays a µm-sized closure error where the tree placement compounds it;
a tile cut 1 % too large still fails to close."""

from __future__ import annotations

import numpy as np
from fabkiri.mechanics.contract import with_contracted_states
from fabkiri.pattern import geometry, standard_pattern
from fabkiri.verify.assemble import Assembly
from fabkiri.verify.matching import assembled, place_from_shapes

from .. import layout_fixtures as lf


def test_jacobian_matches_finite_differences():
    p = lf.distinct_pattern()
    C = p.corners() + np.random.default_rng(1).normal(scale=1e-3, size=p.corners().shape)
    a = Assembly(p, C, 2)
    x = np.random.default_rng(2).normal(size=3 * a.T)
    J = a.jacobian(x).toarray()
    F = np.zeros_like(J)
    h = 1e-6
    for k in range(len(x)):
        e = np.zeros_like(x)
        e[k] = h
        F[:, k] = (a.residuals(x + e) - a.residuals(x - e)) / (2 * h)
    assert np.abs(J - F).max() <= 1e-6 * np.abs(J).max()


def _split(p, Y):
    A, B = p.topology.hinge_tiles.T
    cA, cB = p.topology.hinge_corner.T
    return np.linalg.norm(Y[A, cA] - Y[B, cB], axis=1).max()


def test_rounding_noise_does_not_compound():
    """16x16 lattice of 20 mm tiles, turned, with corners rounded to 1 µm: the tree placement's split grows with
    the tree depth, the fitted assembly's stays at the rounding's size."""
    p = with_contracted_states(standard_pattern(16, 16, tile_size=20.0))
    C = np.round(geometry.rotate(p.contracted[1], 0.577) + np.array([123.4567891, 45.678912]), 3)
    _, tree = place_from_shapes(p, C, 2)
    _, split = assembled(p, C, 2)
    assert tree.max() > 0.02  # measured 0.054 mm: the compounding is real
    assert split.max() <= 5e-3, split.max()  # measured 0.0017 mm


def test_a_scaled_tile_still_fails_to_close():
    p = lf.distinct_pattern()
    C = p.corners().copy()
    c = C[7].mean(0)
    C[7] = (C[7] - c) * 1.01 + c
    _, split = assembled(p, C, 2)
    assert split.max() > 0.05
    _, exact = assembled(p, p.corners(), 2)
    assert exact.max() <= 1e-9
