"""Fabrication-aware design (issue 14): one thinnest-width definition, exact minimum scales, the design's
fabrication rows, and the intent ``cut``/``print`` read back."""

from __future__ import annotations

import json
from dataclasses import replace

import numpy as np
import pytest
import shapely
from fabkiri.design.quad import fabrication as F
from fabkiri.design.quad.constraints import Stencils
from fabkiri.exchange.pattern_json import read_pattern
from fabkiri.fabricate import design_limits
from fabkiri.fabricate import fabricability as fb
from fabkiri.fabricate.cut.materials import load_material
from fabkiri.fabricate.print.printers import load_printer
from fabkiri.pattern import thinness as fab
from fabkiri.pattern.kinds.quad.lattice import standard_pattern
from hypothesis import given, settings
from hypothesis import strategies as st

from ..conftest import TEMPLATES

PATTERNS = TEMPLATES / "patterns"
DATA = (
    TEMPLATES.parent / "tests" / "data"
)  # templates that do not print on prusa-mk4, kept for their geometry


def convex_quad(draw_angles, radii):
    a = np.sort(np.asarray(draw_angles))
    return np.stack([radii * np.cos(a), radii * np.sin(a)], -1)


quads = st.builds(
    lambda a, r: convex_quad(a, np.asarray(r)),
    st.lists(st.floats(0, 2 * np.pi - 0.01), min_size=4, max_size=4, unique=True),
    st.lists(st.floats(0.5, 2.0), min_size=4, max_size=4),
)


def brute_width(q: np.ndarray) -> float:
    """Smallest extent over 20 000 directions: the minimum width by its definition."""

    def extents(t):
        p = q @ np.stack([np.cos(t), np.sin(t)], 0)
        return p.max(0) - p.min(0)

    t = np.linspace(0, np.pi, 20000, endpoint=False)
    best, half = t[np.argmin(extents(t))], 3e-4
    # the width has a kink at its minimum, so a sample misses it by up to (slope x step): zoom in twice,
    # or a thin tile's brute width overshoots by more than the relative check below allows
    for _ in range(2):
        fine = np.linspace(best - half, best + half, 20001)
        best, half = fine[np.argmin(extents(fine))], half * 1e-4
    return float(extents(np.array([best]))[0])


@settings(max_examples=60, deadline=None)
@given(quads)
def test_width_is_the_minimum_width(q):
    poly = shapely.Polygon(q)
    if not (poly.is_valid and shapely.is_ccw(poly.exterior)) or not fab.cross_signs_ok(q[None]):
        return
    if (np.linalg.norm(np.roll(q, -1, 0) - q, axis=1) < 1e-9).any():
        return  # coinciding corners (hypothesis found angles 0 and 1e-217): not a tile, limits refuses it
    w = fab.widths(q[None])[0]
    b = brute_width(q)  # sampled directions only overestimate the minimum, by O(step²)
    assert w <= b + 1e-12 and w == pytest.approx(b, rel=1e-6)
    assert fab.polygon_width(q) == pytest.approx(w, rel=1e-12)


@settings(max_examples=60, deadline=None)
@given(quads, st.floats(0.01, 0.3))
def test_shrunk_quads_are_the_mitre_buffer(q, d):
    poly = shapely.Polygon(q)
    if (
        not poly.is_valid
        or not fab.cross_signs_ok(q[None])
        or (fab.shrunk_edges(q[None], d) < 1e-2).any()
    ):
        return
    mine = shapely.Polygon(fab.shrunk_quads(q[None], d)[0])
    geos = shapely.buffer(poly, -d, join_style="mitre", mitre_limit=10.0)
    assert shapely.hausdorff_distance(mine, geos) < 1e-9
    assert fab.widths(q[None], d)[0] == pytest.approx(
        fab.polygon_width(shapely.get_coordinates(geos)), abs=1e-9
    )


