"""Shape conformance: the measure on known shapes, its invariants, and the honest checks built on it."""

from __future__ import annotations

import json

import numpy as np
import pytest
from fabkiri.design.core.conformance import judge, parse_shape_tol
from fabkiri.errors import InputError
from fabkiri.exchange.pattern_json import read_pattern
from fabkiri.pattern import conformance as pc
from fabkiri.pattern.kinds.quad.lattice import standard_pattern
from hypothesis import given, settings
from hypothesis import strategies as st

from ..conftest import TEMPLATES


def circle(r=50.0, n=4096, phase=0.0):
    t = np.linspace(0, 2 * np.pi, n, endpoint=False) + phase
    return r * np.stack([np.cos(t), np.sin(t)], -1)


@pytest.mark.parametrize("n", [5, 12, 40])
def test_inscribed_polygon_against_circle(n):
    R = 50.0
    poly = circle(R, n)
    m = pc.measure(poly, circle(R, 20000))
    sag = R * (
        1 - np.cos(np.pi / n)
    )  # farthest point of the circle from the polygon: an edge's midpoint
    assert m["hausdorff_mm"] == pytest.approx(sag, rel=1e-3, abs=1e-4)
    assert m["hausdorff_rel"] == pytest.approx(sag / (2 * R), rel=1e-3, abs=1e-6)
    assert m["worst"]["on"] == "target"
    poly_area = 0.5 * n * R * R * np.sin(2 * np.pi / n)
    assert m["one_minus_iou"] == pytest.approx(1 - poly_area / (np.pi * R * R), rel=1e-3)
    assert m["spacing_min_mm"] == pytest.approx(2 * R * np.sin(np.pi / n))
    # the mean distance from the circle is far below the largest one, and the polygon's vertices lie on it
    assert 0 < m["mean_target_to_outline_mm"] < m["hausdorff_mm"]


def test_a_missing_star_point_is_the_worst_place():
    t = np.pi / 2 + np.pi * np.arange(10) / 5
    star = np.where(np.arange(10) % 2 == 0, 50.0, 25.0)[:, None] * np.stack(
        [np.cos(t), np.sin(t)], -1
    )
    blunt = star.copy()
    blunt[0] = [0.0, 30.0]  # the top point pulled in by 20 mm
    m = pc.measure(blunt, star)
    assert m["hausdorff_mm"] == pytest.approx(20.0, abs=1e-6)
    assert m["worst"]["at"] == pytest.approx([0.0, 50.0], abs=1e-6)
    assert pc.measure(star, star)["hausdorff_mm"] == 0.0


def star_shaped(radii):
    r = np.asarray(radii)
    t = np.linspace(0, 2 * np.pi, len(r), endpoint=False)
    return r[:, None] * np.stack([np.cos(t), np.sin(t)], -1)


radii = st.lists(st.floats(10.0, 60.0), min_size=3, max_size=24)


@settings(max_examples=30, deadline=None)
@given(radii, radii, st.floats(-20, 20), st.floats(-20, 20))
@pytest.mark.slow
def test_measure_invariants(ra, rb, dx, dy):
    A = star_shaped(ra) + [dx, dy]
    B = star_shaped(rb)
    ab, ba = pc.measure(A, B, size=100.0), pc.measure(B, A, size=100.0)
    h = pc.SAMPLES_PER_SIZE
    assert ab["hausdorff_mm"] == pytest.approx(
        ba["hausdorff_mm"], abs=100.0 / h
    )  # symmetric (to the sampling)
    assert 0.0 <= ab["one_minus_iou"] <= 1.0
    assert ab["one_minus_iou"] == pytest.approx(ba["one_minus_iou"], abs=1e-9)
    assert ab["mean_outline_to_target_mm"] == pytest.approx(
        ba["mean_target_to_outline_mm"], rel=1e-9
    )
    assert (
        max(ab["mean_outline_to_target_mm"], ab["mean_target_to_outline_mm"])
        <= ab["hausdorff_mm"] + 1e-9
    )
    same = pc.measure(A, A)
    assert same["hausdorff_mm"] == 0.0 and same["one_minus_iou"] == pytest.approx(0.0, abs=1e-12)


@pytest.mark.parametrize("rows, cols", [(2, 2), (3, 5), (8, 8)])
def test_boundary_tips_in_order(rows, cols):
    p = standard_pattern(rows, cols, tile_size=10.0, angle_deg=30.0)
    top = p.topology
    order = pc.boundary_tip_order(top.tiles, top.hole_nodes, top.hole_tiles, top.free_nodes)
    assert sorted(order.tolist()) == sorted(top.free_nodes.tolist())
    import shapely

    ring = shapely.LinearRing(p.nodes[order])
    assert ring.is_simple and ring.is_ccw


