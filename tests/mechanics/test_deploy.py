"""Deployment paths: the exact rigid path, the driven elastic path, the collision check."""

from __future__ import annotations

import numpy as np
import pytest
from fabkiri.errors import CheckFailed, InputError
from fabkiri.exchange.obj import import_obj
from fabkiri.exchange.pattern_json import read_pattern
from fabkiri.mechanics import adopt_state_labels, contract
from fabkiri.mechanics.deploy import (
    closed_states,
    collisions,
    deployment_path,
    elastic_path,
    mechanism_split,
    place_rigid,
    rigid_path,
)
from fabkiri.mechanics.elastic import gap_angles
from fabkiri.mechanics.path import path_parameter, tile_angles
from fabkiri.pattern import geometry, standard_pattern
from hypothesis import given, settings
from hypothesis import strategies as st

from ..conftest import REPO, TEMPLATES
from ..designs import reconfigurable_design


def ref(name: str):
    """A reference OBJ beside the checkout, or beside the folder of worktrees holding it."""
    for root in (REPO.parent, REPO.parent.parent):
        path = root / "shared" / "reference" / "additive-kirigami" / f"Example_{name}.obj"
        if path.exists():
            return path
    pytest.skip(f"reference data not available: Example_{name}.obj")


ZERO = 1e-12


def compact_reconfigurable():
    return adopt_state_labels(
        import_obj(
            ref("compact_reconfigurable_design"),
            [ref("compact_reconfigurable_contracted1"), ref("compact_reconfigurable_contracted2")],
        )
    )


def _checkerboard_rotation(pattern, corners):
    """Independent check of the rigid motion: (per-colour spread, ω per frame).

    Each tile's rotation from state 1 (Kabsch on its own corners); the two
    colour classes must turn by γ ± ω with one ω for all tiles.
    """
    s1 = contract(pattern, 1).corners
    rho = np.unwrap(tile_angles(s1[None], corners), axis=0)  # (F, T), continuous in time
    color = pattern.topology.tile_color
    spread = max(np.ptp(rho[:, color == c], axis=1).max() for c in (0, 1))
    omega = np.abs(rho[:, color == 0].mean(1) - rho[:, color == 1].mean(1)) / 2
    return spread, omega


@pytest.mark.parametrize(
    "make",
    [
        lambda: standard_pattern(8, 8, tile_size=10.0),
        lambda: standard_pattern(5, 7, tile_size=3.0, angle_deg=30.0),
        lambda: reconfigurable_design(6, 6, seed=3, amplitude=0.3, waves=3, rigid=True),
        lambda: read_pattern(
            TEMPLATES / "patterns" / "circle-8x8-rigid.json"
        ),  # from `fabkiri design --rigid`
    ],
    ids=["standard-8x8", "standard-5x7-30deg", "rigid-design-6x6", "solver-circle-8x8-rigid"],
)
def test_rigid_path_zero_energy_uniform_checkerboard_no_collision(make):
    p = make()
    path = rigid_path(p, steps=40)
    L = p.tile_size
    assert path.kind == "rigid" and path.n_frames == 41
    assert path.energy.max() <= ZERO
    assert path.hinge_gap.max() <= 1e-9 * L
    spread, omega = _checkerboard_rotation(p, path.corners)
    assert spread <= 1e-9
    assert omega[0] <= 1e-12 and abs(omega[-1] - np.pi / 2) <= 1e-9
    assert (np.diff(omega) > 0).all()  # grows monotonically 0 -> π/2
    assert path.rotation_spread.max() <= 1e-9  # the module's own figure agrees
    # it passes through the three states
    for name, d in path.state_mismatch.items():
        assert d <= 1e-9 * L, name
    assert path.collisions.collision_free() and not path.collisions.self_intersecting


def test_rigid_path_deployed_angle_is_the_design_angle():
    p = standard_pattern(4, 4, angle_deg=30.0)
    path = rigid_path(p, steps=10)
    assert path.omega_deployed == pytest.approx(np.radians(30.0), abs=1e-12)
    # a non-standard rigid design deploys at its own ω, not π/4
    q = reconfigurable_design(6, 6, seed=3, amplitude=0.3, waves=3, rigid=True)
    assert abs(rigid_path(q, steps=4).omega_deployed - np.pi / 4) > 1e-3


