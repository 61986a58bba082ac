"""The homotopy path's contact term: hinged tiles repel before their gap closes past zero.

The fixtures are designed kagome patterns (tests/data: `design --lattice kagome` on main at
16a0bec, closed states and report dropped) whose spring-only homotopy path passed tiles through
each other next to their hinges: the ellipse 5x19 (198 mm) 16 overlaps <= 0.034 mm deep, the
heart 6x11 (120 mm) 115 overlaps <= 1.17 mm deep.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from fabkiri.exchange import pattern_json as io
from fabkiri.mechanics.contact import GapTerm, gap_term, hinge_gaps
from fabkiri.mechanics.drivers.rotations import gap_angles
from fabkiri.mechanics.path import closed_states, node_positions
from fabkiri.pattern.kinds.kagome.lattice import standard_kagome
from fabkiri.pattern.kinds.quad.lattice import standard_pattern

DATA = Path(__file__).parents[1] / "data"


def _fixture(name):
    return io.read_pattern(DATA / f"kagome-{name}.json")


def _fd_check(term: GapTerm, x: np.ndarray) -> tuple[float, float]:
    """Relative errors of the analytic gradient and Hessian against central differences."""
    h, eye = 1e-6, np.eye(len(x))
    g = np.array([(term.energy(x + h * e) - term.energy(x - h * e)) / (2 * h) for e in eye])
    Hf = np.array([(term.gradient(x + h * e) - term.gradient(x - h * e)) / (2 * h) for e in eye])
    H = term.hessian(x).toarray()
    assert np.abs(H - H.T).max() <= 1e-12 * np.abs(H).max()
    return (
        float(np.abs(g - term.gradient(x)).max() / np.abs(g).max()),
        float(np.abs(H - Hf.T).max() / np.abs(H).max()),
    )


@pytest.mark.parametrize(
    "make", [lambda: standard_kagome(3, 4, angle_deg=30.0), lambda: standard_pattern(2, 3)]
)
def test_gap_term_derivatives_match_finite_differences(make):
    p = make()
    gaps = hinge_gaps(p, closed_states(p))
    x = p.nodes.ravel() + 0.05 * p.tile_size * np.random.default_rng(0).standard_normal(
        p.nodes.size
    )
    ang = gaps.angles(x)
    rows = np.flatnonzero(np.abs(ang) < 2.5)  # away from the ±π cut of atan2
    # clearances above every watched gap, by different margins: every term active, none at its kink
    term = GapTerm(gaps, rows, np.abs(ang[rows]) + np.linspace(0.01, 0.3, len(rows)), 1.3, 0.5)
    assert len(rows) >= 4 and term.energy(x) > 0
    grad_err, hess_err = _fd_check(term, x)
    assert grad_err <= 1e-7 and hess_err <= 1e-7


def test_gaps_follow_the_topology_convention_and_the_homotopy_turns():
    """Gap k of hinge i is row 2i + k, measured as `gap_angles` measures it; turning the tiles by
    the homotopy's closed-state angles moves every gap onto its closed-state value, and on the
    designed ellipse it never crosses zero on the way (the rigid blend has no collision at a hinge:
    the path's overlaps were the springs')."""
    p = _fixture("ellipse-5x19")
    states = closed_states(p)
    gaps = hinge_gaps(p, states)
    measured = np.mod(gaps.angles(p.nodes.ravel()), 2 * np.pi)
    assert np.abs(np.angle(np.exp(1j * (measured - gaps.deployed)))).max() <= 1e-12
    for s in (1, 2):
        closed = gap_angles(p, states[s]).ravel()
        end = gaps.deployed + gaps.turn[s]
        assert np.abs(np.angle(np.exp(1j * (end - closed)))).max() <= 1e-9
        assert end.min() >= -1e-9 and end.max() <= 2 * np.pi + 1e-9
        assert np.abs(gaps.rigid(0.0 if s == 1 else 1.0) - end).max() == 0.0
    assert np.array_equal(gaps.rigid(0.5), gaps.deployed)


def test_gap_term_is_zero_at_the_states_and_pushes_a_closing_gap_open():
    p = _fixture("ellipse-5x19")
    states = closed_states(p)
    gaps = hinge_gaps(p, states)
    nodes = {0.5: p.nodes}
    for s, t in ((1, 0.0), (2, 1.0)):
        nodes[t] = node_positions(p, states[s])
    for t, x in nodes.items():
        term = gap_term(gaps, t, weight=1.0, kappa=0.5)
        assert term.energy(x.ravel()) == 0.0, t  # the states are exact: the term changes none
    # half way to state 1 a folding gap narrowed below half its rigid value costs energy, and the
    # force on its far corner turns it open
    term = gap_term(gaps, 0.25, weight=1.0, kappa=0.5)
    closing = term.rows[np.argmin(term.clearance)]
    x = p.nodes.ravel().copy()
    h, u = gaps.h[closing], gaps.u[closing]
    base = gaps.angles(x)[closing]
    target = 0.2 * term.clearance.min()  # rotate u about h so the gap is well inside its clearance
    c, s_ = np.cos(base - target), np.sin(base - target)
    X = x.reshape(-1, 2)
    d = X[u] - X[h]
    X[u] = X[h] + [c * d[0] - s_ * d[1], s_ * d[0] + c * d[1]]
    assert gaps.angles(x)[closing] == pytest.approx(target)
    assert term.energy(x) > 0
    step = -1e-6 * term.gradient(x)  # downhill
    assert gaps.angles(x + step)[closing] > target


def _deploy(p, weight=None):
    from fabkiri.mechanics.deploy import deployment_path
    from fabkiri.mechanics.drivers.homotopy import Homotopy

    if weight is None:
        return deployment_path(p, 40)
    old = Homotopy.contact_weight
    Homotopy.contact_weight = weight
    try:
        return deployment_path(p, 40)
    finally:
        Homotopy.contact_weight = old


@pytest.mark.slow  # ~2-3 CPU s each; the quick loop takes the homotopy path on generic 4x4 / 7x5
@pytest.mark.parametrize("name", ["ellipse-5x19", "heart-6x11"])
def test_designed_kagome_deploys_without_overlaps(name):
    """Measured (41 frames): ellipse 16 overlaps <= 0.034 mm deep without the contact term, none
    with it (narrowest gap 0.47 of its rigid value); heart 6x11 115 <= 1.17 mm, none (0.27)."""
    p = _fixture(name)
    bare = _deploy(p, weight=0.0)
    assert len(bare.collisions.overlaps) > 0  # the springs alone let hinged tiles pass through
    path = _deploy(p)
    assert path.driver == "homotopy"
    assert path.collisions.collision_free() and not path.collisions.self_intersecting
    for k, f in path.mark_frames().items():
        assert path.state_mismatch[k] <= 1e-13 * p.tile_size, k
        assert path.energy[f] <= 1e-20, k
    s = path.solver
    assert s["unconverged_steps"] == 0 and s["mirrored_tiles_max"] == 0
    assert 0.0 < s["narrowest_gap_to_rigid"] < 1.0 and s["contact_energy_max"] > 0.0
    # the branch the springs alone follow, no snap: the largest sub-step move is theirs
    moved = s["largest_substep_move_tile_sizes"]
    assert moved <= 1.05 * bare.solver["largest_substep_move_tile_sizes"]
    # the term repels only: the springs' energy barely moves (E_max within 2 %)
    assert abs(path.energy.max() - bare.energy.max()) <= 0.02 * bare.energy.max()