def test_closed_outline_and_alignment():
    from fabkiri.mechanics.contract import contract

    p = standard_pattern(4, 4, tile_size=10.0)
    Y = contract(p, 1).corners
    outline = pc.closed_outline(Y)
    lo, hi = outline.min(0), outline.max(0)
    assert np.allclose(hi - lo, hi[0] - lo[0]) and len(outline) == 4  # a square of 4 tile sizes
    th = 0.7
    R = np.array([[np.cos(th), -np.sin(th)], [np.sin(th), np.cos(th)]])
    target = (outline - outline.mean(0)) @ R.T + [100.0, -40.0]
    Ra, t = pc.align_rigid(outline, target)
    assert pc.measure(outline @ Ra.T + t, target)["hausdorff_mm"] < 1e-4  # ICP converges linearly


def test_shape_tol_parsing_and_judgement():
    assert parse_shape_tol("2%") == (0.02, "rel")
    assert parse_shape_tol("0.5mm") == (0.5, "mm")
    assert parse_shape_tol("0.03") == (0.03, "rel")
    for bad in ("", "-1%", "2 inches", "150%", "0mm"):
        with pytest.raises(InputError):
            parse_shape_tol(bad)
    conf = {"hausdorff_mm": 3.0, "hausdorff_rel": 0.03, "size_mm": 100.0}
    j = judge(conf, (0.02, "rel"), (16, 16))
    assert (
        j["status"] == "missed"
        and j["by_mm"] == pytest.approx(1.0)
        and j["suggested_tiles"] == [24, 24]
    )
    assert judge(conf, (3.5, "mm"))["status"] == "met"


