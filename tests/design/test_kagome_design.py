"""Kagome inverse-design constraints: Jacobians, ranks and the dimension of the families."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
from fabkiri.design.kagome import constraints as K
from fabkiri.pattern.kinds.kagome.lattice import standard_kagome
from fabkiri.pattern.residuals import state_residuals
from fabkiri.verify import verify_pattern


@pytest.mark.parametrize("state", [1, 2])
def test_family_jacobians_match_finite_differences(state):
    p = standard_kagome(3, 4, angle_deg=50.0)
    rng = np.random.default_rng(4)
    x = p.nodes / p.tile_size + 0.05 * rng.standard_normal(p.nodes.shape)
    for fam in K.families(p, (state,)):
        r, J = fam(x)
        assert np.array_equal(r, fam.residual(x))
        fd = np.zeros(J.shape)
        h = 1e-6
        for i in range(x.size):
            d = np.zeros(x.size)
            d[i] = h
            fd[:, i] = (
                fam.residual(x + d.reshape(x.shape)) - fam.residual(x - d.reshape(x.shape))
            ) / (2 * h)
        assert np.abs(J.toarray() - fd).max() <= 1e-7, fam.name


def test_families_vanish_exactly_where_the_pattern_closes():
    p = standard_kagome(4, 4, angle_deg=35.0)
    x = p.nodes / p.tile_size
    r, _ = K.stacked(K.families(p), x)
    assert np.abs(r).max() <= 1e-13
    # and they measure what the reported residuals measure
    for s in (1, 2):
        rings = K.ring_family(p, s).residual(x + 0.01)
        assert np.allclose(rings, state_residuals(p, s, x + 0.01).rings)


@pytest.mark.parametrize(
    "rows, cols", [(4, 4), pytest.param(7, 5, marks=pytest.mark.slow)]
)  # 4x4 in the quick loop
def test_reconfigurable_family_loses_one_equation_per_hole(rows, cols):
    """Both states' edge pairs chain the six edges of a hole around a cycle: one of the six
    equalities follows from the others. Nothing else is dependent at these sizes, so the family
    has dimension 2n - 3 - (2H + K) = 2F - K - 3 (F free corners)."""
    p = standard_kagome(rows, cols)
    top = p.topology
    H, Kh, F = top.n_hinges, top.n_holes, len(top.free_nodes)
    one = K.count(p, (1,))
    assert one.equations == one.rank == H + Kh  # contractibility alone: independent
    both = K.count(p, (1, 2))
    assert both.equations == 2 * (H + Kh) and both.rank == 2 * H + Kh
    assert both.dimension == 2 * F - Kh - 3
    # the same at two generic (non-symmetric) points of the family: it is a manifold there
    for seed in (1, 2):
        x = K.nearby_solution(p, (1, 2), seed=seed, step=0.01)
        assert np.abs(x - p.nodes / p.tile_size).max() > 1e-3  # really moved
        c = K.count(p, (1, 2), x)
        assert c.residual <= 1e-13 and c.rank == both.rank


def test_a_generic_reconfigurable_kagome_closes_in_both_states():
    p = standard_kagome(4, 4)
    x = K.nearby_solution(p, (1, 2), seed=5, step=0.01)
    q = replace(p, nodes=x * p.tile_size, lattice=None, name="generic")
    assert not verify_pattern(q).failed()
    # only contractible: state 2 breaks
    y = K.nearby_solution(p, (1,), seed=5, step=0.01)
    failed = {c.name for c in verify_pattern(replace(q, nodes=y * p.tile_size)).failed()}
    assert "state 2: loop closure" in failed and not any(n.startswith("state 1") for n in failed)


@pytest.mark.parametrize("rows, cols", [(4, 4), (7, 5), (6, 6)])
def test_the_kagome_linkage_is_a_mechanism_with_independent_hinges(rows, cols):
    """3(T - 1) - 2H degrees of freedom, i.e. 2R + C - 3 for the R x C lattice (the quad lattice
    is over-constrained instead)."""
    p = standard_kagome(rows, cols)
    top = p.topology
    m = K.linkage_mobility(p)
    assert m == 3 * (top.n_tiles - 1) - 2 * top.n_hinges == 2 * rows + cols - 3


@pytest.mark.slow
def test_16x16_family_dimension_is_the_same_at_the_standard_and_a_generic_point():
    p = standard_kagome(16, 16)
    top = p.topology
    std = K.count(p, (1, 2))
    x = K.nearby_solution(p, (1, 2), seed=3, step=0.003)
    gen = K.count(p, (1, 2), x)
    assert gen.residual <= 1e-13 and gen.rank == std.rank
    # beyond one length equality per hole, angle sums become dependent at this size
    assert std.rank == 2 * top.n_hinges + top.n_holes - _extra_dependent(16, 16)
    assert std.dimension == 2 * len(top.free_nodes) - top.n_holes - 3 + _extra_dependent(16, 16)


def _extra_dependent(rows: int, cols: int) -> int:
    """Angle sums dependent beyond one length equality per hole (a fit, docs/kagome.md)."""
    return max(rows - 3, 0) * max(cols - 6, 0) // 2


@pytest.mark.parametrize("rows, cols", [(3, 7), (5, 8), (8, 8), (6, 9), (4, 10)])
def test_reconfigurable_rank_beyond_six_columns(rows, cols):
    p = standard_kagome(rows, cols)
    top = p.topology
    c = K.count(p, (1, 2))
    assert c.rank == 2 * top.n_hinges + top.n_holes - _extra_dependent(rows, cols)
    assert c.dimension == 2 * len(top.free_nodes) - top.n_holes - 3 + _extra_dependent(rows, cols)


def test_the_fit_moves_along_the_family_and_lands_on_it():
    """One solve of the kagome fit (design/kagome/fit.py) without refinement: the equalities hold to
    rounding after the pull-back, and the tips come nearer the target than the start's."""
    from fabkiri.design.kagome import fit as KF
    from fabkiri.design.kagome import solve as KS
    from fabkiri.design.targets import lookup as TG

    std = standard_kagome(4, 5, tile_size=12.0)
    target = TG.circle().scaled_to(60.0)
    rows, x0, axes = KF.fit_rows(std, target)
    assert axes == ("y", "x")
    sol = KS.solve(rows, x0, max_iter=30)
    assert sol.on_family and sol.max_equality <= 1e-12
    x1, ok, _ = KS.pull_back(rows.eq, KS.land(rows, x0), max_iter=40)  # where the solve starts from
    s1 = rows.soft(x1, jac=False)
    assert ok and sol.soft_cost < 0.5 * s1 @ s1
    xp, ok, _ = KS.project(rows.eq, sol.x)
    assert ok and np.abs(K.stacked(rows.eq, xp)[0]).max() <= 1e-13