@pytest.mark.parametrize("shrink,min_edge", [(0.0, 0.0), (0.8, 0.0), (0.8, 0.4)])
def test_min_scale_is_exact(shrink, min_edge):
    c = read_pattern(PATTERNS / "circle-8x8-rigid.json").contracted[1]
    s, t, _ = fab.min_scale(c, 3.0, shrink, min_edge)

    def ok(k):
        cc = c * k
        w = fab.widths(cc, shrink)
        e = fab.shrunk_edges(cc, shrink)
        return (w >= 3.0 - 1e-9).all() and (e >= max(min_edge, fab.EDGE_EPS_MM) - 1e-9).all()

    assert ok(s * (1 + 1e-9)) and not ok(0.99 * s)


def test_ceil_sig_never_below():
    for x in (2.0700000001, 2.07, 0.0012345678, 123456.7, 4.4497898, 1.0, 0.1 + 0.2):
        assert fb.ceil_sig(x) >= x and fb.ceil_sig(x) <= x * 1.001
        assert fb.floor_sig(x) <= x


# ---------------------------------------------------------------- cut: the stated minimum is exact
CUT_CASES = [  # every check of cut that a scale can fix
    ("circle-8x8.json", "acrylic-3", "tape", "width"),
    ("circle-8x8.json", "acrylic-3", "separate", "width"),
    ("circle-8x8.json", "pp-0.5", "ligament", "width"),  # the thinnest tile once shrunk by gap/2
    (
        "../../tests/data/heart-8x8.json",
        "card-0.3",
        "ligament",
        "edge",
    ),  # a shrunk tile's edge shorter than a web
]


@pytest.mark.slow
@pytest.mark.parametrize("name,material,kind,limit", CUT_CASES)
def test_cut_at_the_stated_minimum_passes_and_below_fails(
    run_cli, tmp_path, name, material, kind, limit
):
    f = PATTERNS / name
    c = read_pattern(f).contracted[1]
    need = fb.cut_minimum(c, load_material(material), kind)
    assert need.limit == limit
    base = [
        "cut",
        f,
        "--material",
        material,
        "--hinge",
        kind,
        "--formats",
        "dxf",
        "--no-labels",
        "--sheet",
        "3000x3000",
    ]
    if (
        kind == "ligament"
    ):  # cut's own checks and the read-back self-checks run; the layout verifier is left
        # out: its four-corner recovery of a 0.4 mm shrunk corner tile misses by 1.6 mm at some scales near
        # this one (circle-8x8 pp-0.5 at 3.3398 and 3.3405 on main too, 3.34 and 3.36 pass): not a scale limit
        base.append("--no-verify")
    code, _, err = run_cli(*base, "--scale", need.scale, "-o", tmp_path / "ok")
    assert code == 0, err
    code, _, err = run_cli(*base, "--scale", 0.99 * need.scale, "-o", tmp_path / "low")
    assert (
        code == 1
        and f"--scale ≥ {need.scale:g}" in err
        and f"--width ≥ {need.width_mm:g} mm" in err
    )
    assert len(err.strip().splitlines()) == 1 and not (tmp_path / "low").exists()
    # the same with --width
    code, _, err = run_cli(*base, "--width", need.width_mm, "-o", tmp_path / "okw")
    assert code == 0, err
    code, _, err = run_cli(*base, "--width", 0.99 * need.width_mm, "-o", tmp_path / "loww")
    assert code == 1 and "--width ≥" in err


@pytest.mark.slow
def test_cut_auto_picks_the_minimum(run_cli, tmp_path):
    f = DATA / "heart-8x8.json"
    need = fb.cut_minimum(read_pattern(f).contracted[1], load_material("acrylic-3"), "tape")
    for flag in ("--scale", "--width"):
        out = tmp_path / flag.strip("-")
        code, _, err = run_cli("cut", f, flag, "auto", "--formats", "dxf", "-o", out)
        assert code == 0, err
        assert json.loads((out / "manifest.json").read_text())["scale"] == pytest.approx(need.scale)


