"""Deployment of kagome patterns: the elastic path, its spring energy E(t), plot and GIF."""

from __future__ import annotations

import json

import numpy as np
import pytest
from fabkiri.errors import CheckFailed
from fabkiri.exchange import pattern_json as io
from fabkiri.mechanics.contract import with_contracted_states
from fabkiri.mechanics.deploy import deployment_path
from fabkiri.mechanics.energy import springs
from fabkiri.pattern.geometry import wrap_angle
from fabkiri.pattern.kinds.kagome.lattice import standard_kagome


def test_triangles_carry_their_three_edges_as_springs():
    p = standard_kagome(2, 3)
    sp = springs(p)
    assert len(sp.pairs) == 3 * p.n_tiles
    assert np.abs(sp.rest - p.tile_size).max() <= 1e-12 * p.tile_size
    assert sp.energy(p.nodes.ravel()) == 0.0
    moved = p.nodes.copy()
    moved[0] += [0.1, 0.0]
    assert sp.energy(moved.ravel()) > 1e-6  # a distorted triangle costs energy


def test_standard_kagome_deploys_along_a_zero_energy_path_to_both_states():
    p = standard_kagome(4, 4, angle_deg=60.0)
    path = deployment_path(p, 20)
    assert path.kind == "elastic"  # the quad hinge-sum rigid family does not apply
    assert path.energy.max() <= 1e-20 and path.hinge_gap.max() <= 1e-9 * p.tile_size
    assert max(path.state_mismatch.values()) <= 1e-9 * p.tile_size
    assert path.collisions.collision_free()
    # up tiles turn by -120° and down tiles by +120° from state 1 to state 2 (through the open
    # kagome): a relative turn of 240°, i.e. -120°, the same at every hinge
    up = p.topology.tile_color == 0
    rel = wrap_angle(path.rotation[-1][up][:, None] - path.rotation[-1][~up][None, :])
    assert np.abs(np.abs(rel) - np.radians(120)).max() <= 1e-9
    with pytest.raises(CheckFailed, match="kagome pattern deploys on the elastic path"):
        deployment_path(p, 20, path="rigid")


@pytest.mark.slow
def test_deploy_command_writes_energy_plot_and_gif(tmp_path, run_cli):
    src = tmp_path / "k.json"
    io.write_pattern(with_contracted_states(standard_kagome(3, 4, angle_deg=45.0)), src)
    out = tmp_path / "dep"
    code, _, err = run_cli(
        "deploy",
        src,
        "--steps",
        "12",
        "--plot",
        "--gif",
        "--gif-frames",
        "7",
        "--no-frames",
        "-o",
        out,
    )
    assert code == 0, err
    assert (out / "energy.png").stat().st_size > 1000 and (out / "deploy.gif").stat().st_size > 1000
    rows = np.loadtxt(out / "energy.csv", delimiter=",", skiprows=1, ndmin=2)
    assert len(rows) >= 13 and np.abs(rows[:, 1]).max() <= 1e-20
    summary = json.loads((out / "deploy.json").read_text())
    assert summary["path"] == "elastic" and summary["collision_free"]


# --- the homotopy driver: designed (generic) kagome patterns -------------------------------------


def _generic(rows, cols, seed=5, step=0.02):
    """A generic point of the reconfigurable kagome family near the standard (not rigid-deployable:
    no checkerboard mechanism reaches its closed states)."""
    from dataclasses import replace

    import fabkiri.design.kagome.constraints as K

    p = standard_kagome(rows, cols, angle_deg=45.0)
    x = K.nearby_solution(p, (1, 2), seed=seed, step=step)
    return replace(p, nodes=x * p.tile_size, lattice=None, name=f"generic {rows}x{cols}")


def test_the_kind_chooses_the_homotopy_driver_through_the_registry():
    from fabkiri.mechanics.drivers.registry import path_driver
    from fabkiri.pattern.kinds.tessellation import tessellation

    p = standard_kagome(2, 3)
    assert tessellation("kagome").deploy_driver == "homotopy"
    assert tessellation("quad").deploy_driver == "rotations"
    assert path_driver("auto", p).name == "homotopy"
    assert deployment_path(p, 4).driver == "homotopy"


