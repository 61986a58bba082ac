"""How much a pattern opens (issue 32, item 4): the figures, the ``--min-opening`` row, design and info."""

from __future__ import annotations

import json

import numpy as np
import pytest
from fabkiri.cli.main import main
from fabkiri.design.core.stencils import Stencils
from fabkiri.design.quad.opening_rows import opening_families, opening_row
from fabkiri.mechanics.contract import with_contracted_states
from fabkiri.pattern import geometry
from fabkiri.pattern.kinds.quad.lattice import standard_pattern
from fabkiri.pattern.model import Pattern
from fabkiri.pattern.opening import OPENS_LITTLE, Opening, opening
from hypothesis import given, settings
from hypothesis import strategies as st

from ..conftest import TEMPLATES
from .kagome_routes import ACRYLIC_OPEN_GROUP, ACRYLIC_OPEN_HEART

DATA = TEMPLATES.parent / "tests" / "data"


def _standard(rows: int, cols: int, psi_deg: float, tile: float = 10.0) -> Pattern:
    return with_contracted_states(standard_pattern(rows, cols, tile_size=tile, angle_deg=psi_deg))


def _closed_form(rows: int, cols: int, psi_deg: float) -> float:
    """Rotating squares at ψ: (M-1)(N-1) rhombus holes of angle 2ψ among MN unit squares."""
    holes = (rows - 1) * (cols - 1) * np.sin(np.radians(2 * psi_deg))
    return holes / (rows * cols + holes)


@pytest.mark.parametrize("rows,cols,psi", [(8, 8, 45.0), (4, 6, 20.0), (6, 4, 60.0), (5, 7, 10.0)])
def test_standard_pattern_figures_match_the_closed_form(rows, cols, psi):
    o = opening(_standard(rows, cols, psi))
    f = _closed_form(rows, cols, psi)
    assert o.hole_fraction == pytest.approx(f, rel=1e-9)
    assert o.tile_area_mm2 == pytest.approx(rows * cols * 100.0, rel=1e-9)
    for s in (1, 2):  # both closed states are compact: the area shrinks by the holes
        assert o.area_ratio[s] == pytest.approx(1.0 / (1.0 - f), rel=1e-6)
    if rows * cols % 2 == 0:  # as many tiles turn each way: the mean turn is the pattern's own
        assert o.turn_deg[1] == pytest.approx(psi, abs=1e-6)
        assert o.turn_deg[2] == pytest.approx(90.0 - psi, abs=1e-6)
    assert o.opens_little == (f < OPENS_LITTLE)


def test_a_nearly_closed_pattern_warns_and_an_open_one_does_not():
    shut, open_ = opening(_standard(6, 6, 2.0)), opening(_standard(6, 6, 45.0))
    assert shut.hole_fraction < OPENS_LITTLE <= open_.hole_fraction
    assert "opens little" in (shut.warning() or "")
    assert open_.warning() is None
    assert Opening.from_dict(json.loads(json.dumps(shut.to_dict()))) == shut


@settings(max_examples=25, deadline=None)
@given(
    psi=st.floats(5.0, 85.0),
    turn=st.floats(-np.pi, np.pi),
    turn_closed=st.floats(-np.pi, np.pi),
    scale=st.floats(0.05, 20.0),
    shift=st.tuples(st.floats(-500, 500), st.floats(-500, 500)),
)
def test_figures_do_not_depend_on_placement_or_units(psi, turn, turn_closed, scale, shift):
    """Moving, turning or scaling the pattern, and storing a closed state at another placement, leaves
    the hole fraction, the area ratios and the turns as they were."""
    p = _standard(4, 4, psi)
    ref = opening(p)
    moved = Pattern(
        nodes=geometry.rotate(p.nodes, turn) * scale + np.array(shift),
        tiles=p.tiles,
        contracted={
            s: geometry.rotate(c.reshape(-1, 2), turn_closed).reshape(c.shape) * scale
            for s, c in p.contracted.items()
        },
        lattice=p.lattice,
    )
    o = opening(moved)
    assert o.hole_fraction == pytest.approx(ref.hole_fraction, rel=1e-7, abs=1e-12)
    for s in (1, 2):
        assert o.area_ratio[s] == pytest.approx(ref.area_ratio[s], rel=1e-6)
        assert o.turn_deg[s] == pytest.approx(ref.turn_deg[s], abs=1e-6)
    assert o.sheet_area_mm2 == pytest.approx(ref.sheet_area_mm2 * scale**2, rel=1e-7)