def test_web_refusal_does_not_contradict_itself(run_cli, tmp_path):
    """The width the message names is below the web it names (it used to print an inscribed circle
    larger than the minimum web while an opening check refused)."""
    f = PATTERNS / "circle-8x8-rigid.json"
    need = fb.cut_minimum(read_pattern(f).contracted[1], load_material("card-0.3"), "tape")
    code, _, err = run_cli(
        "cut",
        f,
        "--material",
        "card-0.3",
        "--hinge",
        "tape",
        "--scale",
        0.9 * need.scale,
        "-o",
        tmp_path / "x",
    )
    assert code == 1
    w = float(err.split(" mm wide")[0].split()[-1])
    web = float(err.split("minimum web ")[1].split()[0])
    assert w < web


def test_ligament_never_for_acrylic():
    need = fb.cut_minimum(
        np.zeros((1, 4, 2)) + [[0, 0], [1, 0], [1, 1], [0, 1]],
        load_material("acrylic-3"),
        "ligament",
    )
    assert need.scale is None and "no scale works" in need.advice()


# ---------------------------------------------------------------- print: plan checks at the minimum
def test_print_minimum_is_exact_for_the_plan_checks():
    p = read_pattern(PATTERNS / "circle-8x8-rigid.json")
    pr = load_printer("prusa-mk4")
    need = fb.print_minimum(p, "tiles-and-strips", pr)
    assert need.possible
    assert fb._plan_error(fb.scaled(p, need.min_scale), "tiles-and-strips", 1, pr) == ""
    assert fb._plan_error(fb.scaled(p, 0.99 * need.min_scale), "tiles-and-strips", 1, pr) != ""
    assert need.max_scale is not None and need.max_scale >= need.min_scale


@pytest.mark.slow
def test_print_refusal_states_the_minimum(run_cli, tmp_path):
    f = PATTERNS / "circle-8x8-rigid.json"
    need = fb.print_minimum(read_pattern(f), "tiles-and-strips", load_printer("prusa-mk4"))
    code, _, err = run_cli("print", f, "--scale", 0.99 * need.min_scale, "-o", tmp_path / "p")
    # a refusal of the plan checks is a check that failed (exit 1), as with --scale auto (it was 2)
    assert code == 1 and f"print at --scale ≥ {need.min_scale:g}" in err, err
    assert not (tmp_path / "p").exists()


# ---------------------------------------------------------------- design rows
LIMITS = F.FabricationLimits(
    min_width_mm=0.3,
    shrink_mm=0.05,
    min_edge_mm=0.02,
    hinge_spacing_mm=0.2,
    hinge_edge_mm=0.25,
    min_hinge_angle_deg=20,
    min_hole_mm=0.1,
    strip_clearance_mm=0.03,
    strip_width_mm=0.4,
    strip_reach_mm=0.4,
)


@settings(max_examples=10, deadline=None)
@given(st.integers(0, 2**31 - 1))
@pytest.mark.slow
def test_fabrication_jacobians_match_finite_differences(seed):
    p = standard_pattern(4, 4, tile_size=1.0)
    stc = Stencils.from_pattern(p)
    x = p.nodes + 0.05 * np.random.default_rng(seed).standard_normal(p.nodes.shape)
    fams = F.families(stc, len(x), LIMITS, 1.0, p.nodes)
    assert {f.name for f in fams} == {
        "fabrication_width",
        "fabrication_shrunk_edges",
        "fabrication_hinge_angles",
        "fabrication_hinge_spacing",
        "fabrication_hinge_edges",
        "fabrication_holes",
        "fabrication_strip_clearance",
    }
    h = 1e-6
    for f in fams:
        r, J = f(x)
        J = J.toarray()
        Jn = np.empty_like(J)
        for i in range(x.size):
            e = np.zeros(x.size)
            e[i] = h
            Jn[:, i] = (f.residual(x + e.reshape(x.shape)) - f.residual(x - e.reshape(x.shape))) / (
                2 * h
            )
        assert np.abs(J - Jn).max() < 1e-6, f.name


def test_width_rows_are_the_shared_definition():
    p = standard_pattern(4, 4, tile_size=1.0)
    stc = Stencils.from_pattern(p)
    x = p.nodes + 0.05 * np.random.default_rng(1).standard_normal(p.nodes.shape)
    for d in (0.0, 0.05):
        rows = F.width_rows(x, stc.tiles, 0.0, d).v.reshape(-1, 4).min(1)
        w = fab.widths(x[stc.tiles], d)
        assert (rows <= w + 1e-12).all() and (
            rows >= w - F.SMOOTH
        ).all()  # the smooth max: never above


