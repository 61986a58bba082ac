"""Fabrication-aware kagome design: the rows of design/kagome/fabrication.py and ``design --lattice kagome
--material/--printer`` (docs/kagome.md, "Designing for a material or a printer")."""

from __future__ import annotations

import json

import numpy as np
import pytest
from fabkiri.design.kagome import fabrication as KF
from fabkiri.design.quad.fabrication import FabricationLimits
from fabkiri.pattern import thinness as fab
from fabkiri.pattern.kinds.kagome.lattice import standard_kagome

from .kagome_routes import ACRYLIC_OPEN_GROUP, ACRYLIC_OPEN_HEART

# every row kind at once, in tile edges (the rows are built at unit_mm = 1)
LIMITS = FabricationLimits(
    min_width_mm=0.3,
    shrink_mm=0.02,
    min_edge_mm=0.05,
    hinge_spacing_mm=0.3,
    hinge_edge_mm=0.35,
    min_hinge_angle_deg=25.0,
    min_hole_mm=0.2,
    strip_clearance_mm=0.03,
    strip_width_mm=0.3,
    strip_reach_mm=0.3,
)
NAMES = {
    "fabrication_width",
    "fabrication_shrunk_edges",
    "fabrication_hinge_angles",
    "fabrication_hinge_spacing",
    "fabrication_hinge_edges",
    "fabrication_strip_clearance",
    "fabrication_holes",
}


def _jittered(seed: int, amount: float = 0.05):
    p = standard_kagome(4, 4, tile_size=1.0)
    x = p.nodes + amount * np.random.default_rng(seed).standard_normal(p.nodes.shape)
    return p, x


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_kagome_fabrication_jacobians_match_finite_differences(seed):
    p, x = _jittered(seed)
    # a margin above every row makes every row active: the residual is g - margin everywhere (smooth)
    fams = KF.families(p, LIMITS, 1.0, margin=100.0)
    assert {f.name for f in fams} == NAMES
    h = 1e-6
    for f in fams:
        r, J = f(x)
        assert np.allclose(r, f.residual(x)) and (r < 0).all()
        J = J.toarray()
        Jn = np.empty_like(J)
        for i in range(x.size):
            e = np.zeros(x.size)
            e[i] = h
            e = e.reshape(x.shape)
            Jn[:, i] = (f.residual(x + e) - f.residual(x - e)) / (2 * h)
        assert np.abs(J - Jn).max() < 1e-6, f.name


def test_rows_are_zero_on_fat_triangles_and_negative_on_a_sliver():
    p = standard_kagome(4, 4, tile_size=1.0)  # every tile equilateral, edge 1
    lim = FabricationLimits(min_width_mm=0.5, min_hinge_angle_deg=30.0, hinge_edge_mm=0.5)
    fams = {f.name: f for f in KF.families(p, lim, 1.0, weight=1.0)}
    x = p.nodes.copy()
    for f in fams.values():
        assert np.array_equal(f.residual(x), np.zeros_like(f.residual(x))), f.name
    # squash one tile: its free corner (a tip, on that tile alone) onto the middle of its opposite edge
    top = p.topology
    tip = int(top.free_nodes[0])
    t, k = np.argwhere(top.tiles == tip)[0]
    a, b = x[top.tiles[t, (k + 1) % 3]], x[top.tiles[t, (k + 2) % 3]]
    x[tip] = 0.5 * (a + b) + 0.1 * (x[tip] - 0.5 * (a + b))  # altitude 0.087 < 0.5
    width = fams["fabrication_width"].residual(x).reshape(-1, 3)
    assert (width[t] < 0).any() and (np.delete(width, t, 0) == 0).all()
    # the row is the altitude (the definition cut checks) minus the width and the margin
    assert np.isclose(width[t].min(), fab.widths(x[top.tiles])[t] - 0.5 - KF.MARGIN)
    angles = fams["fabrication_hinge_angles"].residual(x)
    assert (angles < 0).any()  # the sliver's hinge corners are sharper than 30°


@pytest.mark.parametrize("shrink", [0.0, 0.04])
def test_measured_width_rows_are_cuts_definition(shrink):
    p, x = _jittered(3, 0.08)
    lim = FabricationLimits(min_width_mm=0.2, shrink_mm=shrink)
    g = KF.rows(p, lim, 1.0)[0]
    assert g.name == "fabrication_width"
    rows = g.g(x).v.reshape(-1, 3).min(1) + 0.2
    assert np.allclose(rows, fab.widths(x[p.topology.tiles], shrink), atol=1e-12)