# ------------------------------------------------------------------ the --min-opening row


def _lattice_and_nodes(rows=4, cols=5, seed=0):
    std = standard_pattern(rows, cols, tile_size=1.0)
    stc = Stencils.from_pattern(std)
    x = std.nodes + np.random.default_rng(seed).normal(0.0, 0.05, std.nodes.shape)
    return std, stc, x


def test_the_row_gradient_matches_finite_differences():
    std, stc, x = _lattice_and_nodes()
    (fam,) = opening_families(stc, len(x), 0.3, std.nodes)
    r, J = fam(x)
    J = J.toarray()
    assert J.shape == (1, 2 * len(x))
    h = 1e-6
    fd = np.zeros(2 * len(x))
    for i in range(2 * len(x)):
        xp, xm = x.copy(), x.copy()
        xp.flat[i] += h
        xm.flat[i] -= h
        fd[i] = (fam.residual(xp)[0] - fam.residual(xm)[0]) / (2 * h)
    assert np.abs(J[0] - fd).max() <= 1e-7 * max(1.0, np.abs(fd).max())
    assert np.count_nonzero(J) > 0.9 * 2 * len(x)  # every node of a tile or a hole is in it
    assert fam.residual(x) == pytest.approx(r)


@pytest.mark.parametrize("psi", [10.0, 30.0, 45.0])
def test_the_row_is_nonnegative_exactly_when_the_reported_fraction_meets_the_floor(psi):
    std = standard_pattern(5, 5, tile_size=1.0, angle_deg=psi)
    stc = Stencils.from_pattern(std)
    holes = stc.hole_nodes
    from fabkiri.design.quad.fabrication import ccw_polygons

    ccw = ccw_polygons(holes, standard_pattern(5, 5, tile_size=1.0).nodes)
    f = opening(std).hole_fraction
    for floor in (0.5 * f, f * (1 - 1e-6), f * (1 + 1e-6), min(0.99, 1.5 * f)):
        g = opening_row(std.nodes, stc.tiles, ccw, floor)[0][0]
        assert (g >= 0) == (f >= floor)


def test_no_row_without_a_floor():
    std, stc, x = _lattice_and_nodes()
    assert opening_families(stc, len(x), None, std.nodes) == []


# ------------------------------------------------------------------ through the CLI


def test_design_reports_the_opening_and_meets_the_floor(tmp_path, run_cli):
    out = tmp_path / "c.json"
    code, _, err = run_cli(
        "design",
        "--tiles",
        "6x6",
        "--target",
        "circle",
        "--min-opening",
        "0.4",
        "--no-preview",
        "-o",
        out,
    )
    data = json.loads(out.read_text())
    o = data["design"]["report"]["opening"]
    assert o["hole_fraction"] >= 0.4 and o["min_opening"] == 0.4
    assert data["design"]["options"]["min_opening"] == 0.4
    assert "opening: holes" in err and "opens little" not in err
    assert code == 0


@pytest.mark.slow
def test_design_warns_when_it_opens_little_and_names_the_floor(tmp_path, run_cli):
    out = tmp_path / "s.json"
    _, _, err = run_cli("design", "--tiles", "8x8", "--target", "star", "--no-preview", "-o", out)
    warn = [line for line in err.splitlines() if "opens little" in line]
    o = json.loads(out.read_text())["design"]["report"]["opening"]
    assert o["hole_fraction"] < OPENS_LITTLE
    assert len(warn) == 1 and warn[0].startswith("fabkiri: warning:") and "--min-opening" in warn[0]


@pytest.mark.parametrize("value", ["0", "1", "1.5", "-0.2", "nan", "x"])
def test_a_bad_floor_is_refused_in_one_line(tmp_path, capsys, value):
    out = tmp_path / "x.json"
    with pytest.raises(SystemExit) as exc:
        main(
            [
                "design",
                "--tiles",
                "4x4",
                "--target",
                "circle",
                "--min-opening",
                value,
                "-o",
                str(out),
            ]
        )
    assert exc.value.code == 2
    assert len(capsys.readouterr().err.strip().splitlines()[-1:]) == 1
    assert not out.exists()


def test_info_reports_the_opening_in_text_and_json(run_cli):
    path = TEMPLATES.parent / "tests" / "data" / "heart-16x16-rigid.json"
    code, out, err = run_cli("info", path)
    assert code == 0 and "opening      holes 5.1 %" in out
    assert err.count("opens little") == 1
    code, out, _ = run_cli("info", path, "--json")
    o = json.loads(out)["opening"]
    assert o["hole_fraction"] == pytest.approx(0.0512, abs=5e-4)
    assert set(o["turn_deg"]) == {"1", "2"}