@pytest.mark.slow
@pytest.mark.parametrize(
    "rigid", [True, pytest.param(False, marks=pytest.mark.slow)]
)  # one in the quick loop
def test_design_for_acrylic_cuts_with_no_flags(run_cli, tmp_path, rigid):
    """Without the rows the 8x8 circle at 100 mm has 1.45 mm tiles; with them every tile is ≥ 3 mm and
    `cut p.json` (acrylic-3 tape, from the stored intent) passes."""
    f = tmp_path / "p.json"
    code, _, err = run_cli(
        "design",
        "--tiles",
        "8x8",
        "--target",
        "circle",
        "--size",
        "100",
        "--material",
        "acrylic-3",
        *(["--rigid"] if rigid else []),
        "-o",
        f,
    )
    assert code == 0, err
    d = json.loads(f.read_text())["design"]
    assert d["options"]["fabrication"]["material"] == "acrylic-3"
    rep = d["report"]
    assert rep["fabricability"]["thinnest_tile_mm"] >= 3.0 - 1e-9
    assert (
        rep["fabrication"]["rows"]["fabrication_width"] == 256
        and rep["fabrication"]["active"]["fabrication_width"] > 0
    )
    assert rep["fabricability"]["cut"]["acrylic-3"]["tape"]["min_scale"] <= 1.0
    assert "fabrication rows: width" in err
    code, _, err = run_cli("cut", f, "--formats", "dxf", "-o", tmp_path / "cut")
    assert code == 0, err


def test_impossible_request_exits_2_naming_the_smallest_size(run_cli, tmp_path):
    f = tmp_path / "p.json"
    code, _, err = run_cli(
        "design",
        "--tiles",
        "64x64",
        "--target",
        "star",
        "--size",
        "50",
        "--material",
        "acrylic-3",
        "-o",
        f,
    )
    assert code == 2 and len(err.strip().splitlines()) == 1
    assert "the smallest size that could work is --size" in err and "3 mm" in err
    assert not f.exists()


def test_info_shows_fabricability(run_cli):
    code, out, _ = run_cli("info", PATTERNS / "circle-8x8-rigid.json", "--json")
    assert code == 0
    s = json.loads(out)["fabricability"]
    c = read_pattern(PATTERNS / "circle-8x8-rigid.json").contracted[1]
    assert s["thinnest_tile_mm"] == pytest.approx(fab.widths(c).min())
    assert (
        s["cut"]["acrylic-3"]["tape"]["min_scale"]
        == fb.cut_minimum(c, load_material("acrylic-3"), "tape").scale
    )
    assert "prusa-mk4" in s["print"]
    code, out, _ = run_cli("info", PATTERNS / "circle-8x8-rigid.json")
    assert "fabricability: thinnest tile" in out and "acrylic-3: tape ≥" in out


# ---------------------------------------------------------------- printed strips in closed form
STRIP_CASES = ["circle-8x8-rigid", "square-circle-9x9-rigid", "standard-8x8", "heart-8x8"]


def _strip_case(name: str):
    return (
        PATTERNS / f"{name}.json" if (PATTERNS / f"{name}.json").exists() else DATA / f"{name}.json"
    )


@pytest.mark.parametrize("name", STRIP_CASES)
def test_strip_faces_from_the_fold_rules_are_prints_faces(name):
    from fabkiri.fabricate.cut.hinges import assign_faces

    p = read_pattern(_strip_case(name))
    top = p.topology
    pairs = np.concatenate(
        [
            fab.coincident_hinges(
                top.hinge_tiles, top.hinge_corner, top.fold(s).fold_corner_ends, top.n_tiles
            )
            for s in (1, 2)
        ]
    )
    face = fab.strip_faces(np.unique(pairs, axis=0), top.n_hinges)
    assert (face == assign_faces(p, dict(p.contracted)).face).all()