def test_elastic_path_on_a_rigid_design_is_the_rigid_path():
    p = reconfigurable_design(6, 6, seed=3, amplitude=0.3, waves=3, rigid=True)
    r = rigid_path(p, steps=20)
    e = elastic_path(p, steps=20)
    assert e.energy.max() <= ZERO
    worst = max(geometry.aligned_distance(a, b) for a, b in zip(r.corners, e.corners))
    assert worst <= 1e-9 * p.tile_size


def _assert_reconfigurable_landscape(path, L):
    """Zero at the three states, barriers next to both closed states, a zero-energy middle."""
    marks = path.mark_frames()
    for name, f in marks.items():
        assert path.energy[f] <= ZERO, name
        assert path.state_mismatch[name] <= 1e-9 * L, name
    assert path.solver["unconverged_steps"] == 0
    t, e = path.t, path.energy
    assert len(path.elastic_segments) == 2
    (a1, b1), (a2, b2) = path.elastic_segments
    assert a1 == 0.0 and b2 == 1.0 and b1 < 0.25 < 0.75 < a2  # next to the closed states
    inside = path.in_segments()
    assert inside.sum() >= 8
    assert (e[inside] > 1e3 * ZERO).all()  # E > 0 wherever the tiles leave the mechanism
    assert e[~inside].max() <= ZERO  # the mechanism-like middle
    assert e[(t > 0) & (t < b1)].max() > 1e3 * ZERO and e[(t > a2) & (t < 1)].max() > 1e3 * ZERO


@pytest.mark.slow
def test_reference_compact_reconfigurable_elastic_landscape():
    p = compact_reconfigurable()
    path = deployment_path(p, steps=40)  # auto: not rigid-deployable -> elastic
    assert path.kind == "elastic" and path.driver == "rotations"
    _assert_reconfigurable_landscape(path, p.tile_size)
    # its bow-tie tile 2 is named, and every overlap involves tile 1 (non-convex, 195° at one corner)
    # or tile 2; tile 1 overlaps tile 3 in the stored state-1 file as well, inside the bow-tie's lobe
    c = path.collisions
    assert 2 in c.self_intersecting
    assert c.overlaps and all({o.tile_a, o.tile_b} & {1, 2} for o in c.overlaps)
    assert not c.collision_free() and c.collision_free(exclude=[1, 2])
    assert {(o.tile_a, o.tile_b) for o in c.overlaps if 0 < o.frame < path.n_frames - 1} == {(1, 2)}


def test_generated_reconfigurable_design_elastic_landscape():
    p = reconfigurable_design(6, 6, seed=2, amplitude=0.3, waves=3)
    from fabkiri.pattern.residuals import hinge_sums

    assert np.abs(hinge_sums(p)).max() > 1e-4  # genuinely not rigid-deployable
    with pytest.raises(CheckFailed, match="not rigid-deployable"):
        rigid_path(p)
    path = elastic_path(p, steps=20)
    _assert_reconfigurable_landscape(path, p.tile_size)
    assert path.collisions.collision_free()
    # in the middle the tiles follow the uniform checkerboard rotation about the deployed state
    mid = (path.t > 0.1) & (path.t < 0.9)
    assert np.ptp(path.rotation_spread[mid]) <= 1e-9


def test_mechanism_split_of_a_rigid_design_has_no_residual():
    p = reconfigurable_design(6, 6, seed=3, amplitude=0.3, waves=3, rigid=True)
    split = mechanism_split(p, closed_states(p))
    for s in (1, 2):
        assert np.abs(split[s].residual).max() <= 1e-9
        assert split[s].closing == pytest.approx(1.0, abs=1e-9)
    # the deployed state sits |a1| from state 1 and |a2| from state 2 along the rigid path
    assert abs(split[1].amplitude) + abs(split[2].amplitude) == pytest.approx(np.pi / 2, abs=1e-9)
    assert abs(split[1].amplitude) == pytest.approx(rigid_path(p, steps=2).omega_deployed, abs=1e-9)


