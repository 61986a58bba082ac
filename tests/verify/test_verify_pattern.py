"""Pattern checks of the geometric verifier, on reference data and constructed patterns."""

from __future__ import annotations

import json

import numpy as np
import pytest
from fabkiri.exchange.obj import import_obj
from fabkiri.mechanics import adopt_state_labels, with_contracted_states
from fabkiri.pattern import Pattern, geometry, standard_pattern
from fabkiri.pattern.kinds.quad.lattice import DX, DY, quad_topology
from fabkiri.verify import Report, rigid_claimed, tolerances, verify_pattern
from fabkiri.verify.pattern_checks import rigid_path
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.sparse.csgraph import breadth_first_order

from .. import layout_fixtures as lf
from ..conftest import ref


def _failed(rep: Report) -> set[str]:
    return {c.name for c in rep.failed()}


def test_compact_reconfigurable_only_the_bow_tie_fails():
    p = adopt_state_labels(
        import_obj(
            ref("compact_reconfigurable_design"),
            [ref("compact_reconfigurable_contracted1"), ref("compact_reconfigurable_contracted2")],
        )
    )
    rep = verify_pattern(p)
    assert _failed(rep) == {
        "tiles simple",
        "state 1: no overlaps",
        "state 2: no overlaps",
        "state 1: union area = sum of tile areas",
        "state 2: union area = sum of tile areas",
    }
    simple = rep.get("tiles simple")
    assert simple.value == 1 and simple.worst == "tile 2" and "720°" in simple.detail
    for s in (1, 2):
        ov = rep.get(f"state {s}: no overlaps")
        assert "2" in ov.worst.split(" ")[1].split("/")
        assert "all caused by self-intersecting tile(s) [2]" in ov.detail
        # the overlaps are slight (the file's tiles are otherwise exact)
        assert 1e-5 * p.tile_size < ov.value < 1e-3 * p.tile_size
        for name in (
            "loop closure",
            "holes closed",
            "folded gaps closed",
            "no interior gaps",
            "one outline",
            "stored state matches computed",
            "tiles congruent (lengths)",
        ):
            assert rep.get(f"state {s}: {name}").ok, name
    # the ring that the bow-tie puts off by 2π is flagged, not failed
    assert any(
        "wrapped by 2π because of tiles [2]" in c.detail
        for c in rep.checks
        if c.name.endswith("rings")
    )
    hs = rep.get("hinge sums")
    assert not hs.applies and hs.ok and 0.08 < hs.value < 0.09


def test_non_contractible_fails_closure_in_both_states():
    p = adopt_state_labels(import_obj(ref("non-contractible_design")))
    rep = verify_pattern(p)
    for s in (1, 2):
        lc = rep.get(f"state {s}: loop closure")
        assert not lc.ok and lc.value > 0.5 * p.tile_size and lc.worst.startswith("hole ")
        assert not rep.get(f"state {s}: holes closed").ok
        assert not rep.get(f"state {s}: rings").ok
    assert rep.get("tiles simple").ok


def test_contractible_passes_state_1_and_fails_state_2():
    p = adopt_state_labels(import_obj(ref("contractible_design"), [ref("contractible_contracted")]))
    rep = verify_pattern(p)
    state1 = [c for c in rep.checks if c.name.startswith("state 1:")]
    assert len(state1) >= 10 and all(c.ok for c in state1)
    assert not rep.get("state 2: loop closure").ok
    assert all(c.name.startswith("state 2:") for c in rep.failed())


@pytest.mark.parametrize("angle", [45.0, 30.0])
def test_standard_lattice_passes_with_rigid_path(angle):
    p = standard_pattern(6, 7, tile_size=12.0, angle_deg=angle)
    assert rigid_claimed(p)
    rep = verify_pattern(p)
    assert rep.ok, rep.to_text()
    assert rep.get("rigid path: hinge closure").detail.startswith("33 samples")
    assert rep.get("rigid path: no overlap").ok


def test_rigid_path_passes_through_the_deployed_state():
    p = with_contracted_states(standard_pattern(4, 5, tile_size=10.0, angle_deg=45.0))
    frames, mismatch = rigid_path(p, p.contracted[1], np.array([0.0, np.pi / 4, np.pi / 2]))
    assert mismatch.max() < 1e-12 * 10 * p.tile_size
    assert geometry.aligned_distance(frames[0], p.contracted[1]) < 1e-9
    assert geometry.aligned_distance(frames[1], p.corners()) < 1e-9
    assert geometry.aligned_distance(frames[2], p.contracted[2]) < 1e-9