@pytest.mark.parametrize("printer", ["prusa-mk4", "bambu-x1-petg"])
@pytest.mark.parametrize("name", STRIP_CASES)
@pytest.mark.slow
def test_print_bound_is_accepted_and_close_to_the_minimum(name, printer):
    """The closed form: print's plan checks accept it, and it is at most 5 % above their bisected minimum
    (pinned: a lower bound, never above it)."""
    p, pr = read_pattern(_strip_case(name)), load_printer(printer)
    b = fb.print_bound(p, "tiles-and-strips", pr)
    m = fb.print_minimum(p, "tiles-and-strips", pr)
    assert not b.exact and b.min_scale is not None and m.min_scale is not None
    assert fb._plan_error(fb.scaled(p, b.min_scale), "tiles-and-strips", 1, pr) == ""
    assert m.min_scale * (1 - fb.BISECT_RTOL) <= b.min_scale <= 1.05 * m.min_scale
    pin = fb.print_bound(p, "pinned", pr)
    if pin.min_scale is not None:
        assert pin.min_scale <= fb.print_minimum(p, "pinned", pr).min_scale


def test_summary_covers_every_printer_and_style():
    from fabkiri.fabricate.print.printers import available_printers

    s = fb.summary(read_pattern(PATTERNS / "circle-8x8-rigid.json"))
    assert set(s["print"]) == set(available_printers())
    for styles in s["print"].values():
        assert set(styles) == set(fb.PRINT_STYLES)
        assert styles["strips"]["max_scale"] is None and styles["pinned"]["max_scale"] is not None


@pytest.mark.parametrize("state", [1, 2])
def test_strip_rows_met_means_print_accepts(state):
    """The standard 8x8 pattern: where the strip clearance rows of the printed closed state hold, print's plan
    checks for that state pass; 3 % below the plan's own minimum (8.7 mm tiles on prusa-mk4) the rows fail."""
    pr = load_printer("prusa-mk4")
    lim = F.FabricationLimits(
        **design_limits.printer_limits(pr, "tiles-and-strips"), print_state=state
    )
    p = standard_pattern(8, 8, tile_size=1.0)
    stc = Stencils.from_pattern(p)

    def rows(L):  # the rows in units of the tile (1 = L mm)
        return next(
            f
            for f in F.families(stc, len(p.nodes), lim, L, p.nodes)
            if f.name == "fabrication_strip_clearance"
        ).residual(p.nodes)

    sizes = np.linspace(8.4, 9.6, 25)
    ok = [rows(L).min() >= 0 for L in sizes]
    assert len(rows(9.0)) > 0 and any(ok) and not ok[0]
    first = float(sizes[int(np.argmax(ok))])
    assert (
        fb._plan_error(standard_pattern(8, 8, tile_size=first), "tiles-and-strips", state, pr) == ""
    )
    assert (
        fb._plan_error(standard_pattern(8, 8, tile_size=0.97 * 8.7), "tiles-and-strips", state, pr)
        != ""
    )


def test_scaled_limits_scale_every_requirement_and_set_the_margin():
    lim = F.FabricationLimits(
        **design_limits.printer_limits(load_printer("prusa-mk4"), "tiles-and-strips"), source="mk4"
    )
    half = lim.scaled(0.5, 0.02)
    for k, v in lim.to_dict().items():
        if k not in F.NOT_LIMITS:
            assert getattr(half, k) == pytest.approx(0.5 * v)
    assert half.source == "mk4" and half.margin == 0.02 and lim.margin == 0.0
    assert (
        replace(lim, print_state=2).scaled(0.5).print_state == 2
        and not F.FabricationLimits(print_state=2).active
    )
    st_ = Stencils.from_pattern(standard_pattern(4, 4, tile_size=1.0))
    base = standard_pattern(4, 4, tile_size=1.0).nodes
    assert all(f.meta["margin"] == 0.02 for f in F.families(st_, len(base), half, 10.0, base))
    assert all("margin" not in f.meta for f in F.families(st_, len(base), lim, 10.0, base))


