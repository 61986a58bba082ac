"""Above 96x96 tiles (``family.EXACT_GRID``): a member's nodes with its rows met to round-off (``exact_nodes``),
a coarse member's seeds from its seed tiles (``member_seeds``), a fine start's seeds by the core's normal
equations (``seeds_for_grid``), and ``Y S`` by the tiles' translations (``translations``, rank's closed states)."""

from __future__ import annotations

import numpy as np
import pytest
from fabkiri.design.quad import constraints as C
from fabkiri.design.quad.rigid import family as F
from fabkiri.design.quad.rigid.family import RigidFamily
from fabkiri.pattern import standard_pattern

EPS = np.finfo(float).eps


def _member(rows: int, cols: int, amp: float = 0.05, seed: int = 0):
    std = standard_pattern(rows, cols, tile_size=1.0)
    st = C.Stencils.from_pattern(std)
    fam = RigidFamily.build(st, std.topology.spanning_tree(0))
    gi, gj = np.divmod(fam.seeds, cols + 1)
    rng = np.random.default_rng(seed)
    S = np.stack([gj, gi], -1).astype(float) + amp * rng.standard_normal((fam.n_seeds, 2))
    return fam, S


def _midpoint_miss(fam: RigidFamily, c: np.ndarray) -> float:
    z, a, b = fam.midpoint.T
    return float(np.abs(c[z] - 0.5 * (c[a] + c[b])).max())


def test_exact_nodes_are_the_member_with_its_midpoint_rows_met_to_round_off():
    fam, S = _member(40, 40)
    X = fam.nodes(S, 0.7)
    E = fam.exact_nodes(S, 0.7)
    assert np.abs(E - X).max() <= 1e-9 * np.abs(X).max()
    # at ψ = 0 every node sits on its grid vertex: the grid exact_nodes solved for
    c = np.empty((len(fam.Z), 2))
    c[fam.node_vertex] = fam.exact_nodes(S, 0.0)
    assert np.array_equal(c[fam.seeds], S)
    assert _midpoint_miss(fam, c) <= 8 * EPS * np.abs(c).max()
    assert _midpoint_miss(fam, c) < _midpoint_miss(fam, fam.Z @ S)


def test_exact_nodes_are_z_s_and_tau_s_to_round_off_on_an_uneven_lattice():
    """The grid solved from the seeds is ``Z S``, the translations integrated along the tree ``τ S``."""
    fam, S = _member(30, 24, seed=3)
    psi = 0.9
    E, X = fam.exact_nodes(S, psi), fam.nodes(S, psi)
    assert np.abs(E - X).max() <= 1e-9 * np.abs(X).max()
    c = np.empty((len(fam.Z), 2))
    c[fam.node_vertex] = fam.exact_nodes(S, 0.0)
    assert np.abs(c - fam.Z @ S).max() <= 1e-9 * np.abs(c).max()


def test_member_seeds_recover_a_member_and_refuse_a_pattern_off_the_family():
    fam, S = _member(20, 16, seed=1)
    X = fam.nodes(S, 0.8)
    got = fam.member_seeds(X, 0.8)
    assert got is not None
    assert np.abs(got - S).max() <= 1e-9 * np.abs(S).max()
    Y = X.copy()
    Y[len(Y) // 2] += 1e-6  # one interior node off the family: the seed tiles alone cannot see it
    assert fam.member_seeds(Y, 0.8) is None
    full, gap = fam.fit(Y, 0.8)
    assert gap > 0.0 and np.abs(full - S).max() <= 1e-5


def test_seeds_for_grid_by_the_core_normal_equations_is_the_least_squares_fit(monkeypatch):
    fam, S = _member(12, 10, seed=2)
    rng = np.random.default_rng(5)
    grid = fam.Z @ S + 0.02 * rng.standard_normal((len(fam.Z), 2))
    lstsq, *_ = np.linalg.lstsq(fam.Z, grid, rcond=None)
    assert np.array_equal(fam.seeds_for_grid(grid), lstsq)  # at or below EXACT_GRID: lstsq itself
    monkeypatch.setattr(F, "EXACT_GRID", 0)
    assert np.array_equal(
        fam.seeds_for_grid(grid), lstsq
    )  # not asked: lstsq (a minimax finish may follow)
    normal = fam.seeds_for_grid(grid, normal=True)
    assert not np.array_equal(normal, lstsq)  # the other route
    assert np.abs(normal - lstsq).max() <= 1e-10 * np.abs(lstsq).max()


@pytest.mark.parametrize("large", [False, True])
def test_translations_are_y_s(monkeypatch, large):
    fam, S = _member(9, 11, seed=4)
    if large:  # the tiles' route: (τ S)[tile] - σ Zn S
        monkeypatch.setattr(F, "LARGE_GRID", 0)
    got = fam.translations(S, (fam.Z @ S)[fam.node_vertex])
    assert np.abs(got - fam.Y @ S).max() <= 1e-12 * np.abs(fam.Y @ S).max()
