"""What the radial change of a designed tube is along its deployment path (docs/tubes.md)."""

from __future__ import annotations

import numpy as np
import pytest
from fabkiri.api.tube import design_tube_pattern
from fabkiri.mechanics.deploy import deployment_path
from fabkiri.mechanics.tube import tube_state
from fabkiri.pattern.periodic import seam_map, seam_of


@pytest.mark.slow
def test_designed_tube_stays_a_cylinder_but_its_radius_overshoots_on_the_path():
    """The large-axial-change design deploys rigidly; every frame's seam is a translation (so the radius
    is the same all along the axis at every instant), yet the radius does not change monotonically: on
    the way to closed state 2 it passes above its final value (Fig. 5B's "nonuniform radial change
    throughout the deployment and contraction process", in time, not along the axis)."""
    pat = design_tube_pattern((6, 8), "cylinder:113.137,135").pattern
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
    assert np.all(np.diff(radius[:half + 1]) > 0)  # while from closed state 1 it only grows