@pytest.mark.parametrize("fraction", [0.25, 0.5, 0.75])
def test_a_continuation_step_is_the_full_limits_on_the_design_grown(fraction):
    """A step ``f`` of the continuation asks of a design what the full limits ask of it grown by ``1/f``: every
    length row alike, the strip pads (mm²) included (the hinge angle, no length, is ramped apart). ``scaled``
    takes the pad area times ``f``: a quarter step asked 1 mm² of a 1 x 1.05 mm band, so the 16x16 heart for
    prusa-mk4 had every pad row active and its step stalled."""
    lim = F.FabricationLimits(
        **design_limits.printer_limits(load_printer("prusa-mk4"), "tiles-and-strips")
    )
    assert lim.strip_pad_mm2 > 0 and lim.min_hinge_angle_deg > 0
    assert lim.step(fraction).min_hinge_angle_deg == pytest.approx(
        fraction * lim.min_hinge_angle_deg
    )
    lim = replace(lim, min_hinge_angle_deg=0.0)
    step = lim.step(fraction, 0.02)
    assert step.strip_pad_mm2 == pytest.approx(fraction**2 * lim.strip_pad_mm2)
    assert step.strip_width_mm == pytest.approx(fraction * lim.strip_width_mm)
    assert step.margin == 0.02 and step.print_state == lim.print_state
    pat = standard_pattern(4, 4, tile_size=9.0)  # jittered: no band edge exactly on a tile edge
    x = pat.nodes / 9.0 + np.random.default_rng(3).normal(0.0, 0.01, pat.nodes.shape)
    st_ = Stencils.from_pattern(pat)
    full = {f.name: f.residual(x) for f in F.families(st_, len(x), lim, 9.0 / fraction, x)}
    stepped = {f.name: f.residual(x) for f in F.families(st_, len(x), step, 9.0, x)}
    assert "fabrication_strip_pads" in full and full.keys() == stepped.keys()
    for name, r in full.items():
        np.testing.assert_allclose(stepped[name], r, atol=1e-12, err_msg=name)
    linear = {f.name: f.residual(x) for f in F.families(st_, len(x), lim.scaled(fraction), 9.0, x)}
    assert not np.allclose(linear["fabrication_strip_pads"], full["fabrication_strip_pads"])


@pytest.mark.slow
def test_continuation_is_tried_and_the_kept_design_keeps_the_rows():
    """The 4x4 heart at 80 mm for acrylic-3 misses the shape (it does without rows too, its thinnest tile
    0.46 mm): the continuation from the design without the rows is tried, and the design kept, whichever
    attempt won, has every tile at least 3 mm wide. (The 8x8 heart at 150 mm takes the same attempts, the
    continuation with its refinement and then every guess; docs/speed.md, session 50.)"""
    from fabkiri.api.design import PatternRequest, design_pattern

    out = design_pattern(
        PatternRequest(tiles=(4, 4), target="heart", size=80, material="acrylic-3", quiet=True)
    )
    cont = [a for a in out.report["attempts"] if a["init"].startswith("continuation")]
    assert len(cont) == 1 and cont[0]["hausdorff_max_rel"] > 0
    assert out.valid
    assert out.report["fabricability"]["thinnest_tile_mm"] >= 3.0 - 1e-9
    assert out.report["fabrication"]["min"]["fabrication_width"] >= 0.0


def test_a_design_for_a_printer_that_fits_its_bed_ranks_first():
    """prusa-mk4's bed is 250 x 210 mm: a 240 x 200 mm closed state fits, 200 x 227 mm does not (the refined 8x8
    heart); a valid design that fits ranks above one with a better shape that does not."""
    from fabkiri.api.design import _rank
    from fabkiri.api.design_report import DesignAttempt

    box = lambda w, h: np.array([[[0, 0], [w, 0], [w, h], [0, h]]], float)  # noqa: E731
    assert design_limits.fits_bed(box(240, 200), "prusa-mk4")
    assert not design_limits.fits_bed(box(200, 227), "prusa-mk4")
    assert not design_limits.fits_bed(box(260, 100), "prusa-mk4")

    def outcome(fits, h):
        rep = {
            "checks": {"fits_bed": fits},
            "conformance": {"deployed": {"hausdorff_rel": h}},
            "shape": {"deployed": {"status": "missed"}},
        }
        return DesignAttempt(None, rep, [], True, {})

    assert _rank(outcome(True, 0.06)) < _rank(outcome(False, 0.03))
    assert _rank(outcome(True, 0.03)) < _rank(outcome(True, 0.06))