def test_designed_distinct_pattern_passes():
    p = lf.distinct_pattern()
    rep = verify_pattern(p)
    assert rep.ok, rep.to_text()
    assert "rigid path: no overlap" in rep.names()
    # tiles really are pairwise distinct, so layout matching is meaningful
    L = geometry.edge_lengths(p.corners())
    assert len(np.unique(np.round(np.sort(L, 1), 6), axis=0)) == p.n_tiles


def two_size_squares(
    rows: int, cols: int, a: float = 10.0, b: float = 6.0, psi: float = np.radians(30)
) -> Pattern:
    """Rotating squares of two sizes: parallelogram holes, rigid-deployable.

    (docs/algorithm.md#parallelogram-holes)"""
    tiles, _ = quad_topology(rows, cols)
    T = rows * cols
    r, c = np.divmod(np.arange(T), cols)
    even = (r + c) % 2 == 0
    size = np.where(even, a, b)
    sigma = np.where(even, 1.0, -1.0)
    off = np.stack([DX - 0.5, DY - 0.5], -1)
    local = geometry.rotate(off[None] * size[:, None, None], (-sigma * psi)[:, None])
    top = Pattern(nodes=np.zeros((tiles.max() + 1, 2)), tiles=tiles).topology
    order, pred = breadth_first_order(top.tile_adjacency, 0, directed=False)
    Y = np.zeros((T, 4, 2))
    Y[0] = local[0]
    for t in order[1:]:
        h = int(top.tile_adjacency[pred[t], t]) - 1
        (A, _), (cA, cB) = top.hinge_tiles[h], top.hinge_corner[h]
        cp, cc = (cA, cB) if A == pred[t] else (cB, cA)
        Y[t] = local[t] - local[t][cc] + Y[pred[t]][cp]
    nodes = np.zeros((tiles.max() + 1, 2))
    nodes[tiles.ravel()] = Y.reshape(-1, 2)
    assert np.abs(nodes[tiles] - Y).max() < 1e-12
    return Pattern(
        nodes=nodes, tiles=tiles, name="two-size squares", design={"rigid_deployable": True}
    )


def test_parallelogram_holes_count_as_closed():
    p = two_size_squares(5, 6)
    rep = verify_pattern(p)
    assert rep.ok, rep.to_text()
    for s in (1, 2):
        assert (
            "T-junctions (parallelogram holes)" in rep.get(f"state {s}: folded gaps closed").detail
        )
    assert "notch pairs differ" in rep.get("state 1: edge pairs").detail


def test_standard_lattice_reports_rhombus_closure():
    rep = verify_pattern(standard_pattern(3, 4))
    assert "coincident endpoints (rhombus holes)" in rep.get("state 1: folded gaps closed").detail


def test_stored_state_with_a_displaced_tile_is_caught():
    p = with_contracted_states(standard_pattern(5, 5, tile_size=10.0, angle_deg=35.0))
    bad = p.contracted[1].copy()
    bad[12] = geometry.rotate(bad[12] - bad[12].mean(0), 0.01) + bad[12].mean(0)  # still congruent
    q = p.with_contracted({1: bad, 2: p.contracted[2]})
    rep = verify_pattern(q)
    assert rep.get("state 1: tiles congruent (lengths)").ok
    assert not rep.get("state 1: stored state matches computed").ok
    assert not rep.get("state 1: no overlaps").ok
    assert "12" in rep.get("state 1: no overlaps").worst
    assert rep.get("state 2: stored state matches computed").ok


def test_claimed_rigidity_that_does_not_hold_fails():
    p = lf.distinct_pattern()
    top = p.topology
    nodes = p.nodes.copy()
    nodes[top.free_nodes[0]] += [0.3, -0.2]  # a free corner: hinge sums break (a notch pair too)
    q = Pattern(nodes=nodes, tiles=p.tiles, design={"rigid_deployable": True})
    rep = verify_pattern(q)
    hs = rep.get("hinge sums")
    assert hs.applies and not hs.ok and hs.worst.startswith("hinge ") and hs.value > 1e-3
    assert "rigid path: hinge closure" in rep.names()
    # not claimed: the same figure is information only
    free = verify_pattern(Pattern(nodes=nodes, tiles=p.tiles, design={"rigid_deployable": False}))
    assert free.get("hinge sums").ok and not free.get("hinge sums").applies
    assert "rigid path: hinge closure" not in free.names()