def test_every_same_face_pair_is_a_strip_row_and_none_other():
    p = standard_kagome(4, 4, tile_size=1.0)
    lim = FabricationLimits(strip_clearance_mm=0.1, strip_width_mm=0.2, strip_reach_mm=0.2)
    every = KF.rows(p, lim, 1.0)[0]
    H = p.topology.n_hinges
    alt = np.arange(H) % 2
    some = KF.rows(p, lim, 1.0, faces=alt)[0]
    per_tile = np.bincount(p.topology.hinge_tiles.ravel(), minlength=p.n_tiles)
    assert len(every.owner) == int((per_tile * (per_tile - 1) // 2).sum())
    assert 0 < len(some.owner) < len(every.owner)


def test_impossible_kagome_request_exits_2_naming_the_smallest_size(run_cli, tmp_path):
    out = tmp_path / "k.json"
    code, _, err = run_cli(
        "design", "--lattice", "kagome", "--tiles", "6x11", "--target", "heart",
        "--size", "20", "--material", "acrylic-3", "-o", out,
    )  # fmt: skip
    assert code == 2 and "Pál" in err and "--size" in err and not out.exists(), err


def test_hinge_without_material_is_refused_for_kagome(run_cli, tmp_path):
    out = tmp_path / "k.json"
    code, _, err = run_cli(
        "design", "--lattice", "kagome", "--tiles", "4x5", "--target", "circle",
        "--hinge", "tape", "-o", out,
    )  # fmt: skip
    assert code == 2 and "--hinge needs --material" in err and not out.exists(), err


@pytest.mark.slow  # the quick loop takes the rows above; this is the whole path, design to cut
@pytest.mark.xdist_group(ACRYLIC_OPEN_GROUP)  # shares its design with test_opening.py's kagome test
def test_heart_for_acrylic_meets_the_web_and_cuts_at_scale_1(
    run_cli, tmp_path, shared_kagome_designs
):
    """A 4x7 heart at 80 mm: the free design's tiles are too thin for acrylic-3 (as the 6x11 heart's at
    120 mm, 1.06 mm where cut needs 3 mm), so it is designed again with the rows; its thinnest tile is at
    least 3 mm and ``cut`` (which defaults to the design's material, at scale 1) writes verified files.
    The design carries an opening floor too (``ACRYLIC_OPEN_HEART``), which test_opening.py checks."""
    out = tmp_path / "h.json"
    code, _, err = run_cli(*ACRYLIC_OPEN_HEART, "-o", out)
    assert out.exists() and "fabrication (acrylic-3 tape): met" in err, err
    report = json.loads(out.read_text())["design"]["report"]
    assert report["max_equality_residual"] <= 1e-10
    fr = report["fabrication"]
    assert fr["met"] and fr["thinnest_tile_mm"] >= 3.0 - fab.WEB_SLACK_MM
    # the free design missed the limits: designed again with the rows (its Hausdorff kept beside)
    assert fr["without_limits_hausdorff_rel"] is not None
    assert fr["route"] in ("continuation", "initial guess")
    code, _, err = run_cli("cut", out, "-o", tmp_path / "cut")
    assert code == 0 and "verifier passed" in err, err
    assert json.loads((tmp_path / "cut" / "manifest.json").read_text())["scale"] == 1.0


def test_the_nearest_design_that_meets_the_limits_is_kept():
    """``api/kagome._nearest``: of the routes tried with the rows, the one whose first closing candidate that
    meets the limits is nearest the target; none meets them: the first route, with no pattern."""
    from types import SimpleNamespace

    from fabkiri.api.kagome import _nearest

    std = standard_kagome(4, 4, tile_size=10.0)
    far = SimpleNamespace(pattern=std, candidates=((0.2, std.nodes),))
    near = SimpleNamespace(pattern=std, candidates=((0.1, std.nodes),))
    name, d, pattern, k = _nearest({"continuation": far, "initial guess": near}, lambda p: True)
    assert (name, d, k) == ("initial guess", near, 0) and sorted(pattern.contracted) == [1, 2]
    name, d, pattern, k = _nearest({"continuation": far, "initial guess": near}, lambda p: False)
    assert (name, d, pattern, k) == ("continuation", far, None, 1)
