"""Deployment of kagome patterns: the elastic path, its spring energy E(t), plot and GIF."""

from __future__ import annotations

import json

import numpy as np
import pytest
from fabkiri.errors import CheckFailed
from fabkiri.mechanics.contract import with_contracted_states
from fabkiri.mechanics.deploy import deployment_path
from fabkiri.mechanics.energy import springs
from fabkiri.pattern import io
from fabkiri.pattern.geometry import wrap_angle
from fabkiri.pattern.kagome import standard_kagome


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


def test_deploy_command_writes_energy_plot_and_gif(tmp_path, run_cli):
    src = tmp_path / "k.json"
    io.write_pattern(with_contracted_states(standard_kagome(3, 4, angle_deg=45.0)), src)
    out = tmp_path / "dep"
    code, _, err = run_cli("deploy", src, "--steps", "12", "--plot", "--gif", "--gif-frames", "7",
                           "--no-frames", "-o", out)
    assert code == 0, err
    assert (out / "energy.png").stat().st_size > 1000 and (out / "deploy.gif").stat().st_size > 1000
    rows = np.loadtxt(out / "energy.csv", delimiter=",", skiprows=1, ndmin=2)
    assert len(rows) >= 13 and np.abs(rows[:, 1]).max() <= 1e-20
    summary = json.loads((out / "deploy.json").read_text())
    assert summary["path"] == "elastic" and summary["collision_free"]
