"""The quad (``rotations``) elastic path keeps hinged tiles apart: it leaves the mechanism before
its first gap folds, and carries the contact term of the kagome homotopy.

The fixtures are non-rigid designs (tests/data: `design --tiles 16x16 --target star --solver full`
and `... --target ellipse --solver full --init rescaled` on main at 93b5a38, closed states and
report dropped) whose path on main passed hinged tiles through each other: the star 8 overlaps
(2.8e-8 mm², one hinge whose gap stayed folded flat over the whole end segment), the ellipse 18
(6.9e-6 mm²).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from fabkiri.exchange import pattern_json as io
from fabkiri.mechanics.contact import blend_term, hinge_gaps
from fabkiri.mechanics.deploy import closed_states, deployment_path, mechanism_split
from fabkiri.mechanics.drivers.rotations import barrier_frames, gap_angles, rotation_targets
from fabkiri.mechanics.path import node_positions, path_parameter

from ..designs import reconfigurable_design
from .test_kagome_contact import _fd_check

DATA = Path(__file__).parents[1] / "data"


def _design():
    return reconfigurable_design(6, 6, seed=2, amplitude=0.3, waves=3)  # not rigid-deployable


def test_rigid_gaps_of_the_rotation_targets_stay_open_until_the_closed_states():
    """Tiles turned rigidly by the driver's angles: every gap is its closed-state value at t = 0
    and 1 and open (> 0) everywhere in between. Leaving the mechanism exactly where its first gap
    folds (main) held that gap at 0 over the whole end segment."""
    p = _design()
    states = closed_states(p)
    gaps = hinge_gaps(p, states)
    split = mechanism_split(p, states)
    t = np.union1d(path_parameter(40), barrier_frames(split, 10))
    rigid = np.stack([gaps.turned(th) for th in rotation_targets(p, states, t)])
    for s, f in ((1, 0), (2, -1)):
        closed = gap_angles(p, states[s]).ravel()
        assert np.abs(np.angle(np.exp(1j * (rigid[f] - closed)))).max() <= 1e-9
        assert split[s].leaves < split[s].closing < 1.0
    inner = rigid[1:-1]
    assert inner.min() > 1e-4  # rad: the narrowest gap of any frame strictly inside the path
    # the gaps that fold flat first are still open by a part of their deployed value
    folded = np.abs(np.angle(np.exp(1j * rigid[0]))) <= 1e-9
    assert folded.sum() >= 4


def test_contact_term_on_the_rotation_targets_matches_finite_differences():
    p = _design()
    states = closed_states(p)
    gaps = hinge_gaps(p, states)
    split = mechanism_split(p, states)
    t = 0.25 * (1.0 - split[1].leaves)  # half way through the end segment next to state 1
    term = blend_term(gaps, gaps.turned(rotation_targets(p, states, t)[0]), weight=1.3, kappa=0.5)
    assert len(term.rows) >= 4
    x = p.nodes.ravel()
    assert term.energy(x) == 0.0  # the deployed gaps are wider than any clearance
    # closed state 1, nudged: its folded gaps sit inside their clearances, by different margins
    y = node_positions(p, states[1]).ravel()
    y = y + 0.01 * p.tile_size * np.random.default_rng(1).standard_normal(y.size)
    short = term.clearance - gaps.angles(y)[term.rows]
    assert (short > 1e-3).sum() >= 4 and term.energy(y) > 0
    grad_err, hess_err = _fd_check(term, y)
    assert grad_err <= 1e-7 and hess_err <= 1e-7


@pytest.mark.slow
@pytest.mark.parametrize("name", ["star-16x16-nonrigid", "ellipse-16x16-nonrigid"])
def test_designed_non_rigid_quad_deploys_without_overlaps(name):
    p = io.read_pattern(DATA / f"{name}.json")
    path = deployment_path(p, 40)
    assert path.kind == "elastic" and path.driver == "rotations"
    c = path.collisions
    assert c.collision_free() and not c.self_intersecting, (len(c.overlaps), c.max_area)
    for state, miss in path.state_mismatch.items():
        assert miss <= 1e-9 * p.tile_size, state
    assert path.solver["unconverged_steps"] == 0
    # the sprung gaps kept most of their rigid value (0 or less: tiles touching at a hinge)
    assert path.solver["narrowest_gap_to_rigid"] > 0.5
    for f in path.mark_frames().values():
        assert path.energy[f] <= 1e-12