def test_a_solve_whose_steps_have_stalled_stops_before_its_cap():
    """The steps along the family stop once their last ``LM_STALL`` accepted steps lowered the soft cost
    by less than its share (the 4x5 circle's solve: 26 steps; it ran to the cap of 60 before)."""
    from fabkiri.design.kagome import fit as KF
    from fabkiri.design.kagome import solve as KS
    from fabkiri.design.targets import lookup as TG

    assert KS.stalled([1.0] * 11, 10, 1e-3) and not KS.stalled([1.0] * 10, 10, 1e-3)
    assert not KS.stalled([1.0] + [0.99] * 10, 10, 1e-3)
    std = standard_kagome(4, 5, tile_size=12.0)
    rows, x0, _ = KF.fit_rows(std, TG.circle().scaled_to(60.0))
    sol = KS.solve(rows, x0, max_iter=60)
    assert sol.on_family and sol.max_equality <= 1e-12 and sol.iterations < 60


@pytest.mark.parametrize("state", [1, 2])
def test_rigid_family_jacobians_match_finite_differences(state):
    p = standard_kagome(3, 4, angle_deg=50.0)
    x = p.nodes / p.tile_size + 0.05 * np.random.default_rng(2).standard_normal(p.nodes.shape)
    for fam in (K.alternating_sums(p), K.equal_gaps(p, state)):
        r, J = fam(x)
        fd = np.zeros(J.shape)
        for i in range(x.size):
            d = np.zeros(x.size)
            d[i] = 1e-6
            fd[:, i] = (fam(x + d.reshape(x.shape))[0] - fam(x - d.reshape(x.shape))[0]) / 2e-6
        assert np.abs(J.toarray() - fd).max() <= 1e-7, fam.name


@pytest.mark.parametrize(
    "rows, cols", [(4, 4), pytest.param(7, 5, marks=pytest.mark.slow)]
)  # 4x4 in the quick loop
def test_a_four_dimensional_counter_rotating_rigid_subfamily_exists(rows, cols):
    """Up tiles +ω, down tiles -ω: every hole's up-tile edges sum to zero and each state's folded
    gaps are equal. The family has dimension 4 (modulo rigid motions) whatever the size; its
    generic members close in both states and deploy along a zero-energy path."""
    from fabkiri.mechanics.deploy import deployment_path

    p = standard_kagome(rows, cols)
    fams = K.rigid_families(p)
    r, J = K.stacked(fams, p.nodes / p.tile_size)
    assert np.abs(r).max() <= 1e-13  # the standard lattice is in it (at every ψ)
    assert 2 * len(p.nodes) - K.numerical_rank(J) - 3 == 4
    x = K.nearby_solution(p, (1, 2), seed=7, step=0.02, fams=fams)
    assert np.abs(x - p.nodes / p.tile_size).max() > 0.05  # a different pattern
    _, Jg = K.stacked(fams, x)
    assert K.numerical_rank(Jg) == K.numerical_rank(J)
    q = replace(p, nodes=x * p.tile_size, lattice=None, name="rigid generic")
    assert not verify_pattern(q).failed()
    path = deployment_path(q, 20)
    assert path.energy.max() <= 1e-20 and path.collisions.collision_free()
    assert max(path.state_mismatch.values()) <= 1e-9 * p.tile_size


def test_a_pull_back_that_fails_never_leaves_the_family_further_than_its_start():
    """The 8x8 heart (a lattice of the wrong aspect): the landing from the initial guess stops with
    equalities at ~0.25, from where full Newton steps onto the family diverge (~1e11 in ten steps; the
    design was then written with nodes ~5e6 mm). A pull-back that fails gives the nearest point it
    reached: the design of one solve without refinement ends no further from the family than its initial
    guess, near the target."""
    from fabkiri.design.kagome import fit as KF
    from fabkiri.design.kagome import solve as KS
    from fabkiri.design.targets import lookup as TG

    target = TG.load_target("heart", None)
    span = np.ptp(standard_kagome(8, 8, tile_size=1.0).nodes, 0).max()
    std = standard_kagome(8, 8, tile_size=target.size / span)
    lo, hi = target.bbox
    rows, x0, _ = KF.fit_rows(std, target.transformed(1.0, -0.5 * (lo + hi)))
    x1 = KS.land(rows, x0)
    xp, ok, _ = KS.project(rows.eq, x1)
    assert np.abs(rows.equality_residuals(xp)).max() <= np.abs(rows.equality_residuals(x1)).max()
    d = KF.design(std, target, refine_steps=0)
    assert d.max_equality <= np.abs(rows.equality_residuals(x0)).max()
    assert np.abs(d.pattern.nodes).max() <= 2 * target.size
