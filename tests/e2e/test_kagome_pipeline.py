"""The kagome kind through the pattern-level pipeline: new, info, verify, export, import."""

from __future__ import annotations

import json
from dataclasses import replace

import numpy as np
import pytest
from fabkiri.exchange import pattern_json as io
from fabkiri.exchange.fold import fold_text, loads_fold
from fabkiri.mechanics.contract import with_contracted_states
from fabkiri.pattern.kinds.kagome.lattice import standard_kagome
from fabkiri.pattern.residuals import state_residuals
from fabkiri.verify import verify_pattern
from scipy.optimize import least_squares


def test_new_kagome_info_verify_and_every_export_round_trip(tmp_path, run_cli):
    p = tmp_path / "k.json"
    code, _, err = run_cli(
        "new",
        "--lattice",
        "kagome",
        "--tiles",
        "7x5",
        "--tile-size",
        "12",
        "--angle",
        "40",
        "-o",
        p,
    )
    assert code == 0 and "standard kagome 7x5" in err and "ψ = 40°" in err, err
    pat = io.read_pattern(p)
    assert pat.kind == "kagome" and sorted(pat.contracted) == [1, 2]
    assert json.loads(p.read_text())["kind"] == "kagome"
    code, out, _ = run_cli("info", p, "--json", "--check")
    info = json.loads(out)
    assert code == 0 and info["closes_both"] and (info["tiles"], info["holes"]) == (35, 9)
    assert info["hinge_sum_max_rad"] is None  # the quad rigid test does not apply
    for s in info["states"]:
        assert s["max_closure_rel"] <= 1e-12 and s["edge_pair_max_mm"] <= 1e-12 * 12
    code, out, _ = run_cli("verify", p, "--exact", "--json")
    rep = json.loads(out)
    assert code == 0, [c for c in rep["checks"] if not c["ok"]]
    # OBJ of all three states back into a pattern with the same tiles and both states
    objs = []
    for state in ("deployed", "1", "2"):
        o = tmp_path / f"s{state}.obj"
        assert run_cli("export", p, "--state", state, "-o", o)[0] == 0
        objs.append(o)
    back = tmp_path / "back.json"
    code, _, err = run_cli("import", objs[0], "--contracted", objs[1], objs[2], "-o", back)
    assert code == 0, err
    again = io.read_pattern(back)
    assert again.kind == "kagome" and np.array_equal(again.tiles, pat.tiles)
    for s in (1, 2):
        assert np.abs(again.contracted[s] - pat.contracted[s]).max() <= 1e-12 * 12
    assert run_cli("verify", back, "--exact")[0] == 0
    # FOLD: the face arity names the kind
    f = loads_fold(fold_text(pat))
    assert f.kind == "kagome" and np.abs(f.nodes - pat.nodes).max() == 0.0
    assert np.abs(f.contracted[2] - pat.contracted[2]).max() <= 1e-12 * 12


def test_pattern_json_round_trip_is_byte_stable():
    pat = with_contracted_states(standard_kagome(4, 4, angle_deg=20.0))
    text = io.dumps(pat)
    back = io.loads(text)
    assert back.kind == "kagome" and io.dumps(back) == text


def _break_one_hole(state_kept: int, rel: float = 0.1):
    """A 3x4 kagome whose nodes are moved so every constraint of ``state_kept`` holds exactly while
    one fold pair of hole 0 in the other state differs by ``rel`` tile sizes (its edges unequal)."""
    p = standard_kagome(3, 4, angle_deg=50.0)
    top = p.topology
    broken = 3 - state_kept
    fb = top.fold(broken)
    h = top.hole_hinges[0][fb.hole_folds[0]][0]
    a, b = fb.fold_ends[h]
    hn = top.hinge_node[h]
    fk = top.fold(state_kept)

    def residuals(v):
        x = v.reshape(-1, 2)
        H = x[top.hinge_node]
        la = np.linalg.norm(x[fk.fold_ends[:, 0]] - H, axis=1)
        lb = np.linalg.norm(x[fk.fold_ends[:, 1]] - H, axis=1)
        unequal = np.linalg.norm(x[a] - x[hn]) - np.linalg.norm(x[b] - x[hn]) - rel * p.tile_size
        return np.r_[la - lb, state_residuals(p, state_kept, x).rings, unequal]

    sol = least_squares(
        residuals, p.nodes.ravel(), method="trf", xtol=1e-15, ftol=1e-15, gtol=1e-15
    )
    assert np.abs(residuals(sol.x)).max() <= 1e-12 * p.tile_size
    return replace(p, nodes=sol.x.reshape(-1, 2), lattice=None, name="hole 0 unequal")


@pytest.mark.parametrize("kept", [1, 2])
def test_a_hole_with_unequal_edges_fails_verify_in_the_state_it_breaks(kept, tmp_path, run_cli):
    q = _break_one_hole(kept)
    broken = 3 - kept
    r = state_residuals(q, broken)
    assert r.edge_pairs.max() >= 0.09 * q.tile_size  # 0.1 of the standard 10 mm
    rep = verify_pattern(q)
    failed = {c.name for c in rep.failed()}
    assert f"state {broken}: loop closure" in failed and f"state {broken}: edge pairs" in failed
    assert all(name.startswith(f"state {broken}:") for name in failed), failed
    # through the CLI: exit 1, the failure names the broken state only
    src = tmp_path / "broken.json"
    io.write_pattern(q, src)
    code, out, err = run_cli("verify", src, "--exact")
    assert code == 1 and f"state {broken}: loop closure" in err and f"state {kept}:" not in err


@pytest.mark.slow
@pytest.mark.xdist_group("kagome-heart-6x11-120")  # shares its design (shared_kagome_designs)
def test_design_kagome_heart_is_written_but_fails_naming_the_shape(
    tmp_path, run_cli, shared_kagome_designs
):
    out = tmp_path / "h.json"
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
        out,
    )
    # the heart is not matched to 2 % on this lattice (docs/kagome.md): the design is written, closed
    # in both states without overlaps, and the verdict names the shape
    assert code == 1 and "shape missed" in err and "FAIL target shape" in err, err
    p = io.read_pattern(out)
    assert p.kind == "kagome" and p.design["valid"] is False
    assert p.design["report"]["max_equality_residual"] <= 1e-10
    assert {c.name for c in verify_pattern(p).failed()} == {"target shape"}


def test_design_kagome_refuses_quad_only_options(tmp_path, run_cli):
    code, _, err = run_cli(
        "design", "--lattice", "kagome", "--tiles", "6x10", "--rigid", "-o", tmp_path / "x.json"
    )
    assert code == 2 and "--rigid is not available for kagome designs" in err
    assert not (tmp_path / "x.json").exists()


@pytest.mark.slow
@pytest.mark.xdist_group("kagome-circle-6x11-120")  # shares its design (shared_kagome_designs)
def test_design_kagome_circle_meets_every_check(tmp_path, run_cli, shared_kagome_designs):
    out = tmp_path / "c.json"
    # 6x11: both mirrors imposed (9x15 circle at 180 mm misses: 2.88 %, docs/kagome.md)
    code, _, err = run_cli(
        "design",
        "--lattice",
        "kagome",
        "--tiles",
        "6x11",
        "--target",
        "circle",
        "--size",
        "120",
        "-o",
        out,
    )
    assert code == 0 and "shape met" in err and "verify: pass" in err, err
    code, _, err = run_cli("verify", out, "--exact")
    assert code == 0, err