@pytest.mark.slow
def test_design_shape_tol_missed_is_written_and_exits_1(tmp_path, run_cli):
    out = tmp_path / "c.json"
    code, _, err = run_cli(
        "design",
        "--tiles",
        "4x4",
        "--target",
        "circle",
        "--rigid",
        "--shape-tol",
        "0.5%",
        "-o",
        out,
    )
    assert code == 1
    p = read_pattern(out)
    assert p.design["valid"] is True and p.design["shape"] == "missed"
    rep = p.design["report"]
    conf = rep["conformance"]["deployed"]
    assert conf["hausdorff_rel"] > 0.005 and rep["shape"]["deployed"]["status"] == "missed"
    lines = [ln for ln in err.splitlines() if "shape missed" in ln]
    assert (
        len(lines) == 1 and "tiles if the miss falls as 1/tiles" in lines[0] and "by " in lines[0]
    )
    assert (tmp_path / "c.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    # the same design within a looser tolerance passes, and --no-preview writes no picture
    out2 = tmp_path / "d.json"
    code, _, err = run_cli(
        "design",
        "--tiles",
        "4x4",
        "--target",
        "circle",
        "--rigid",
        "--shape-tol",
        "20%",
        "--no-preview",
        "-o",
        out2,
    )
    assert (
        code == 0
        and read_pattern(out2).design["shape"] == "met"
        and not (tmp_path / "d.png").exists()
    )
    assert "shape deployed: met" in err
    code, _, err = run_cli(
        "design",
        "--tiles",
        "4x4",
        "--target",
        "circle",
        "--shape-tol",
        "2 inches",
        "-o",
        tmp_path / "e.json",
    )
    assert code == 2 and "--shape-tol" in err


def _mutated(tmp_path, name, fn):
    data = json.loads((TEMPLATES / "patterns" / name).read_text())
    fn(data["design"])
    out = tmp_path / f"mut-{name}"
    out.write_text(json.dumps(data))
    return out


@pytest.mark.slow
def test_verify_catches_a_moved_or_swapped_target(tmp_path, run_cli):
    name = "circle-8x8-rigid.json"
    code, out, _ = run_cli("verify", TEMPLATES / "patterns" / name)
    assert code == 0 and "target shape" in out

    def moved(d):  # 3 % of the 100 mm size
        d["target"]["points"] = (np.asarray(d["target"]["points"]) + [3.0, 0.0]).tolist()

    def swapped(d):
        from fabkiri.design.targets.lookup import load_target

        d["target"] = load_target("hexagon").to_dict()

    for fn in (moved, swapped):
        code, out, err = run_cli("verify", _mutated(tmp_path, name, fn))
        assert code == 1 and "target shape" in err

    # the closed-state targets likewise
    def swapped_closed(d):
        from fabkiri.design.targets.lookup import load_target

        d["contracted_targets"]["2"] = load_target("square", 112.8).to_dict()

    code, out, err = run_cli(
        "verify", _mutated(tmp_path, "square-circle-9x9-rigid.json", swapped_closed)
    )
    assert code == 1 and "state 2: outline shape" in err


@pytest.mark.slow
def test_info_reports_conformance(run_cli):
    code, out, _ = run_cli("info", TEMPLATES / "patterns" / "circle-8x8-rigid.json")
    assert code == 0 and "shape        deployed vs circle: Hausdorff" in out
    code, out, _ = run_cli(
        "info", "--json", TEMPLATES / "patterns" / "square-circle-9x9-rigid.json"
    )
    d = json.loads(out)
    assert set(d["conformance"]) == {"state_1", "state_2"}
    assert d["conformance"]["state_2"]["hausdorff_rel"] < 0.02


def test_a_miss_of_many_tip_spacings_is_called_a_local_minimum_and_promises_no_tile_count():
    from fabkiri.design.core.conformance import describe_miss

    resolution = {
        "hausdorff_mm": 3.0,
        "hausdorff_rel": 0.03,
        "size_mm": 100.0,
        "spacing_mean_mm": 9.0,
        "worst": {"at": [0.0, 0.0]},
    }
    basin = dict(resolution, hausdorff_mm=13.0, hausdorff_rel=0.13, spacing_mean_mm=1.9)
    j = judge(resolution, (0.02, "rel"), (8, 8))
    assert j["suggested_tiles"] == [12, 12] and "local_minimum" not in j
    j = judge(basin, (0.02, "rel"), (32, 32))
    assert (
        j["local_minimum"]
        and "suggested_tiles" not in j
        and j["spacings"] == pytest.approx(13.0 / 1.9)
    )
    line = describe_miss("deployed", j, basin)
    assert "local minimum" in line and "tiles if the miss falls" not in line and "\n" not in line


@pytest.mark.slow
def test_the_suggested_tile_count_reaches_the_tolerance(tmp_path, run_cli):
    """The honest part of the suggestion: design again at the suggested lattice and it meets the tolerance."""
    code, out, _ = run_cli(
        "design",
        "--tiles",
        "6x6",
        "--target",
        "circle",
        "--rigid",
        "--shape-tol",
        "0.5%",
        "--json",
        "--no-preview",
        "-o",
        tmp_path / "a.json",
    )
    j = json.loads(out)["shape"]["deployed"]
    assert code == 1 and j["status"] == "missed" and not j.get("local_minimum")
    r, c = j["suggested_tiles"]
    assert (r, c) != (6, 6)
    code, out, _ = run_cli(
        "design",
        "--tiles",
        f"{r}x{c}",
        "--target",
        "circle",
        "--rigid",
        "--shape-tol",
        "0.5%",
        "--json",
        "--no-preview",
        "-o",
        tmp_path / "b.json",
    )
    assert code == 0 and json.loads(out)["shape"]["deployed"]["status"] == "met"


def test_outlines_measured_against_one_target_share_its_samples_and_tree(monkeypatch):
    """A design measures several outlines against one target (its coarse level, each start, the report): the
    target's dense samples and KD-tree are made once, and every figure is the one a fresh measure gives."""
    target = circle(50.0, 4096)
    outlines = [circle(49.0, 32), circle(51.0, 40, 0.1), circle(49.0, 32)]
    fresh = []
    for outline in outlines:
        pc._samples_of.cache_clear()
        fresh.append(pc.measure(outline, target))
    built = []
    real = pc.KDTree
    monkeypatch.setattr(pc, "KDTree", lambda pts: built.append(len(pts)) or real(pts))
    pc._samples_of.cache_clear()
    shared = [pc.measure(outline, target) for outline in outlines]
    assert json.dumps(shared) == json.dumps(fresh)  # the same bits
    # one tree for the target, one per outline
    assert len(built) == 1 + len(outlines)
    pc.measure(outlines[0], target * 2.0)  # another target: its own samples
    assert len(built) == 3 + len(outlines)


def test_an_outline_far_off_its_target_is_sampled_within_a_bound():
    """An outline a million times the target's size (a diverged design's) is sampled at its length over
    ``MAX_SAMPLES``, not at the target's spacing (some 1e10 points), and the target with it; the miss is
    measured to that spacing, which the result states."""
    target = star_shaped([50.0] * 12)
    outline = 1e6 * target
    dense = pc.densify(outline, 100.0 / pc.SAMPLES_PER_SIZE)
    assert len(dense) <= pc.MAX_SAMPLES + len(outline)
    m = pc.measure(outline, target)
    assert m["sampling_mm"] == pytest.approx(
        (pc.perimeter(outline) + pc.perimeter(target)) / pc.MAX_SAMPLES
    )
    exact = 1e6 * 50.0 - 50.0  # the outline's vertices are the farthest points from the target
    assert abs(m["hausdorff_mm"] - exact) <= 0.5 * m["sampling_mm"]
    assert "sampling_mm" not in pc.measure(1.5 * target, target)