def test_target_fit():
    p = standard_pattern(4, 4, tile_size=10.0)
    tips = p.nodes[p.topology.free_nodes]
    centre = tips.mean(0)
    ang = np.arctan2(*(tips - centre).T[::-1])
    outline = tips[np.argsort(ang)]
    good = Pattern(
        nodes=p.nodes,
        tiles=p.tiles,
        lattice=p.lattice,
        design={
            "rigid_deployable": True,
            "target": {"points": outline.tolist(), "tolerance_mm": 1e-6},
        },
    )
    assert verify_pattern(good).get("target shape").ok
    far = Pattern(
        nodes=p.nodes,
        tiles=p.tiles,
        design={"target": {"points": (outline * 1.1).tolist(), "tolerance_mm": 1e-6}},
    )
    chk = verify_pattern(far).get("target shape")
    assert not chk.ok and chk.value > 1.0 and "Hausdorff" in chk.detail


def test_tolerance_tiers():
    p = standard_pattern(3, 3, tile_size=10.0)
    assert tolerances(p).length == pytest.approx(1e-8)
    solved = Pattern(nodes=p.nodes, tiles=p.tiles, design={"solver": {"status": "converged"}})
    assert tolerances(solved).length == pytest.approx(1e-4)
    assert tolerances(p, tol_mm=0.01).length == 0.01


def test_report_serialises_and_lists_failures_first():
    p = adopt_state_labels(import_obj(ref("non-contractible_design")))
    rep = verify_pattern(p)
    d = json.loads(rep.to_json())
    assert d["ok"] is False and d["kind"] == "pattern"
    assert set(d["failed"]) == {c.name for c in rep.failed()}
    for c in d["checks"]:
        assert {"name", "ok", "value", "tol", "unit", "worst"} <= set(c)
    lines = rep.to_text().splitlines()
    marks = [ln.split()[0] for ln in lines[2:] if ln and ln.split()[0] in ("FAIL", "ok", "info")]
    assert marks[: len(rep.failed())] == ["FAIL"] * len(rep.failed())
    assert "FAIL" not in marks[len(rep.failed()) :]
    assert lines[-1].startswith("verdict: FAIL")


@settings(max_examples=15, deadline=None)
@given(st.integers(1, 6), st.integers(1, 6), st.floats(5.0, 85.0), st.floats(1.0, 40.0))
def test_every_standard_lattice_passes(rows, cols, angle, size):
    rep = verify_pattern(standard_pattern(rows, cols, tile_size=size, angle_deg=angle))
    assert rep.ok, rep.to_text()


def test_target_shape_ignores_the_solver_claim():
    """The shape check measures the outline against the target and --shape-tol, whatever the file claims."""
    import dataclasses
    import json

    from fabkiri.exchange.pattern_json import read_pattern
    from fabkiri.verify import verify_pattern

    from ..conftest import TEMPLATES

    p = read_pattern(TEMPLATES / "patterns" / "circle-8x8-rigid.json")
    chk = verify_pattern(p).get("target shape")
    assert (
        chk.ok and 1e-3 < chk.value < 2.0
    )  # a real, inexact outline within 2 % of the 100 mm size
    claims = json.loads(json.dumps(p.design))
    claims["report"]["fit"]["shape"]["max_mm"] = 1e-9  # a false claim changes nothing
    claims["target"]["tolerance_mm"] = 1e6
    assert (
        verify_pattern(dataclasses.replace(p, design=claims)).get("target shape").value == chk.value
    )
    assert not verify_pattern(p, shape_tol=(0.5 * chk.value, "mm")).get("target shape").ok


def test_closed_state_checks_carry_stable_ids():
    """Code selects checks by id, not by display name: every closed-state check
    of both states has its id, and the gate's edge-pair checks are found by it."""
    from fabkiri.mechanics.contract import with_contracted_states
    from fabkiri.pattern.kinds.quad.lattice import standard_pattern
    from fabkiri.verify import verify_pattern

    rep = verify_pattern(with_contracted_states(standard_pattern(3, 3)))
    for s in (1, 2):
        for what in (
            "loop-closure",
            "congruent-lengths",
            "congruent-angles",
            "holes-closed",
            "edge-pairs",
            "rings",
        ):
            assert rep.by_id(f"state{s}.{what}").ok
        assert rep.by_id(f"state{s}.edge-pairs").name == f"state {s}: edge pairs"
    ids = [c.id for c in rep.checks if c.id]
    assert len(ids) == len(set(ids))