def test_the_printed_state_is_the_one_that_fits_the_bed():
    """prusa-mk4 (250 x 210 mm): the 16x16 2:1 ellipse at 200 mm closes 176 x 298 mm in state 1 and 215 x 164 mm
    in state 2, so state 2 is printed; state 1 when it fits, and state 1 (reported as not fitting) when neither does."""
    box = lambda w, h: np.array([[[0, 0], [w, 0], [w, h], [0, h]]], float)  # noqa: E731
    assert design_limits.bed_state({1: box(176, 298), 2: box(215, 164)}, "prusa-mk4") == 2
    assert design_limits.bed_state({1: box(200, 200), 2: box(215, 164)}, "prusa-mk4") == 1
    assert design_limits.bed_state({1: box(176, 298), 2: box(300, 100)}, "prusa-mk4") == 1
    assert design_limits.bed_state({1: box(176, 298)}, "prusa-mk4") == 1


def test_print_state_defaults_to_the_designs_intent(monkeypatch):
    """``print`` with no ``--state`` makes the state stored in the design's intent (else 1); ``--state`` overrides."""
    from fabkiri.api import print as api_print

    class Built(Exception):
        pass

    def build(
        pattern, style, state, printer, scale, memo=None
    ):  # the state the job is asked for, before any meshing
        raise Built(state)

    monkeypatch.setattr(api_print, "_build_job", build)
    p = standard_pattern(4, 4, tile_size=30.0)
    for intent, asked, printed in ((2, None, 2), (None, None, 1), (2, 1, 1), (None, 2, 2)):
        design = {"options": {"fabrication": {"state": intent}}} if intent else {}
        with pytest.raises(Built) as got:
            api_print.print_pattern(replace(p, design=design), api_print.PrintOptions(state=asked))
        assert got.value.args == (printed,)


@pytest.mark.slow
def test_ellipse_for_prusa_mk4_prints_the_state_that_fits_with_no_flags(run_cli, tmp_path):
    """The 6x6 2:1 ellipse at 200 mm closes about 114 x 231 mm in one state, off prusa-mk4's 250 x 210 mm bed,
    and about 200 x 96 mm in the other (8x8: 130 x 229 and 199 x 98): the design picks the state that fits,
    raises that state's strip rows, stores it, and `print p.json` prints it; the 3MF slices when prusa-slicer
    is installed."""
    import shutil
    import subprocess

    f = tmp_path / "e.json"
    code, _, err = run_cli(
        "design",
        "--tiles",
        "6x6",
        "--target",
        "ellipse",
        "--size",
        "200",
        "--printer",
        "prusa-mk4",
        "-o",
        f,
    )
    assert code == 0, err
    d = json.loads(f.read_text())
    # which closed state is the wide one is the design's (its basin): the one chosen must fit, the other not
    state = d["design"]["options"]["fabrication"]["state"]
    assert state in (1, 2) and d["design"]["report"]["checks"]["fits_bed"]
    size = {
        s: np.ptp(np.asarray(d["contracted"][str(s)], float).reshape(-1, 2), axis=0) for s in (1, 2)
    }
    w, h = size[state]
    assert w <= 250 and h <= 210
    assert size[3 - state][1] > 210  # as laid out, the other state is off the bed
    code, _, err = run_cli("print", f, "-o", tmp_path / "D")
    assert code == 0, err
    assert f"closed state {state}" in err and (tmp_path / "D" / "e.3mf").exists()
    if shutil.which("prusa-slicer"):
        done = subprocess.run(
            [
                "prusa-slicer",
                "--export-gcode",
                str(tmp_path / "D" / "e.3mf"),
                "-o",
                str(tmp_path / "x.gcode"),
            ],
            capture_output=True,
            text=True,
            timeout=300,
        )
        assert done.returncode == 0 and (tmp_path / "x.gcode").stat().st_size > 0, done.stderr[
            -500:
        ]
