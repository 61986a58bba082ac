"""The reconfigurable tube family is locally the rigid-deployable one (docs/tubes.md, "Why no cone")."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.linalg
from fabkiri.design.quad import constraints as C
from fabkiri.design.tube import periodic as P
from fabkiri.design.tube import rank as TR
from fabkiri.design.tube import solve as TS
from fabkiri.pattern.kinds.periodic.sheet import seam_map


def _problem(rows, cols):
    return TS._TubeProblem(
        TS.TubeRequest(rows, cols, P.parse_tube_target(f"cylinder:{cols * 10},{rows * 10}"))
    )


def test_free_seam_rows_match_finite_differences():
    """Columns over (x, β, τ): the residual x_copy - R(β) x_first - τ differentiated numerically."""
    prob = _problem(4, 6)
    x = prob.std.nodes + 0.05 * np.random.default_rng(0).normal(size=prob.std.nodes.shape)
    pairs = prob.seam.node_pairs(prob.st.tiles)
    beta = seam_map(x[prob.st.tiles], prob.seam).rotation
    tau = np.array([0.3, -0.2])

    def res(z):
        xx, b, t = z[:-3].reshape(-1, 2), z[-3], z[-2:]
        R = np.array([[np.cos(b), -np.sin(b)], [np.sin(b), np.cos(b)]])
        return (xx[pairs[:, 1]] - xx[pairs[:, 0]] @ R.T - t).ravel()

    z = np.concatenate([x.ravel(), [beta], tau])
    fd = np.stack([(res(z + e) - res(z - e)) / 2e-6 for e in 1e-6 * np.eye(z.size)], -1)
    J = TR.free_seam_rows(prob.seam, prob.st, x).toarray()
    assert np.abs(J - fd).max() < 1e-7


def _dims_at(rows, cols, seed=None):
    prob = _problem(rows, cols)
    x = prob.std.nodes.copy()
    if seed is not None:  # a generic tube: a perturbed sheet projected onto the equalities
        start = prob.X0 + 0.05 * np.random.default_rng(seed).normal(size=prob.X0.shape)
        x, eq_max, _ = TS._project(prob, start, 1e-12, 60)
        assert eq_max <= 1e-12
        assert np.abs(x - prob.X0).max() > 1e-2  # really somewhere else than the standard tube
    return TR.family_dimensions(prob.st, prob.seam, x)


@pytest.mark.slow
@pytest.mark.parametrize(
    "rows, cols, seed",
    [
        (4, 6, None),
        (4, 6, 1),
        pytest.param(6, 8, None, marks=pytest.mark.slow),
        pytest.param(6, 8, 2, marks=pytest.mark.slow),
    ],
)
def test_hinge_sums_do_not_cut_the_tube_family(rows, cols, seed):
    """Adding the rigidity rows leaves the tube family's rank unchanged (same tangent space), while the
    same rows cut the planar family (2(M+N)+5 against 2(M+N)+2: docs/algorithm.md#reconfigurability)
    and the family with only closed state 1 a cylinder (its extra direction turns the deployed seam: a cone)."""
    d = _dims_at(rows, cols, seed)
    for fam in d.values():
        assert fam["gap"] > 1e6  # a clear numerical rank
    assert d["planar_rigid"]["rank"] - d["planar"]["rank"] == 3
    assert d["planar"]["dimension"] == 2 * (rows + cols + 1) + 5 + 3  # + the 3 rigid motions
    assert d["tube_closed1_rigid"]["rank"] > d["tube_closed1"]["rank"]
    assert d["tube_rigid"]["rank"] == d["tube"]["rank"]
    assert d["tube"]["dimension"] == d["tube_closed1"]["dimension"] - 1
    if seed is None:  # the dimension test's shortcut (the tube family alone) gives the same figure
        assert _tube_dimension(rows, cols) == d["tube"]["dimension"]


def test_tube_family_dimension_depends_on_columns_only():
    """Measured: the tube family's dimension (4 similarities included) grows with the columns around and
    not with the rows (docs/tubes.md table)."""
    dims = {rc: _tube_dimension(*rc) for rc in [(4, 6), (8, 6), (4, 10)]}
    assert dims[(4, 6)] == dims[(8, 6)] < dims[(4, 10)]


def _tube_dimension(rows, cols):
    """``family_dimensions(...)["tube"]["dimension"]`` at the standard tube, without the other five families."""
    prob = _problem(rows, cols)
    J = TR.tube_jacobian(prob.st, prob.seam, prob.std.nodes.copy(), (1, 2), False)
    rank, gap = TR._rank(J)
    assert gap > 1e6  # a clear numerical rank
    return J.shape[1] - rank


def test_generic_tube_is_rigid_and_its_deployed_seam_does_not_turn():
    """The consequence, on a projected tube: hinge sums vanish and no tangent direction of the tube family
    turns the deployed seam."""
    prob = _problem(4, 6)
    start = prob.X0 + 0.05 * np.random.default_rng(1).normal(size=prob.X0.shape)
    x = TS._project(prob, start, 1e-12, 60)[0]
    assert np.abs(C.hinge_sums(prob.st, prob.st.n_nodes)(x)[0]).max() < 1e-10
    assert abs(seam_map(x[prob.st.tiles], prob.seam).rotation) < 1e-10
    beta = x.size  # the deployed seam's turn, in the Jacobian's columns
    for closed, turns in [((1,), True), ((1, 2), False)]:
        null = scipy.linalg.null_space(
            TR.tube_jacobian(prob.st, prob.seam, x, closed).toarray(), rcond=1e-10
        )
        assert (np.abs(null[beta]).max() > 1e-3) == turns


@pytest.mark.slow
@pytest.mark.parametrize(
    "spec, seed, amp", [("cone:18,9,56.6", 0, 0.0), ("cone:16,11,56.6", 2, 0.1)]
)
def test_a_cone_sheet_projects_onto_a_rigid_cylinder_when_the_seam_is_free(spec, seed, amp):
    """Globally, not only near the standard tube: a sheet laid on a cone's unrolled sector (deployed seam
    turned by 0.5-1 rad), projected onto the tube family with the deployed seam map left free, lands on a
    rigid-deployable cylinder: the projection itself turns the seam back to 0."""
    prob = TS._TubeProblem(TS.TubeRequest(4, 6, P.parse_tube_target(spec)))
    start = prob.X0 + amp * np.random.default_rng(seed).normal(size=prob.X0.shape)
    assert seam_map(start[prob.st.tiles], prob.seam).rotation > 0.5
    x, eq_max, beta, _ = TR.project_free(prob.st, prob.seam, start)
    assert eq_max <= 1e-12
    assert abs(beta) < 1e-10
    assert np.abs(C.hinge_sums(prob.st, prob.st.n_nodes)(x)[0]).max() < 1e-10
    assert (
        C.non_overlap(prob.st, prob.st.n_nodes)(x)[0].min() > 0.05
    )  # a proper sheet, not collapsed
