"""The rigid-deployable family with parallelogram holes (design/quad/rigid/offsets.py): an offset per hole."""

from __future__ import annotations

import numpy as np
import pytest
from fabkiri.design.quad import constraints as C
from fabkiri.design.quad.rigid.family import RigidFamily
from fabkiri.design.quad.rigid.offsets import OffsetFamily
from fabkiri.mechanics.contract import contract
from fabkiri.pattern.geometry import signed_areas
from fabkiri.pattern.kinds.quad.lattice import standard_pattern
from fabkiri.pattern.model import Pattern


def _lattice(m, n):
    std = standard_pattern(m, n, tile_size=1.0)
    st = C.Stencils.from_pattern(std)
    tree = std.topology.spanning_tree(0)
    rig = RigidFamily.build(st, tree)
    S0, _ = rig.fit(std.nodes, np.pi / 4)
    return std, st, OffsetFamily.build(st, tree), rig, rig.grid(S0)[rig.seeds]


@pytest.mark.parametrize("m, n", [(5, 5), (4, 7)])
def test_zero_offsets_are_the_rhombus_family(m, n):
    std, st, fam, rig, S = _lattice(m, n)
    y = fam.state1(S, np.zeros(fam.n_holes))
    S0, _ = rig.fit(std.nodes, np.pi / 4)
    assert np.abs(fam.at(y, np.pi / 4) - rig.nodes(S0, np.pi / 4)).max() < 1e-12


@pytest.mark.parametrize("m, n, seed", [(5, 5, 0), (6, 4, 1), (7, 7, 2)])
def test_members_with_offsets_are_rigid_parallelogram_patterns_that_close(m, n, seed):
    std, st, fam, _, S = _lattice(m, n)
    t = np.random.default_rng(seed).uniform(-0.4, 0.4, fam.n_holes)
    y = fam.state1(S, t)
    for psi in (0.3, np.pi / 4, 1.2):
        X = fam.at(y, psi)
        assert signed_areas(X[std.tiles]).min() > 0
        for f in (
            C.hole_opposite_sides(st, len(X)),
            C.notch_pairs(st, 1, len(X)),
            C.notch_pairs(st, 2, len(X)),
            C.hinge_sums(st, len(X)),
        ):
            assert np.abs(f.residual(X)).max() < 1e-12, f.name
    X = fam.at(y, np.pi / 4)
    # not rhombi: the offsets are real
    assert np.abs(C.edge_pairs(st, 1, len(X)).residual(X)).max() > 1e-3
    pat = Pattern(nodes=X, tiles=std.tiles, lattice=std.lattice, parity=0)
    for s in (1, 2):
        assert contract(pat, s).max_closure < 1e-12
    # closed state 2 is the member at ψ = π/2: its tiles are the contraction's, up to a rigid motion
    c2 = contract(pat, 2).corners
    x2 = fam.at(y, np.pi / 2)[std.tiles]
    d = c2.reshape(-1, 2) - c2.reshape(-1, 2).mean(0), x2.reshape(-1, 2) - x2.reshape(-1, 2).mean(0)
    assert np.allclose(
        np.sort(np.linalg.norm(d[0], axis=1)), np.sort(np.linalg.norm(d[1], axis=1)), atol=1e-10
    )


def test_jacobians_match_finite_differences():
    std, st, fam, _, S = _lattice(5, 6)
    rng = np.random.default_rng(3)
    t = rng.uniform(-0.3, 0.3, fam.n_holes)
    y, Z, Dt = fam.state1(S, t, jac=True)
    h = 1e-6
    for k in rng.choice(fam.n_holes, 4, replace=False):
        tp, tm = t.copy(), t.copy()
        tp[k] += h
        tm[k] -= h
        fd = (fam.state1(S, tp) - fam.state1(S, tm)) / (2 * h)
        assert np.abs(fd - Dt[:, :, k]).max() < 1e-7
    for j in rng.choice(fam.n_seeds, 3, replace=False):
        Sp = S.copy()
        Sp[j, 1] += h
        fd = (fam.state1(Sp, t) - y)[:, 1] / h
        assert np.abs(fd - Z[:, j]).max() < 1e-7


def test_state_one_outline_does_not_depend_on_the_offsets():
    """Why a square in state 1 stays a linear equality on the seeds."""
    std, st, fam, rig, S = _lattice(6, 6)
    _, _, Dt = fam.state1(S, np.full(fam.n_holes, 0.2), jac=True)
    g = C.ClosedGrid.build(st, 1, 0)
    on_boundary = np.isin(rig.node_vertex, g.boundary)
    assert np.abs(Dt[on_boundary]).max() < 1e-12 and np.abs(Dt[~on_boundary]).max() > 1e-3


@pytest.mark.parametrize("m, n, seed", [(5, 5, 0), (4, 7, 1)])
def test_fixed_pattern_columns_equal_the_sliced_sum(m, n, seed):
    # A(t)'s dependent and seed columns on their fixed patterns: the same stored entries as (A0 + At)[:, cols]
    # (no stored zeros at t = 0, where the offset entries vanish), so the LU and the members are unchanged
    _, _, fam, _, _ = _lattice(m, n)
    dep, seeds = fam._blocks()
    for t in (np.zeros(fam.n_holes), np.random.default_rng(seed).uniform(-0.9, 0.9, fam.n_holes)):
        A = fam.matrix(t)
        for block, cols in ((dep, fam.dep), (seeds, fam.seeds)):
            want, got = A[:, cols].tocsc(), block.at(t)
            assert np.array_equal(want.indptr, got.indptr) and np.array_equal(
                want.indices, got.indices
            )
            assert np.array_equal(want.data, got.data)
