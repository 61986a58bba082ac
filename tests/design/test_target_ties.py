"""A point as far from two stretches of a target gets one foot, whatever the round-off (issue #36: the 16x16
heart's fit went to one of two minima as the BLAS kernels rounded a chord midpoint on its axis)."""

from __future__ import annotations

import json
import os
import subprocess
import sys

import numpy as np
import pytest
from fabkiri.design.targets.lookup import load_target

from ..conftest import REPO


@pytest.mark.parametrize("y", [30.0, 26.0])
def test_a_point_on_the_hearts_axis_above_its_cusp_gets_one_foot(y):
    # the heart is symmetric about x = 0: above its cusp both lobes are as far; the rounding of x used to
    # pick the lobe (left of the axis the one, right of it the other)
    heart = load_target("heart")
    p = np.array([[-1e-12, y], [0.0, y], [1e-12, y], [-3e-11, y]])
    u, foot, d, grad = heart.project(p)
    # (main: u 0.48 or 0.52, the gradient's x +0.92 or -0.92, as x rounded)
    assert np.ptp(np.mod(u, 1.0)) <= 1e-9 and np.ptp(foot, axis=0).max() <= 1e-9
    assert np.ptp(grad, axis=0).max() <= 1e-9 and np.ptp(d) <= 1e-9
    # the rule: of the two feet, the one further along the counter-clockwise curve (which runs from the
    # bottom tip up the right lobe, then over the left): the left lobe's
    assert foot[0, 0] < 0.0


def test_off_the_axis_each_point_keeps_its_own_nearest_foot():
    heart = load_target("heart")
    p = np.array([[-0.5, 30.0], [0.5, 30.0]])
    u, foot, d, grad = heart.project(p)
    assert foot[0, 0] < 0.0 < foot[1, 0]  # each on its own lobe: no tie, nothing changed
    assert abs(foot[0, 0] + foot[1, 0]) <= 1e-6 and abs(d[0] - d[1]) <= 1e-9


@pytest.mark.slow
def test_heart_16x16_takes_the_short_route_with_this_machines_own_kernels(tmp_path):
    # no OPENBLAS_CORETYPE (conftest pins Haswell for the test process): on an AVX-512 box main's rescaled
    # member missed (4.65 %) and the design went the long way (rigid family misses, then the rigid design
    # with the full solver, ~11 CPU s); both kernels now meet it from rescaled at 1.42 %
    env = {k: v for k, v in os.environ.items() if k != "OPENBLAS_CORETYPE"}
    env["PYTHONPATH"] = str(REPO)
    out = tmp_path / "p.json"
    argv = ["design", "--tiles", "16x16", "--target", "heart", "--no-preview", "-v", "-o", str(out)]
    proc = subprocess.run(
        [sys.executable, "-m", "fabkiri.cli.main", *argv],
        capture_output=True,
        text=True,
        env=env,
        cwd=REPO,
    )
    assert proc.returncode == 0, proc.stderr[-500:]
    assert "rigid family from rescaled: outline within 1.4" in proc.stderr
    assert "full solver too" not in proc.stderr
    rep = json.loads(out.read_text())["design"]["report"]
    assert rep["conformance"]["deployed"]["hausdorff_rel"] <= 0.0143
