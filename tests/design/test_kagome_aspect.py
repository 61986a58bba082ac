"""The kagome lattice's aspect against the outline's (design/kagome/aspect.py): R x C chosen from the
target when ``--tiles`` is absent, and a one-line warning with a better R x C when the given one does not
suit (docs/kagome.md, "Which R x C")."""

from __future__ import annotations

import numpy as np
import pytest
from fabkiri.design.kagome import aspect as KA
from fabkiri.design.targets import lookup as TG
from fabkiri.design.targets.lookup import load_target


@pytest.mark.parametrize("rows, cols", [(2, 2), (4, 5), (6, 11), (8, 8), (5, 19)])
def test_the_lattice_aspect_is_c_over_root3_r(rows, cols):
    assert KA.lattice_aspect(rows, cols) == pytest.approx(cols / (np.sqrt(3.0) * rows), rel=1e-12)


@pytest.mark.parametrize("name", ["circle", "ellipse", "heart", "star", "rectangle"])
@pytest.mark.parametrize("n", [36, 66, 135, 252])
def test_the_suggested_lattice_has_the_outline_aspect_and_about_the_tile_count(name, n):
    fit = KA.suggest(load_target(name, 120.0), n)
    rows, cols = fit.tiles
    assert abs(np.log(fit.lattice / (KA.WIDER * fit.target))) <= 0.06 and rows >= 2 and cols >= 2
    assert abs(rows * cols - n) <= KA.COUNT_SLACK * n and rows * cols <= KA.MAX_TILES


def test_the_egg_outline_gets_a_tall_lattice():
    fit = KA.suggest(load_target("tests/data/egg.csv", 120.0))
    assert fit.target == pytest.approx(0.754, abs=1e-3) and fit.miss <= 0.12
    assert fit.tiles[0] > fit.tiles[1] / np.sqrt(3.0)  # taller than a square lattice of its columns


def test_a_lattice_that_does_not_suit_the_outline_gets_one_line_naming_a_better_one():
    circle, ellipse = TG.circle().scaled_to(120.0), TG.ellipse().scaled_to(120.0)
    line = KA.advice(8, 8, circle)  # the 8x8 circle: 0.58 wide for 1 high
    assert line is not None and "\n" not in line and "try --tiles 6x11" in line
    assert KA.aspect_fit(6, 11, circle).miss < KA.aspect_fit(8, 8, circle).miss
    assert KA.advice(6, 11, circle) is None and KA.advice(5, 19, ellipse) is None
    assert "try --tiles 4x14" in (KA.advice(6, 11, ellipse) or "")
    assert "try --tiles 11x15" in (KA.advice(9, 15, load_target("tests/data/egg.csv", 180.0)) or "")


def test_the_suggestion_is_a_little_wider_than_the_outline():
    """Measured (docs/kagome.md): circle 6x11 (1.06 wide for 1 high) 1.23 %, 6x10 (0.96) 2.84 %; ellipse 2:1
    4x14 (2.02) 1.32 %, 4x15 (2.17) 1.55 %, 4x13 (1.88) 2.25 %."""
    circle, ellipse = TG.circle().scaled_to(120.0), TG.ellipse().scaled_to(120.0)
    assert KA.suggest(circle, 66).tiles == (6, 11) and KA.suggest(ellipse, 66).tiles == (4, 14)
    assert KA.advice(6, 10, circle) is None  # 4 % narrower: within the tolerance, no warning


def test_the_front_door_chooses_the_lattice_or_notes_a_warning():
    from fabkiri.api.kagome import choose_lattice

    circle = TG.circle().scaled_to(120.0)
    rows, cols, rep = choose_lattice(None, circle)
    assert (rows, cols) == KA.suggest(circle).tiles and rep["chosen"] and rep["miss"] <= 0.1
    assert f"{rows}x{cols} chosen from the outline" in rep["note"]
    rows, cols, rep = choose_lattice((8, 8), circle)  # the user's lattice is kept, with a warning
    assert (rows, cols) == (8, 8) and not rep["chosen"]
    assert rep["note"].startswith("warning:") and "6x11" in rep["note"]
    assert choose_lattice((6, 11), circle)[2]["note"] is None


def test_cli_a_refused_lattice_gets_no_aspect_advice(tmp_path, run_cli):
    out = tmp_path / "k.json"
    argv = ["design", "--lattice", "kagome", "--target", "circle", "-o", out, "--tiles"]
    for tiles, why in (("1x1", "at least 2x2"), ("300x300", "largest tested")):
        code, _, err = run_cli(*argv, tiles)
        assert code == 2 and why in err and len(err.strip().splitlines()) == 1 and not out.exists()


def test_cli_quad_design_without_tiles_is_refused_in_one_line(tmp_path, run_cli):
    code, _, err = run_cli("design", "--target", "circle", "-o", tmp_path / "q.json")
    assert code == 2 and "quad designs need --tiles" in err and len(err.strip().splitlines()) == 1
    assert not (tmp_path / "q.json").exists()


@pytest.mark.slow  # no group: without --tiles the 6x11 is cut to the circle, a design no other test makes
def test_the_suggested_lattice_fits_better_than_the_one_that_does_not_suit(tmp_path, run_cli):
    """The issue's case: 8x8 kagome circle (measured 6.1 %) warned, and the suggested 6x11 nearer."""
    import json

    found = {}
    for tiles in ("8x8", None):
        out = tmp_path / f"{tiles}.json"
        argv = ["design", "--lattice", "kagome", "--target", "circle", "--size", "120", "-o", out]
        code, _, err = run_cli(*argv, *(["--tiles", tiles] if tiles else []))
        rep = json.loads(out.read_text())["design"]["report"]
        found[tiles] = (code, err, rep)
    code, err, rep = found["8x8"]
    assert "warning: a 8x8 kagome" in err and "try --tiles 6x11" in err
    assert "chosen from the outline" in found[None][1]
    assert found[None][2]["conformance"]["hausdorff_rel"] < rep["conformance"]["hausdorff_rel"]