@pytest.mark.slow
def test_the_report_shows_the_opening_and_warns_when_it_opens_little():
    from fabkiri.exchange.pattern_json import read_pattern
    from fabkiri.render.report import build_report

    page = build_report(
        read_pattern(TEMPLATES.parent / "tests" / "data" / "heart-16x16-rigid.json")
    )
    assert "<h3>opening</h3>" in page and "5.1 %" in page and "opens little" in page
    wide = build_report(_standard(4, 4, 45.0))
    assert "<h3>opening</h3>" in wide and "opens little" not in wide


# ------------------------------------------------------------------ hard outlines (issue 32, item 5)


def _load(name: str):
    from fabkiri.design.targets.lookup import load_target

    return load_target(str(DATA / f"{name}.csv"), None)


def test_the_l_and_the_crescent_have_one_deep_pocket_and_a_circle_none():
    from fabkiri.design.targets.pockets import pockets

    (ell,) = pockets(_load("letter-l"))
    assert ell.depth_mm == pytest.approx(25.0) and ell.area_mm2 == pytest.approx(35 * 75 / 2)
    assert ell.deepest == pytest.approx((-5.0, -25.0))  # the inner corner (25, 25), centred
    (hollow,) = pockets(_load("crescent"))
    assert 25.0 < hollow.depth_mm < 35.0
    assert pockets(load_target_named("circle")) == []


def test_a_pocket_is_named_where_the_worst_miss_lies_on_its_side_though_little_of_it_is_covered():
    import shapely
    from fabkiri.design.core.conformance import target_polygon
    from fabkiri.design.targets.pockets import COVERED, pocket_covered, pockets

    ell = _load("letter-l")
    (pocket,) = pockets(ell)
    own = shapely.Polygon(target_polygon(ell))  # covers none of its pocket; its hull all of it
    outline, hull = (np.asarray(p.exterior.coords) for p in (own, own.convex_hull))
    assert pocket_covered(ell, outline) is None
    found = pocket_covered(ell, hull)
    assert found is not None and found[1] >= COVERED
    # the worst miss on the pocket's side (x = -5, the L's inner edge, centred), away from its ends
    found = pocket_covered(ell, outline, (-5.0, -17.275))
    assert found is not None and found[0] == pocket and found[1] < COVERED
    assert pocket_covered(ell, outline, (-30.0, -50.0)) is None  # the L's far corner


def load_target_named(name: str):
    from fabkiri.design.targets.lookup import load_target

    return load_target(name, 100.0)


def _missed(**extra) -> dict:
    return {
        "hausdorff_mm": 30.0,
        "hausdorff_rel": 0.3,
        "tol_mm": 2.0,
        "tol_rel": 0.02,
        "by_mm": 28.0,
        "local_minimum": True,
        "spacings": 6.0,
        **extra,
    }


CONF = {"worst": {"at": [27.8, 7.8]}}


def test_a_missed_shape_never_advises_a_guess_already_tried():
    from fabkiri.design.core.conformance import describe_miss

    some = describe_miss(
        "deployed", _missed(tried_inits=["conformal", "rescaled", "standard"]), CONF
    )
    assert "try another --init" not in some
    assert "not tried: --init coarse" in some
    every = describe_miss(
        "deployed", _missed(tried_inits=["conformal", "rescaled", "standard", "coarse"]), CONF
    )
    assert "not tried" not in every and "try another" not in every
    assert "every initial guess was tried" in every
    pocket = {"depth_mm": 25.0, "deepest": [-5.0, -25.0], "area_mm2": 1312.5}
    why = describe_miss("deployed", _missed(tried_inits=["coarse"], pocket=pocket), CONF)
    assert (
        "pocket of the target 25 mm deep" in why
        and "covering 100 %" in why
        and "(-5.0, -25.0)" in why
    )
    assert "not tried: --init standard, rescaled, conformal" in why


