"""examples/quickstart.py: the notebook-style tour of the top-level API runs and makes real files."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import zipfile

import ezdxf
import pytest

from ..conftest import REPO

SCRIPT = REPO / "examples" / "quickstart.py"


def test_quickstart_is_short():
    code = [line for line in SCRIPT.read_text().splitlines() if line.strip()]
    assert len(code) <= 15


@pytest.mark.slow
def test_quickstart_designs_cuts_prints_and_deploys(tmp_path):
    env = {**os.environ, "PYTHONPATH": str(REPO)}
    run = subprocess.run(
        [sys.executable, str(SCRIPT), str(tmp_path)], capture_output=True, text=True, env=env
    )
    assert run.returncode == 0, run.stderr
    said = run.stdout.splitlines()
    assert [line.split()[0] for line in said] == ["design", "cut", "print", "deploy"]
    assert said[0].startswith("design circle-8x8-rigid: ok") and "read-back passed" in said[1]
    stem = "circle-8x8-rigid"
    design = json.loads((tmp_path / "design" / f"{stem}.json").read_text())
    assert design["design"]["valid"] and len(design["tiles"]) == 64
    doc = ezdxf.readfile(tmp_path / "cut" / f"{stem}.dxf")
    assert len(doc.modelspace()) > 64  # every tile's outline, and the hinges
    assert json.loads((tmp_path / "cut" / "manifest.json").read_text())["verification"]["ok"]
    with zipfile.ZipFile(tmp_path / "print" / f"{stem}.3mf") as z:
        assert "3D/3dmodel.model" in z.namelist()
    assert (tmp_path / "print" / f"{stem}_tiles.stl").stat().st_size > 0
    deployed = json.loads((tmp_path / "deploy" / "deploy.json").read_text())
    assert deployed["collision_free"] and deployed["frames"] == 41
    assert (tmp_path / "deploy" / "energy.csv").read_text().count("\n") == 42  # header + 41 frames