def test_a_third_kind_plugs_in_its_driver_by_name():
    """A kind names a registered driver (here a test driver registered from outside); `auto`
    follows it, with no change to the path code."""
    from dataclasses import replace

    from fabkiri.mechanics.drivers.homotopy import Homotopy
    from fabkiri.mechanics.drivers.registry import _DRIVERS, register_driver
    from fabkiri.pattern.kinds.tessellation import _KINDS, register, tessellation

    class Counting(Homotopy):
        name = "counting-test"
        calls = 0

        def constraints(self, pattern, states, t):
            type(self).calls += 1
            return super().constraints(pattern, states, t)

    register_driver(Counting())
    register(replace(tessellation("kagome"), kind="tri-test", deploy_driver="counting-test"))
    try:
        p = replace(standard_kagome(2, 3), kind="tri-test")
        path = deployment_path(p, 4)
        assert path.driver == "counting-test" and Counting.calls == 1
        assert max(path.state_mismatch.values()) <= 1e-9 * p.tile_size
    finally:
        _KINDS.members.pop("tri-test", None)
        _DRIVERS.members.pop("counting-test", None)


@pytest.mark.slow
@pytest.mark.parametrize("rows, cols", [(4, 4), (7, 5)])
def test_generic_kagome_design_deploys_through_all_three_states(rows, cols):
    """Measured (4x4 / 7x5, 20 steps): end frames within 5e-14 mm of the states, E there <= 2e-28,
    E_max 1.1e-4 / 2.4e-4 against 1.2e-3 / 2.5e-3 with the quad rotations driver."""
    p = _generic(rows, cols)
    path = deployment_path(p, 20)
    assert path.driver == "homotopy" and path.kind == "elastic"
    size = p.tile_size
    for name, f in path.mark_frames().items():
        assert path.state_mismatch[name] <= 1e-9 * size, name
        assert path.energy[f] <= 1e-20, name
    assert np.isfinite(path.energy).all() and path.energy.min() >= 0.0
    # generic: not a mechanism, so the interpolated motion strains the tiles between the states
    inside = np.setdiff1d(np.arange(path.n_frames), list(path.mark_frames().values()))
    assert (path.energy[inside] > 1e-12).all()
    assert path.hinge_gap.max() <= 1e-9 * size  # hinges are shared nodes: pins, never apart
    assert path.collisions.collision_free()
    s = path.solver
    assert s["unconverged_steps"] == 0 and s["mirrored_tiles_max"] == 0
    # a followed branch: no sub-step moves a node much more than the rigid blend does
    assert (
        s["largest_substep_move_tile_sizes"]
        <= 3.0 * s["rigid_blend_largest_substep_move_tile_sizes"]
    )
    rot = deployment_path(p, 20, driver="rotations")
    assert path.energy.max() < 0.5 * rot.energy.max()


def test_homotopy_driver_is_kind_agnostic_on_a_quad_design():
    from ..designs import reconfigurable_design

    p = reconfigurable_design(5, 5, seed=1, amplitude=0.2)
    path = deployment_path(p, 12, driver="homotopy")
    assert path.driver == "homotopy"
    for name, f in path.mark_frames().items():
        assert path.state_mismatch[name] <= 1e-9 * p.tile_size, name
        assert path.energy[f] <= 1e-20, name
    assert 0.0 < path.energy.max() < 1.0