@pytest.mark.slow  # a 15x15 rigid design and its refinement; the row's quick test is the 6x6 circle
def test_a_star_at_150_mm_opens_30_percent_and_still_meets_its_shape():
    """Every guess misses under the floor (rescaled 3.0 %, standard 14 %) and the minimax refinement under
    it meets the shape (1.81 %) and is kept, as for the 16x16 star; the 15x15 star's figures are the same
    with the tests' BLAS kernel pin and without it (docs/speed.md, session 50)."""
    from fabkiri.api.design import PatternRequest, design_pattern

    out = design_pattern(
        PatternRequest(tiles=(15, 15), target="star", size=150, rigid=True, min_opening=0.3)
    )
    o = out.report["opening"]
    assert o["hole_fraction"] >= 0.3
    assert out.report["conformance"]["deployed"]["hausdorff_rel"] <= 0.02
    assert out.success and out.exit_code == 0
    assert any(a["init"].startswith("minimax refinement") for a in out.report["attempts"])


@pytest.mark.slow  # 6x6 designs from every initial guess; the wording's quick test is above
def test_the_letter_l_miss_names_its_pocket_and_no_guess_already_tried(tmp_path, run_cli):
    # 6x6 misses as 8x8 did: the guess's miss runs across the pocket, which is named (docs/speed.md); by
    # default the pocket attempt (a lattice corner in it, docs/design-solver.md "Session 53 (boot53)") comes
    # closer than every guess, and the bent strip after it ("Session 54 (u54)") meets the shape and is kept
    out = tmp_path / "l.json"
    args = (
        "design",
        "--tiles",
        "6x6",
        "--target",
        DATA / "letter-l.csv",
        "--no-preview",
        "-o",
        out,
    )
    code, _, err = run_cli(*args, "--init", "rescaled")
    (line,) = [x for x in err.splitlines() if "shape missed" in x]
    assert code == 1
    assert "pocket of the target 25 mm deep" in line
    assert "try another --init" not in line
    tried = json.loads(out.read_text())["design"]["report"]["shape"]["deployed"]["tried_inits"]
    assert tried and all(f"--init {i}" not in line.split("not tried")[-1] for i in tried)
    code, _, _ = run_cli(*args)
    report = json.loads(out.read_text())["design"]["report"]
    h = {a["init"]: a["hausdorff_max_rel"] for a in report["attempts"] if "hausdorff_max_rel" in a}
    assert h["pocket"] < min(v for k, v in h.items() if k not in ("pocket", "strip"))
    assert code == 0 and h["strip"] <= 0.02 and report["strip"]["asked"] == [6, 6]
    assert report["conformance"]["deployed"]["hausdorff_rel"] == pytest.approx(h["strip"])


def test_a_sweep_passes_the_floor_by_name():
    from fabkiri.sweep.job import request_of
    from fabkiri.sweep.spec import PARAMS

    req = request_of({"tiles": "4x4", "target": "circle", "min_opening": 1 / 4})
    assert req.min_opening == 0.25 and isinstance(req.min_opening, float)
    assert float in PARAMS["min_opening"]


def test_the_kagome_floor_is_soft_and_one_sided():
    from fabkiri.design.kagome import opening as KO
    from fabkiri.pattern.kinds.kagome.lattice import standard_kagome

    std = standard_kagome(3, 5, tile_size=1.0)
    f = opening(std, closed={}).hole_fraction
    (below,) = KO.families(std, 0.5 * f, weight=10.0)
    (above,) = KO.families(std, min(0.95, f + 0.1), weight=10.0)
    assert below.residual(std.nodes)[0] == 0.0
    r, J = above(std.nodes)
    assert r[0] < 0 and J.nnz > 0
    assert KO.accepting(lambda p: True, f + 0.1)(std) is False
    assert KO.accepting(lambda p: True, 0.5 * f)(std) is True


@pytest.mark.slow  # the soft row's quick test is above
@pytest.mark.xdist_group(ACRYLIC_OPEN_GROUP)  # one design with test_kagome_fab.py's acrylic heart
def test_a_kagome_design_opens_at_least_its_floor(tmp_path, run_cli, shared_kagome_designs):
    """A 4x7 heart at 80 mm whose free design opens 50 % of its sheet, designed under a 55 % floor (and
    acrylic-3's web: ``ACRYLIC_OPEN_HEART``, one design with test_kagome_fab.py)."""
    out = tmp_path / "k.json"
    code, _, err = run_cli(*ACRYLIC_OPEN_HEART, "-o", out)
    data = json.loads(out.read_text())
    o = data["design"]["report"]["opening"]
    assert o["hole_fraction"] >= 0.55 and o["min_opening"] == 0.55
    assert "opening: holes" in err and "below --min-opening" not in err
    assert code == (0 if data["design"]["valid"] else 1)  # the 4x7 heart misses 2 % either way
