"""``fabkiri deploy`` end to end: files, figures, determinism, errors."""

from __future__ import annotations

import csv
import io
import json

import numpy as np
import pytest
from fabkiri.exchange.pattern_json import read_pattern, write_pattern
from fabkiri.mechanics import with_contracted_states
from fabkiri.pattern import standard_pattern
from PIL import Image

from ..designs import reconfigurable_design
from ..mechanics.test_deploy import ref


def _read_csv(path):
    return list(csv.DictReader(io.StringIO(path.read_text())))


@pytest.mark.slow
def test_deploy_standard_writes_everything(run_cli, tmp_path):
    src = tmp_path / "std.json"
    write_pattern(with_contracted_states(standard_pattern(4, 4, tile_size=5.0)), src)
    out = tmp_path / "out"
    code, _, err = run_cli("deploy", src, "--steps", "9", "--gif", "--plot", "-o", out)
    assert code == 0, err
    assert "rigid path, 11 frames" in err and "collisions: none" in err
    rows = _read_csv(out / "energy.csv")
    assert len(rows) == 11 and {"t", "energy", "max_tile_energy"} <= set(rows[0])
    assert float(rows[0]["t"]) == 0 and float(rows[5]["t"]) == 0.5 and float(rows[-1]["t"]) == 1
    assert max(float(r["energy"]) for r in rows) <= 1e-12
    assert abs(float(rows[-1]["rotation_rad"]) - np.pi / 2) <= 1e-9
    summary = json.loads((out / "deploy.json").read_text())
    assert (
        summary["path"] == "rigid"
        and summary["collision_free"]
        and summary["rotation_spread_max_rad"] <= 1e-9
    )
    png = (out / "energy.png").read_bytes()
    assert png[:8] == b"\x89PNG\r\n\x1a\n"
    gif = Image.open(out / "deploy.gif")
    assert (
        gif.format == "GIF"
        and gif.n_frames == 11
        and 800 <= min(gif.size)
        and max(gif.size) <= 1000
    )
    assert (out / "deploy.gif").stat().st_size < 2_000_000
    frames = sorted((out / "frames").iterdir())
    assert len(frames) == 11
    last = read_pattern(frames[-1])
    assert np.array_equal(last.tiles, read_pattern(src).tiles)
    assert last.design["deployment"]["t"] == 1.0
    # the deployed frame is the design up to a rigid motion
    from fabkiri.pattern import geometry

    mid = read_pattern(frames[5])
    assert geometry.aligned_distance(mid.nodes, read_pattern(src).nodes) <= 1e-9 * 5.0


@pytest.mark.slow
def test_deploy_is_deterministic(run_cli, tmp_path):
    src = tmp_path / "d.json"
    write_pattern(reconfigurable_design(4, 4, seed=2, amplitude=0.2), src)
    outs = []
    for k in range(2):
        out = tmp_path / f"o{k}"
        code, _, err = run_cli("deploy", src, "--steps", "6", "--gif", "--plot", "-o", out)
        assert code == 0, err
        assert "elastic path (driver: rotations)" in err
        outs.append(out)
    for name in ("energy.csv", "deploy.json", "energy.png", "deploy.gif", "frames/frame-0003.json"):
        assert (outs[0] / name).read_bytes() == (outs[1] / name).read_bytes(), name


@pytest.mark.slow
def test_deploy_reference_check_fails_on_its_overlaps(run_cli, tmp_path):
    design = ref("compact_reconfigurable_design")
    out = tmp_path / "ref"
    code, _, err = run_cli("deploy", design, "--steps", "10", "--no-frames", "--check", "-o", out)
    assert code == 1
    assert "self-intersecting tiles [1, 2]" in err or "self-intersecting tiles [2]" in err
    assert "tile overlaps" in err and "between tiles" in err
    # the figures are still written: a failed check reports, it does not hide
    rows = _read_csv(out / "energy.csv")
    e = {float(r["t"]): float(r["energy"]) for r in rows}
    assert e[0.0] <= 1e-12 and e[0.5] <= 1e-12 and e[1.0] <= 1e-12
    summary = json.loads((out / "deploy.json").read_text())
    (a1, b1), (a2, b2) = summary["elastic_segments_t"]
    assert a1 == 0 and b1 < 0.25 and a2 > 0.75 and b2 == 1
    eps = 1e-9  # the segment ends are frames on the mechanism (E = 0)
    assert min(v for t, v in e.items() if 0 < t < b1 - eps) > 1e-9
    assert min(v for t, v in e.items() if a2 + eps < t < 1) > 1e-9
    assert max(v for t, v in e.items() if b1 <= t <= a2) <= 1e-12
    assert summary["energy_outside_segments_max"] <= 1e-12
    assert not (out / "frames").exists()


def test_deploy_bad_input_writes_nothing(run_cli, tmp_path):
    out = tmp_path / "x"
    code, _, err = run_cli("deploy", tmp_path / "missing.json", "-o", out)
    assert code == 2 and "no such file" in err and not out.exists()
    src = tmp_path / "s.json"
    write_pattern(standard_pattern(2, 2), src)
    with pytest.raises(SystemExit) as exc:  # argparse usage errors exit 2 from the parser
        run_cli("deploy", src, "--steps", "1", "-o", out)
    assert exc.value.code == 2 and not out.exists()
    code, _, err = run_cli(
        "deploy", ref("compact_reconfigurable_design"), "--path", "rigid", "-o", out
    )
    assert code == 1 and "not rigid-deployable" in err and not out.exists()
    code, _, err = run_cli("deploy", ref("non-contractible_design"), "-o", out)
    assert code == 1 and "does not close" in err and not out.exists()


@pytest.mark.slow
def test_deploy_front_door_gives_the_commands_verdict_without_the_cli():
    from fabkiri.api.deploy import deploy_pattern
    from fabkiri.exchange.obj import import_obj
    from fabkiri.mechanics import adopt_state_labels

    good = deploy_pattern(with_contracted_states(standard_pattern(3, 3)), 8, frames=True)
    assert good.success and good.path.kind == "rigid" and good.n_frame_files == good.path.n_frames
    assert {"energy.csv", "deploy.json"} <= set(good.files)
    bad = deploy_pattern(
        adopt_state_labels(import_obj(ref("compact_reconfigurable_design"))), 10, frames=False
    )
    assert not bad.success and any("tile overlaps" in p for p in bad.problems)
    assert bad.n_frame_files == 0 and set(bad.files) == {"energy.csv", "deploy.json"}