def test_mechanism_is_zero_energy_until_the_first_gap_closes():
    p = reconfigurable_design(6, 6, seed=2, amplitude=0.3, waves=3)
    split = mechanism_split(p, closed_states(p))
    eps = np.where(p.topology.tile_color == 0, 1.0, -1.0)
    top = p.topology
    A, B = top.hinge_tiles.T
    cA, cB = top.hinge_corner.T
    for s in (1, 2):
        m = split[s]
        assert 0.5 < m.closing < 1.0 and np.abs(m.residual).max() > 1e-3
        lam = np.array([0.0, 0.5, m.closing, 1.0])
        placed = place_rigid(p, p.corners(), eps, lam * m.amplitude)
        # hinges stay closed all along: the holes are parallelograms
        assert np.abs(placed[:, A, cA] - placed[:, B, cB]).max() <= 1e-9 * p.tile_size
        gaps = gap_angles(p, placed)
        gap_min = np.minimum(gaps, 2 * np.pi - gaps).min(axis=(1, 2))
        assert gap_min[0] > 1e-3 and gap_min[2] <= 1e-9  # a gap folds flat exactly at `closing`
        assert collisions(placed[:3], p.tile_size).collision_free()
        assert not collisions(placed[3:], p.tile_size).collision_free()  # past it, tiles overlap


def test_coarse_steps_follow_the_same_branch():
    p = compact_reconfigurable()
    fine = elastic_path(p, steps=20)
    coarse = elastic_path(p, steps=4)  # sub-steps keep the continuation on the branch
    assert coarse.solver["solves"] > coarse.n_frames
    shared = 0
    for f, tf in enumerate(coarse.t):
        g = np.flatnonzero(np.isclose(fine.t, tf, rtol=0, atol=1e-12))
        if len(g):
            shared += 1
            assert (
                geometry.aligned_distance(coarse.corners[f], fine.corners[g[0]])
                <= 1e-9 * p.tile_size
            )
    assert shared >= 5


def test_solver_circle_design_landscape():
    """The solver's non-rigid circle. As committed it is within 1e-8 rad of rigid-deployable (hinge sums
    7e-9 rad): its mechanism reaches both closed states to ~1e-8 rad and the whole path has E <= 1e-12.
    Should a regenerated template be genuinely non-rigid, it must show the barriers instead."""
    from fabkiri.pattern.residuals import hinge_sums

    p = read_pattern(TEMPLATES / "patterns" / "circle-8x8.json")
    path = deployment_path(p, steps=20)
    assert path.kind == "elastic"
    if np.abs(hinge_sums(p)).max() < 1e-6:
        assert path.energy.max() <= ZERO
        for name, d in path.state_mismatch.items():
            assert d <= 1e-9 * p.tile_size, name
        assert path.rotation_spread.max() <= 1e-6
    else:
        _assert_reconfigurable_landscape(path, p.tile_size)
    assert path.collisions.collision_free()


def test_tips_driver_reaches_the_three_states():
    p = reconfigurable_design(5, 5, seed=1, amplitude=0.2)
    path = elastic_path(p, steps=20, driver="tips")
    assert path.driver == "tips" and not path.elastic_segments
    for name, f in path.mark_frames().items():
        assert path.energy[f] <= ZERO, name
        assert path.state_mismatch[name] <= 1e-9 * p.tile_size, name
    # linear tip motion is not the mechanism: the tiles strain all along
    inside = np.setdiff1d(np.arange(path.n_frames), list(path.mark_frames().values()))
    assert (path.energy[inside] > 1e3 * ZERO).all()


def test_non_closing_pattern_has_no_path():
    p = adopt_state_labels(import_obj(ref("non-contractible_design")))
    with pytest.raises(CheckFailed, match="does not close in state"):
        elastic_path(p, steps=4)


