"""Fold repair of a coarse-to-fine rigid start (``fabkiri.design.quad.rigid.unfold``)."""

from __future__ import annotations

import numpy as np
import pytest
from fabkiri.design.quad import constraints as C
from fabkiri.design.quad.rigid.family import RigidFamily
from fabkiri.design.quad.rigid.unfold import MARGIN, convex_member
from fabkiri.pattern import standard_pattern

from ..conftest import REPO


def _family(n):
    std = standard_pattern(n, n, tile_size=1.0)
    st = C.Stencils.from_pattern(std)
    fam = RigidFamily.build(st, std.topology.spanning_tree(0))
    return fam, fam.node_vertex[st.tiles]


def _corner_crosses(grid, quads):
    return _corner_crosses_q(grid[quads])


def _corner_crosses_q(q):
    e, f = np.roll(q, -1, 1) - q, np.roll(q, 1, 1) - q
    return e[..., 0] * f[..., 1] - e[..., 1] * f[..., 0]


def _unit_grid(n):
    gx, gy = np.meshgrid(np.arange(n + 1.0), np.arange(n + 1.0))
    return np.stack([gx, gy], -1).reshape(-1, 2)


def test_a_convex_member_is_left_alone():
    fam, quads = _family(6)
    grid = _unit_grid(6)
    S, info = convex_member(fam, quads, grid)
    assert info["ok"] and info["folded_cells"] == 0 and info["move_rel"] == 0.0
    assert np.allclose(S, fam.seeds_for_grid(grid), rtol=0, atol=1e-12)


def test_a_reflex_corner_without_a_fold_is_left_to_the_solver():
    fam, quads = _family(6)
    S_bad = fam.seeds_for_grid(_unit_grid(6))
    S_bad[1] += (0.0, 1.5)
    grid = fam.Z @ S_bad
    assert _corner_crosses(grid, quads).min() < 0.0
    S, info = convex_member(fam, quads, grid)
    assert info["ok"] and info["folded_cells"] == 0 and info["corners_below_margin"] >= 1
    assert np.allclose(S, S_bad, rtol=0, atol=1e-9)


@pytest.mark.parametrize("shift", [(2.5, 2.5), (1.8, 1.8)])
def test_a_folded_member_is_unfolded_to_the_margin(shift):
    """A corner seed pushed across its cell: the nearest member folds a cell; the repaired member has every
    corner of every cell above half the margin, and stays close to the folded grid."""
    fam, quads = _family(6)
    S_bad = fam.seeds_for_grid(_unit_grid(6))
    S_bad[0] += shift
    grid = fam.Z @ S_bad
    before = _corner_crosses(grid, quads)
    assert before.min() < 0.0  # the precondition: the start is not convex
    S, info = convex_member(fam, quads, grid)
    after = _corner_crosses(fam.Z @ S, quads)
    assert info["ok"] and info["corners_below_margin"] >= 1
    q = grid[quads]
    l2 = np.mean(
        0.5 * np.abs(_cross2(q[:, 2] - q[:, 0], q[:, 3] - q[:, 1]))
    )  # the margin's unit, mean cell area
    assert after.min() >= 0.5 * MARGIN * l2
    # the repair moves the grid less than the fold it undoes
    move = np.abs(fam.Z @ S - grid).max()
    assert move == pytest.approx(info["move_rel"] * np.sqrt(l2), rel=1e-9) and move < np.hypot(
        *shift
    )


@pytest.mark.slow
def test_the_leaf_svg_coarse_start_is_repaired_not_discarded():
    """The leaf outline at 32x32 rigid: the nearest member of the resampled 16x16 design folded 3 cells and
    the start was thrown away (13.26 % Hausdorff from rescaled); repaired, it is used, convex with margin."""
    from fabkiri.design.quad.solve import DesignRequest, design_problem
    from fabkiri.design.targets.lookup import load_target
    from fabkiri.pattern import geometry

    tgt = load_target(str(REPO / "bench" / "data" / "leaf.svg"), 100.0)
    prob = design_problem(DesignRequest(32, 32, tgt, rigid=True, init="coarse", outline=True))
    un = prob.coarse["unfold"]
    assert (
        un["folded_cells"] >= 1 and un["ok"]
    )  # the nearest member folded: the case this repair is for
    assert prob.coarse["used"] and prob.coarse["folded_tiles"] == 0
    assert geometry.signed_areas(prob.X0[prob.st.tiles]).min() > 0
    q = prob.rigid_family.grid(prob.start_member[0])[prob.rigid_family.node_vertex[prob.st.tiles]]
    assert _corner_crosses_q(q).min() > 0  # every start tile convex (the repair's margin)
    psi = RigidFamily.deployment_angle(prob.X0, prob.st)
    assert prob.rigid_family.fit(prob.X0, psi)[1] <= 1e-9  # still a member of the fine family


def _cross2(a, b):
    return a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]