@pytest.mark.slow
@pytest.mark.xdist_group("kagome-heart-6x11-120")  # shares its design (shared_kagome_designs)
def test_designed_kagome_pattern_deploys_or_reports_the_miss(
    tmp_path, run_cli, shared_kagome_designs
):
    """`design --lattice kagome` then `deploy`: E(t), plot and GIF; the path reaches the three
    states; overlaps (an earlier fit of the 6x10 heart overlapped itself deployed: 87 tile pairs) are
    reported with their figures and exit 1. The 6x11 heart: the design test_kagome_fit.py and the e2e
    tests make."""
    src = tmp_path / "heart.json"
    code, _, err = run_cli(
        "design",
        "--lattice",
        "kagome",
        "--tiles",
        "6x11",
        "--target",
        "heart",
        "--size",
        "120",
        "-o",
        src,
    )
    assert src.exists(), err
    out = tmp_path / "dep"
    code, _, err = run_cli(
        "deploy", src, "--plot", "--gif", "--gif-frames", "9", "--no-frames", "-o", out
    )
    assert (out / "energy.png").stat().st_size > 1000 and (out / "deploy.gif").stat().st_size > 1000
    s = json.loads((out / "deploy.json").read_text())
    rows = np.loadtxt(out / "energy.csv", delimiter=",", skiprows=1, ndmin=2)
    assert s["driver"] == "homotopy" and np.isfinite(rows[:, 1]).all() and rows[:, 1].min() >= 0
    assert s["energy_at_states"]["deployed"] <= 1e-20  # continued from the deployed state
    size = s["tile_size_mm"]
    # measured on an earlier 6x10 heart's fit (40 steps): every state within 4e-13 mm, E there <= 6e-28
    for name, d in s["state_mismatch_mm"].items():
        assert d <= 1e-9 * size, name
    assert max(s["energy_at_states"].values()) <= 1e-20
    assert s["solver"]["mirrored_tiles_max"] == 0 and s["solver"]["unconverged_steps"] == 0
    if s["collision_free"]:
        assert code == 0, err
    else:  # the fit's deployed state overlaps itself: reported, with figures, exit 1
        assert code == 1 and "tile overlaps" in err and "mm²" in err
        assert "misses" not in err


def test_orientation_term_derivatives_match_finite_differences():
    from fabkiri.mechanics.orientation import area_term
    from fabkiri.pattern.kinds.quad.lattice import standard_pattern

    for p in (standard_kagome(3, 4), standard_pattern(2, 3)):
        a = area_term(p)
        assert a.energy(p.nodes.ravel()) == 0.0
        x = p.nodes.ravel() + 0.3 * np.random.default_rng(0).standard_normal(p.nodes.size)
        h, eye = 1e-6, np.eye(len(x))
        g = np.array([(a.energy(x + h * e) - a.energy(x - h * e)) / (2 * h) for e in eye])
        Hf = np.array([(a.gradient(x + h * e) - a.gradient(x - h * e)) / (2 * h) for e in eye])
        assert np.abs(g - a.gradient(x)).max() <= 1e-7 * np.abs(g).max()
        H = a.hessian(x).toarray()
        assert np.abs(H - Hf.T).max() <= 1e-7 * np.abs(H).max() and (H == H.T).all()


def test_orientation_term_makes_a_mirrored_triangle_cost_energy():
    from fabkiri.mechanics.orientation import area_term

    p = standard_kagome(1, 1)
    sp, a = springs(p), area_term(p)
    mirrored = p.nodes * [-1.0, 1.0]  # same edge lengths, turned over
    assert sp.energy(mirrored.ravel()) <= 1e-28  # the springs cannot tell
    assert a.energy(mirrored.ravel()) == pytest.approx(4.0)  # area -A0: ((-A0 - A0)/A0)² = 4


@pytest.mark.slow
def test_homotopy_path_is_continuous_not_a_snap():
    """Finer sub-steps shrink the largest node move between two of them (a snap would not) and
    leave the frames where they were."""
    from fabkiri.mechanics.elastic import elastic_path

    p = _generic(4, 4)
    coarse = elastic_path(p, 8, max_increment=0.03)
    fine = elastic_path(p, 8, max_increment=0.01)
    a = coarse.solver["largest_substep_move_tile_sizes"]
    b = fine.solver["largest_substep_move_tile_sizes"]
    assert b <= 0.5 * a
    assert np.abs(coarse.nodes - fine.nodes).max() <= 1e-8 * p.tile_size
