"""Clean quad deployment paths: the driver fallback of ``deployment_path`` and the convexity term
(:func:`fabkiri.mechanics.contact.corner_term`):
every tile's interior angles held above a part of their design, so a spring tile cannot fold
into a bow-tie across its hinged neighbour."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from fabkiri.api.deploy import check_problems
from fabkiri.exchange import pattern_json as io
from fabkiri.mechanics.contact import corner_gaps, corner_term
from fabkiri.mechanics.deploy import deployment_path

from ..designs import reconfigurable_design
from .test_deploy import compact_reconfigurable
from .test_kagome_contact import _fd_check

DATA = Path(__file__).parents[1] / "data"


def _design():
    return reconfigurable_design(4, 4, seed=2, amplitude=0.3, waves=3)


def test_corner_angles_are_the_interior_angles_of_every_tile():
    p = _design()
    corners = corner_gaps(p)
    k = p.tiles.shape[1]
    angles = corners.deployed.reshape(-1, k)
    assert (angles > 0).all() and (angles < np.pi).all()
    assert np.allclose(angles.sum(axis=1), 2 * np.pi)  # a convex quad's angles add up to 2π
    assert np.allclose(corners.angles(p.nodes.ravel()), corners.deployed)
    # a rigid motion keeps them: the term is zero at every state
    term = corner_term(p, weight=1.0, kappa=0.5)
    c, s = np.cos(0.7), np.sin(0.7)
    moved = p.nodes @ np.array([[c, s], [-s, c]]) + 3.0
    assert term.energy(p.nodes.ravel()) == 0.0 and term.energy(moved.ravel()) == 0.0


def test_corner_term_penalises_a_bow_tie():
    p = _design()
    term = corner_term(p, weight=1.0, kappa=0.5)
    x = p.nodes.copy()
    a, b = p.tiles[5, 0], p.tiles[5, 1]
    x[[a, b]] = x[[b, a]]  # two corners of tile 5 swapped: it crosses itself
    assert term.energy(x.ravel()) > 0.5  # at least one corner angle below zero: φ ≥ 1


def test_corner_term_matches_finite_differences():
    p = _design()
    corners = corner_gaps(p)
    rng = np.random.default_rng(3)
    x = p.nodes.ravel() + 0.08 * p.tile_size * rng.standard_normal(p.nodes.size)
    ang = corners.angles(x)
    # clearances above every corner angle by different margins: every corner active, none at its kink
    term = corner_term(p, weight=1.3, kappa=0.5)
    term = type(term)(
        corners, term.rows, ang[term.rows] + np.linspace(0.01, 0.3, len(term.rows)), 1.3, 0.5
    )
    assert term.energy(x) > 0
    grad_err, hess_err = _fd_check(term, x)
    assert grad_err <= 1e-6 and hess_err <= 1e-6


@pytest.mark.slow
def test_no_clean_driver_is_reported_with_what_each_found():
    """The reference compact design has a bow-tie tile in its own deployed state: no driver can
    find a clean path, so both are tried and the report names their figures (exit 1)."""
    p = compact_reconfigurable()
    path = deployment_path(p, 10)
    tried = path.solver["drivers_tried"]
    assert list(tried) == ["rotations", "homotopy"] and path.driver == "rotations"
    assert all(f["self_intersecting_tiles"] >= 1 for f in tried.values())
    problems = " ".join(check_problems(path))
    assert "no driver found a collision-free path (rotations" in problems
    assert "tiles cross themselves (bow-ties)" in problems


def test_explicit_driver_is_not_replaced():
    path = deployment_path(compact_reconfigurable(), 10, driver="rotations")
    assert path.driver == "rotations" and "drivers_tried" not in path.solver


@pytest.mark.slow
def test_designed_bean_deploys_without_overlaps_through_the_fallback():
    """`design --tiles 16x16 --target bench/data/bean.csv --size 100 --solver full` (met, 0.8 %):
    main's rotations path passed hinged tiles 239/255 through each other (22 overlaps, 0.12 mm
    deep, 3 bow-tie tiles, exit 1); the homotopy driver it now falls back to finds a clean path."""
    p = io.read_pattern(DATA / "bean-16x16-nonrigid.json")
    path = deployment_path(p, 40)
    assert path.kind == "elastic" and path.driver == "homotopy"
    c = path.collisions
    assert c.collision_free() and not c.self_intersecting, (len(c.overlaps), c.self_intersecting)
    assert path.solver["drivers_tried"]["rotations"]["overlaps"] > 0
    for state, miss in path.state_mismatch.items():
        assert miss <= 1e-9 * p.tile_size, state
    assert path.solver["unconverged_steps"] == 0 and path.solver["mirrored_tiles_max"] == 0
    assert not check_problems(path)
