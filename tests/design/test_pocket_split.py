"""A lattice corner in a deep pocket (``design/quad/pocket_split.py``, ``api/design_pocket.py``): the boot (a
rounded L, 68 x 88 mm) given 16x16 tiles, whose own split leaves its inner corner mid-side and from which
every other guess ran the lattice's side across the pocket (12.8 % rigid, 26.0 % non-rigid)."""

from __future__ import annotations

import numpy as np
import pytest
from fabkiri.api.design import PatternRequest, _check, _solver_request, design_pattern
from fabkiri.api.design_pocket import pocket_request
from fabkiri.design.core import conformance as conf
from fabkiri.design.quad.pocket_split import pocket_split
from fabkiri.design.quad.solve import design
from fabkiri.design.targets.lookup import load_target

from .test_opening import DATA

BOOT = str(DATA / "boot.csv")
# the rounded inner corner's middle, (35.17, 35.17) mm in the file, centred and scaled to 100 mm
INNER = (np.array([35.17, 35.17]) - [30.0, 40.0]) * 100 / 88


def test_the_boots_corner_on_the_pockets_wall_goes_to_its_inner_corner():
    boot = load_target(BOOT, 100)
    split = pocket_split(boot, 16, 16)
    assert split is not None
    moved = np.flatnonzero(np.abs(split.corners - boot.corners) > 1e-9)
    assert moved.tolist() == [
        2
    ]  # TR: the own split put it on the pocket's wall, 16 mm above the corner
    assert np.linalg.norm(boot.corner_points()[2] - INNER) > 10.0
    assert np.linalg.norm(split.corner_points()[2] - INNER) < 1.0


@pytest.mark.parametrize("name", ["heart", "ellipse", "circle"])
def test_outlines_without_such_a_pocket_keep_their_split(name):
    assert pocket_split(load_target(name, 100), 16, 16) is None


@pytest.mark.parametrize("rigid", [True, False])
def test_the_boots_pocket_attempt_meets_the_shape(rigid):
    request, req, target, contracted = _solver_request(
        PatternRequest(tiles=(16, 16), target=BOOT, size=100, rigid=rigid, quiet=True)
    )
    sub = pocket_request(req)
    assert sub is not None and sub.init == ("coarse" if rigid else "rigid")
    outcome = _check(design(sub), contracted, request, target, conf.parse_shape_tol("2%"))
    assert outcome.valid  # converged, both states close, no tile pair overlaps
    assert outcome.report["conformance"]["deployed"]["hausdorff_rel"] < 0.02


def test_the_next_pocket_attempt_shifts_the_corner_only_after_a_fit_that_met():
    _, req, _, _ = _solver_request(
        PatternRequest(tiles=(16, 16), target=BOOT, size=100, rigid=True)
    )
    first = pocket_request(req, [{"init": "rescaled", "shape": "missed"}])
    assert first is not None
    overlapped = [{"init": "pocket", "shape": "met"}]  # met the shape, failed a check (overlaps)
    second = pocket_request(req, overlapped)
    assert second is not None
    step = second.target.corners[2] - first.target.corners[2]
    assert step == pytest.approx(
        -0.5 / 64
    )  # half the spacing of the 64 boundary tips, back along the curve
    assert pocket_request(req, [{"init": "pocket", "shape": "missed"}]) is None


@pytest.mark.slow  # the front door's guesses first (about 6 rigid, 15 non-rigid CPU s)
@pytest.mark.parametrize("rigid", [True, False])
def test_the_boot_passes_at_16x16_by_default(rigid):
    out = design_pattern(
        PatternRequest(tiles=(16, 16), target=BOOT, size=100, rigid=rigid, quiet=True)
    )
    assert out.exit_code == 0
    assert out.report["attempts"][-1]["init"] == "pocket"
