"""Spring model: energy, analytic derivatives against finite differences, invariances."""

from __future__ import annotations

import numpy as np
import pytest
from fabkiri.errors import PatternError
from fabkiri.mechanics import with_contracted_states
from fabkiri.mechanics.energy import corner_energy, springs
from fabkiri.pattern import Pattern, geometry, standard_pattern
from hypothesis import given, settings
from hypothesis import strategies as st

from ..designs import reconfigurable_design


def _perturbed(seed=0, scale=0.05):
    p = standard_pattern(3, 4, tile_size=2.0)
    rng = np.random.default_rng(seed)
    return p, (p.nodes + scale * p.tile_size * rng.normal(size=p.nodes.shape)).ravel()


def test_six_springs_per_tile_with_design_rest_lengths():
    p = standard_pattern(2, 3, tile_size=7.0)
    sp = springs(p)
    assert sp.n_springs == 6 * p.n_tiles
    rest = sp.rest.reshape(-1, 6)
    assert np.allclose(rest[:, :4], 7.0) and np.allclose(rest[:, 4:], 7.0 * np.sqrt(2))
    assert np.array_equal(sp.tile, np.repeat(np.arange(p.n_tiles), 6))


def test_energy_zero_in_deployed_and_both_closed_states():
    p = with_contracted_states(reconfigurable_design(4, 5, seed=2, amplitude=0.2))
    sp = springs(p)
    assert sp.energy(p.nodes) <= 1e-28
    for s in (1, 2):
        assert corner_energy(sp, p.contracted[s]).sum() <= 1e-26
        assert sp.energy(p.node_positions(s)) <= 1e-26  # nodes from the stored tiles


def test_energy_value_and_tile_energy():
    p = standard_pattern(1, 2, tile_size=1.0)
    sp = springs(p)
    x = p.nodes.copy()
    t0 = p.tiles[0]
    free = [v for v in t0 if v not in p.tiles[1]]
    x[free[0]] += [0.1, 0.0]  # stretch one free corner of tile 0
    e = sp.tile_energy(x)
    assert e[1] == 0.0 and e[0] > 0
    r = sp.strains(x)
    assert sp.energy(x) == pytest.approx(float(r @ r)) == pytest.approx(e.sum())
    # by hand: one of its springs is the edge/diagonal pair through that corner
    d = np.linalg.norm(x[sp.pairs[:, 0]] - x[sp.pairs[:, 1]], axis=1)
    assert np.allclose(r, (d - sp.rest) / sp.rest)


def test_gradient_matches_finite_differences():
    p, x = _perturbed(1)
    sp = springs(p)
    g = sp.gradient(x)
    h = 1e-6 * p.tile_size
    fd = np.empty_like(x)
    for k in range(len(x)):
        e = np.zeros_like(x)
        e[k] = h
        fd[k] = (sp.energy(x + e) - sp.energy(x - e)) / (2 * h)
    assert np.abs(g - fd).max() <= 1e-6 * np.abs(g).max()


def test_hessian_and_jacobian_match_finite_differences():
    p, x = _perturbed(2)
    sp = springs(p)
    H = sp.hessian(x).toarray()
    J = sp.jacobian(x).toarray()
    h = 1e-6 * p.tile_size
    Hfd = np.empty_like(H)
    Jfd = np.empty_like(J)
    for k in range(len(x)):
        e = np.zeros_like(x)
        e[k] = h
        Hfd[:, k] = (sp.gradient(x + e) - sp.gradient(x - e)) / (2 * h)
        Jfd[:, k] = (sp.strains(x + e) - sp.strains(x - e)) / (2 * h)
    assert np.abs(H - H.T).max() <= 1e-12 * np.abs(H).max()
    assert np.abs(H - Hfd).max() <= 1e-6 * np.abs(H).max()
    assert np.abs(J - Jfd).max() <= 1e-7 * np.abs(J).max()
    # Gauss-Newton part is 2 JᵀJ and equals H at a zero-strain point
    x0 = p.nodes.ravel()
    assert (
        np.abs(sp.gauss_newton(x0).toarray() - sp.hessian(x0).toarray()).max()
        <= 1e-12 * np.abs(H).max()
    )


@settings(max_examples=25, deadline=None)
@given(
    theta=st.floats(-np.pi, np.pi),
    dx=st.floats(-100, 100),
    dy=st.floats(-100, 100),
    seed=st.integers(0, 50),
)
def test_energy_invariant_under_rigid_motions(theta, dx, dy, seed):
    p, x = _perturbed(seed)
    sp = springs(p)
    moved = geometry.rotate(x.reshape(-1, 2), theta) + [dx, dy]
    e0, e1 = sp.energy(x), sp.energy(moved)
    assert e1 == pytest.approx(e0, rel=1e-9, abs=1e-18)
    # and the gradient rotates with the pattern
    g0 = geometry.rotate(sp.gradient(x).reshape(-1, 2), theta)
    assert np.abs(sp.gradient(moved).reshape(-1, 2) - g0).max() <= 1e-8 * max(1.0, np.abs(g0).max())


def test_zero_length_spring_is_a_pattern_error():
    p = standard_pattern(1, 1)
    nodes = p.nodes.copy()
    nodes[1] = nodes[0]  # collapse an edge: Pattern itself allows it, springs must not
    bad = Pattern(nodes=nodes, tiles=p.tiles)
    with pytest.raises(PatternError, match="zero-length"):
        springs(bad)
