"""What the radial change of a designed tube is along its deployment path (docs/tubes.md)."""

from __future__ import annotations

import numpy as np
import pytest
from fabkiri.api.tube import design_tube_pattern
from fabkiri.mechanics.deploy import deployment_path
from fabkiri.mechanics.tube import tube_along_path, tube_state
from fabkiri.pattern.kinds.periodic.sheet import seam_map, seam_of


@pytest.mark.slow
# the large-axial-change design, shared with the deploy test below and tests/design/test_tube_design.py
@pytest.mark.xdist_group("tube-113-135")
def test_designed_tube_stays_a_cylinder_but_its_radius_overshoots_on_the_path(shared_tube_designs):
    """The large-axial-change design deploys rigidly; every frame's seam is a translation (so the radius
    is the same all along the axis at every instant), yet the radius does not change monotonically: on
    the way to closed state 2 it passes above its final value (Fig. 5B's "nonuniform radial change
    throughout the deployment and contraction process", in time, not along the axis)."""
    pat = shared_tube_designs((6, 8), "cylinder:113.137,135").pattern
    path = deployment_path(pat, steps=40)
    assert path.kind == "rigid"
    seam = seam_of(pat)
    rot = np.array([seam_map(Y, seam).rotation for Y in path.corners])
    dev = np.array([seam_map(Y, seam).translation_dev for Y in path.corners]) / pat.tile_size
    assert np.abs(rot).max() < 1e-9 and dev.max() < 1e-9
    radius = np.array([tube_state(pat, seam, Y, 1).radius_min_mm for Y in path.corners])
    half = len(radius) // 2
    assert radius[half] == pytest.approx(113.137 / (2 * np.pi), rel=1e-4)  # the deployed frame
    assert radius[half:].max() > radius[-1] * 1.05  # overshoot before closed state 2
    assert np.all(np.diff(radius[: half + 1]) > 0)  # while from closed state 1 it only grows


def test_deploy_reports_the_standard_tubes_radius_in_every_frame(tmp_path, run_cli):
    """The standard tube deploys symmetrically: its radius grows monotonically from each closed state to
    the deployed one, and `deploy` writes it frame by frame (tube.csv) and says so."""
    from fabkiri.exchange.pattern_json import write_pattern
    from fabkiri.pattern.kinds.periodic.sheet import standard_tube

    src = tmp_path / "tube.json"
    write_pattern(standard_tube(6, 8), src)
    code, _, err = run_cli("deploy", src, "-o", tmp_path / "dep", "--no-frames")
    assert code == 0, err
    rows = (tmp_path / "dep" / "tube.csv").read_text().splitlines()
    assert len(rows) == 42  # header + 41 frames
    import json

    radius = np.array(
        json.loads((tmp_path / "dep" / "deploy.json").read_text())["tube"]["radius_max_mm"]
    )
    assert np.allclose(
        [float(r.split(",")[2]) for r in rows[1:]], radius, rtol=1e-8
    )  # csv: 9 digits
    assert radius[20] == pytest.approx(radius[0] * np.sqrt(2), rel=1e-9)  # ψ 45° -> 90°: x√2
    assert radius[-1] == pytest.approx(radius[0], rel=1e-9)
    assert "radius, closed state 1 -> deployed: monotonic" in err
    assert "radius, deployed -> closed state 2: monotonic" in err


@pytest.mark.slow
@pytest.mark.xdist_group("tube-113-135")
def test_deploy_says_when_a_designed_tubes_radius_overshoots(
    tmp_path, run_cli, shared_tube_designs
):
    """The large-axial-change design's radius passes beyond its ends on the way to closed state 2, and
    `deploy` reports where."""
    from fabkiri.exchange.pattern_json import write_pattern

    src = tmp_path / "a.json"
    write_pattern(shared_tube_designs((6, 8), "cylinder:113.137,135").pattern, src)
    code, _, err = run_cli("deploy", src, "-o", tmp_path / "dep", "--no-frames")
    assert code == 0, err
    line = next(x for x in err.splitlines() if "deployed -> closed state 2" in x)
    assert "not monotonic" in line and "peak 28.6" in line


@pytest.mark.slow
def test_a_tube_with_a_smaller_axial_change_and_a_radius_that_swells_and_shrinks_on_the_way():
    """Fig. 5B's counterpart: `cylinder:113.137,100` has a smaller axial change than the 135 mm design
    (x2.05 against x2.89) but its radius swells from 18.5 mm to 21.2 mm before shrinking to 18.0 mm on
    the way from closed state 1 to the deployed state (measured 2.68 mm beyond the ends)."""
    out = design_tube_pattern((6, 8), "cylinder:113.137,100")
    pat = out.pattern
    path = deployment_path(pat, steps=40)
    prof = tube_along_path(pat, path.corners, path.t)
    first = prof["radius_change"]["closed state 1 -> deployed"]
    assert not first["monotonic"] and first["beyond_ends_mm"] > 2.0
    assert 0.0 < first["t_at_peak"] < 0.5
    assert max(prof["seam_translation_dev_rel"]) < 1e-10  # a cylinder in every frame
    length = prof["length_change"]
    assert (
        length["closed state 1 -> deployed"]["end_mm"]
        / length["closed state 1 -> deployed"]["start_mm"]
        < 2.5
    )