def test_bad_parameters():
    p = standard_pattern(2, 2)
    with pytest.raises(InputError):
        elastic_path(p, steps=4, driver="wind")
    with pytest.raises(InputError):
        deployment_path(p, steps=4, path="teleport")
    with pytest.raises(InputError):
        path_parameter(1)
    assert path_parameter(5).tolist() == pytest.approx(np.linspace(0, 1, 7).tolist())
    assert 0.5 in path_parameter(7)


def test_collision_check_on_synthetic_tiles():
    sq = np.array([[0, 0], [1, 0], [1, 1], [0, 1]], float)
    touching = np.stack([sq, sq + [1, 0], sq + [1, 1]])  # shared edge, shared corner
    overlapping = np.stack([sq, sq + [0.75, 0.5], sq + [5, 5]])
    bowtie = np.array([[0, 0], [1, 1], [1, 0], [0, 1]], float) + [5, 5]
    frames = np.stack([touching, overlapping, np.stack([sq, sq + [3, 0], bowtie])])
    rep = collisions(frames, tile_size=1.0)
    assert [(o.frame, o.tile_a, o.tile_b) for o in rep.overlaps] == [(1, 0, 1)]
    assert rep.overlaps[0].area == pytest.approx(0.25 * 0.5)
    assert rep.self_intersecting == [2]
    assert not rep.collision_free() and rep.collision_free(exclude=[0])


@settings(max_examples=40, deadline=None)
@given(seed=st.integers(0, 10_000), spread=st.floats(0.5, 3.0))
def test_collision_screen_agrees_with_brute_force_overlay(seed, spread):
    """The separating-axis screen never hides an overlap that the exact overlay finds."""
    import shapely

    rng = np.random.default_rng(seed)
    n = 12
    centres = rng.uniform(0, spread * 3, size=(n, 2))
    ang = np.sort(rng.uniform(0, 2 * np.pi, size=(n, 4)), axis=1)  # CCW, mostly convex, some not
    rad = rng.uniform(0.3, 0.7, size=(n, 4))
    quads = centres[:, None] + rad[..., None] * np.stack([np.cos(ang), np.sin(ang)], -1)
    rep = collisions(quads[None], tile_size=1.0)
    polys = shapely.make_valid(shapely.polygons(quads))
    truth = {
        (i, j)
        for i in range(n)
        for j in range(i + 1, n)
        if shapely.area(shapely.intersection(polys[i], polys[j], grid_size=1e-11)) > 1e-9
    }
    assert set(rep.pairs()) == truth


@settings(max_examples=15, deadline=None)
@given(
    rows=st.integers(2, 6),
    cols=st.integers(2, 6),
    angle=st.floats(5.0, 85.0),
    size=st.floats(0.5, 50.0),
)
def test_rigid_path_of_any_standard_pattern(rows, cols, angle, size):
    p = standard_pattern(rows, cols, tile_size=size, angle_deg=angle)
    path = rigid_path(p, steps=8)
    assert path.energy.max() <= ZERO
    assert path.omega_deployed == pytest.approx(np.radians(angle), abs=1e-9)
    spread, omega = _checkerboard_rotation(p, path.corners)
    assert spread <= 1e-9 and abs(omega[-1] - np.pi / 2) <= 1e-9
    assert path.collisions.collision_free()
    # the elastic machinery agrees: no residual, the mechanism runs to both closed states
    split = mechanism_split(p, closed_states(p))
    assert all(split[s].closing == pytest.approx(1.0, abs=1e-9) for s in (1, 2))


@pytest.mark.slow
def test_solver_heart_design_is_genuinely_reconfigurable():
    """`fabkiri design --tiles 8x8 --target heart` (no --rigid): hinge sums far from π, so the
    landscape has the paper's barriers next to both closed states and a zero-energy middle."""
    from fabkiri.pattern.residuals import hinge_sums

    p = read_pattern(REPO / "tests" / "data" / "heart-8x8.json")
    assert np.abs(hinge_sums(p)).max() > 1e-2
    path = deployment_path(p, steps=20)
    assert path.kind == "elastic"
    _assert_reconfigurable_landscape(path, p.tile_size)
    assert path.collisions.collision_free()
