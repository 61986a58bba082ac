"""``fabkiri make`` and ``fabkiri.make``: one run from a target outline to checked files, the tiles it
chooses, what it keeps when a step fails, and bad input refused with nothing written."""

from __future__ import annotations

import json
import os
import shlex
from pathlib import Path
from types import SimpleNamespace

import fabkiri
import pytest
from fabkiri.api import maker_tiles
from fabkiri.design.quad.fabrication import FabricationLimits
from fabkiri.design.targets.lookup import load_target
from fabkiri.errors import FabricationError
from fabkiri.fabricate import design_limits

from ..e2e.test_bad_input import snapshot


@pytest.mark.slow  # ~4 CPU s with the verifier; the quick loop runs the same steps in the test below
@pytest.mark.xdist_group("make-circle-60mm-acrylic")  # its design, deploy shared
def test_make_cuts_a_circle_end_to_end(tmp_path, shared_designs, run_cli):
    # 60 mm circle with acrylic-3 tape: make chooses 6x6 (8x8 tiles would be 4.7 mm, under 2 x 3 mm)
    out = tmp_path / "circle"
    code, _, err = run_cli("make", "circle", "--size", "60", "--material", "acrylic-3", "-o", out)
    assert code == 0, err
    record = json.loads((out / "make.json").read_text())
    assert record["ok"] and record["tiles"] == [6, 6] and record["process"] == "cut"
    assert [s["name"] for s in record["steps"]] == ["design", "cut", "deploy", "report"]
    assert record["figures"]["hausdorff_rel"] <= 0.02
    for name in ("circle.json", "circle.png", "cut/circle.dxf", "cut/manifest.json"):
        assert (out / name).is_file(), name
    for name in ("deploy/energy.png", "deploy/deploy.gif", "report.html"):
        assert (out / name).is_file(), name
    assert "6x6 tiles" in err and "next: cut" in err and "stopped" not in err
    # the files are what the independent verifier accepts
    code, _, err = run_cli("verify", out / "circle.json", "--layout", out / "cut" / "circle.dxf")
    assert code == 0, err


@pytest.mark.slow
@pytest.mark.xdist_group("make-circle-60mm-acrylic")  # its design, deploy shared
def test_make_from_python_keeps_files_until_written(tmp_path, shared_designs):
    result = fabkiri.make("circle", size=60, material="acrylic-3", hinge="separate", tiles=(6, 6))
    assert isinstance(result, fabkiri.MakeResult)
    assert result.ok and result.exit_code == 0 and result.output is None
    assert result.tiles.tiles == (6, 6) and result.tiles.given
    assert result.pattern is not None and len(result.pattern.tiles) == 36
    assert {"circle.json", "cut/manifest.json", "report.html"} <= set(result.files)
    assert json.loads(result.files["cut/manifest.json"])["hinge"] == "separate"
    assert all(s.cpu_s >= 0 and s.wall_s > 0 for s in result.steps)
    assert not any(tmp_path.iterdir())  # nothing written yet
    result.write(tmp_path / "out")
    assert json.loads((tmp_path / "out" / "make.json").read_text())["fabrication"] == (
        "acrylic-3 separate"
    )
    assert "next: cut" in "\n".join(result.summary())
    # how much it opens, from the design's report, under the design step
    design = result.step("design")
    assert design is not None and design.details[0].startswith("opening: holes ")
    assert f"    {design.details[0]}" in result.summary()


def test_min_opening_reaches_the_design(monkeypatch):
    from fabkiri.api import design
    from fabkiri.errors import InputError

    asked = []

    def design_pattern(request, notify=None):
        asked.append(request)
        raise InputError("stop here")

    monkeypatch.setattr(design, "design_pattern", design_pattern)
    with pytest.raises(InputError, match="stop here"):
        fabkiri.make("star", size=150, material="acrylic-3", tiles=(8, 8), min_opening=0.3)
    assert asked[0].min_opening == 0.3 and asked[0].material == "acrylic-3"


def test_a_design_that_opens_little_is_warned_about():
    from fabkiri.api.maker import _opening_lines
    from fabkiri.exchange.pattern_json import read_pattern
    from fabkiri.pattern.opening import opening

    figures = opening(read_pattern(TEMPLATES / "circle-8x8.json")).to_dict()
    lines = _opening_lines({"opening": figures})
    assert lines == [opening(read_pattern(TEMPLATES / "circle-8x8.json")).line()]
    little = {**figures, "hole_fraction": 0.05}
    lines = _opening_lines({"opening": little})
    assert lines[0].startswith("opening: holes 5.0 %")
    assert "opens little" in lines[1] and lines[1].endswith(
        "make --min-opening F sets a floor on it"
    )
    floored = _opening_lines({"opening": {**little, "min_opening": 0.03}})
    assert "opens little" in floored[1] and "sets a floor" not in floored[1]


@pytest.mark.xdist_group("make-circle-60mm-acrylic")  # its design shared
def test_a_refused_cut_stops_and_keeps_the_design(tmp_path, shared_designs, monkeypatch):
    from fabkiri.api import cut

    def refuse(pattern, options, **kw):
        exc = FabricationError("tiles are 1.2 mm wide at their thinnest; smallest --scale 2.5")
        # as the advice work's refusal carries them: checked options, each a command line
        exc.alternatives = [SimpleNamespace(command="fabkiri cut o/circle.json --scale 2.5 -o o/c")]
        raise exc

    monkeypatch.setattr(cut, "cut_files", refuse)
    lines = []
    result = fabkiri.make(
        "circle",
        size=60,
        material="acrylic-3",
        tiles=(6, 6),
        output=tmp_path / "o",
        progress=lines.append,
    )
    assert not result.ok and result.exit_code == 2
    assert [(s.name, s.ok) for s in result.steps] == [("design", True), ("cut", False)]
    assert sorted(p.name for p in (tmp_path / "o").iterdir()) == [
        "circle.json",
        "circle.png",
        "make.json",
    ]
    text = "\n".join(result.summary())
    assert "smallest --scale 2.5" in text and "stopped at cut (exit 2)" in text
    assert any(line.startswith("make: cut failed (exit 2)") for line in lines)
    assert "try: fabkiri cut o/circle.json --scale 2.5 -o o/c" in text
    record = json.loads((tmp_path / "o" / "make.json").read_text())
    assert record["failed_step"] == "cut"
    assert record["alternatives"] == ["fabkiri cut o/circle.json --scale 2.5 -o o/c"]


TEMPLATES = Path(__file__).resolve().parents[2] / "templates" / "patterns"


def _designed_as(monkeypatch, template: str) -> None:
    """make's design step replaced by a shipped pattern (designed without a material, so cut's real
    web rules refuse it at its size and the real advice names what passes); every other step is real."""
    from fabkiri.api import maker
    from fabkiri.exchange.pattern_json import read_pattern

    text = (TEMPLATES / template).read_text()

    def design(result, plan, say):
        result.pattern = read_pattern(TEMPLATES / template)
        return True, 0, "the shipped pattern", {f"{plan.stem}.json": text}, []

    monkeypatch.setattr(maker, "_design", design)


def test_a_real_cut_refusal_prints_its_checked_options(tmp_path, monkeypatch, run_cli):
    # circle-8x8 (100 mm) has tiles 1.32 mm wide: acrylic-3's 3 mm web refuses it at scale 1
    _designed_as(monkeypatch, "circle-8x8.json")
    out = tmp_path / "o"
    args = ("make", "circle", "--size", "100", "--material", "acrylic-3", "--tiles", "8x8")
    code, stdout, err = run_cli(*args, "-o", out)
    assert code == 1, err  # a check failed, as cut's own refusal
    assert "stopped at cut (exit 1)" in err and "thinner than the minimum web 3 mm" in err
    assert "Traceback" not in err
    options = [
        line.split("    # ")[0] for line in stdout.splitlines() if line.startswith("fabkiri ")
    ]
    assert stdout.startswith("# options") and len(options) >= 2
    # each names this run's own files, so it runs as it is
    assert all(f"{out / 'circle.json'}" in line for line in options if " cut " in line)
    assert options[0].startswith(f"fabkiri cut {out / 'circle.json'} --material acrylic-3")
    assert "--scale 2.278" in options[0]
    record = json.loads((out / "make.json").read_text())
    assert record["alternatives"] == options
    assert not (out / "cut").exists()  # the refused step wrote nothing


@pytest.mark.slow
def test_the_first_option_of_a_refused_make_succeeds(tmp_path, monkeypatch, run_cli):
    _designed_as(monkeypatch, "circle-8x8.json")
    out = tmp_path / "o"
    code, stdout, _ = run_cli(
        "make", "circle", "--size", "100", "--material", "acrylic-3", "--tiles", "8x8", "-o", out
    )
    assert code == 1
    first = next(line for line in stdout.splitlines() if line.startswith("fabkiri "))
    argv = shlex.split(first.split("    # ")[0])[1:]
    code, _, err = run_cli(*argv)
    assert code == 0, err
    assert (out / "cut" / "circle.dxf").is_file()


def test_advice_offers_the_make_line_beside_the_design_line(run_cli):
    from fabkiri.api.advice import Ask, alternatives
    from fabkiri.exchange.pattern_json import read_pattern

    ask = Ask(file="p/circle-8x8.json", output="p/cut")
    options = alternatives(read_pattern(TEMPLATES / "circle-8x8.json"), "cut", ask=ask)
    design = next(a for a in options if a.what == "design")
    made = [a for a in options if a.what == "make"]
    assert (
        len(made) == 1 and made[0].checked == design.checked and made[0].changes == design.changes
    )
    assert made[0].command == (
        "fabkiri make circle --size 100 --material acrylic-3 --hinge tape --tiles 8x8 "
        "-o p/circle-8x8-acrylic-3"
    )
    # the same design: target, size, tiles and process as the design line's
    for words in ("--tiles 8x8", "--target circle", "--size 100", "--material acrylic-3"):
        assert words in design.command
    # make cannot say --rigid: no make line for a rigid design (its design line stays)
    rigid = alternatives(read_pattern(TEMPLATES / "circle-8x8-rigid.json"), "cut", ask=ask)
    assert any(a.what == "design" for a in rigid) and not any(a.what == "make" for a in rigid)


@pytest.mark.slow  # a whole make, 8x8 at 100 mm (~5 CPU s)
def test_the_make_line_under_a_cut_refusal_makes_it(tmp_path, monkeypatch, run_cli):
    src = tmp_path / "circle-8x8.json"
    src.write_text((TEMPLATES / "circle-8x8.json").read_text())
    code, out, _ = run_cli("cut", src, "--material", "acrylic-3", "-o", tmp_path / "no")
    assert code == 1
    line = next(x for x in out.splitlines() if x.startswith("fabkiri make "))
    code, _, err = run_cli(*shlex.split(line.split("    # ")[0])[1:])
    assert code == 0, err
    record = json.loads((tmp_path / "circle-8x8-acrylic-3" / "make.json").read_text())
    assert record["ok"] and record["size_mm"] == 100 and record["tiles"] == [8, 8]


@pytest.mark.slow  # a whole make of a 6x6 circle (~9 s on a loaded machine)
@pytest.mark.xdist_group("make-circle-60mm-acrylic")  # its design, deploy shared
def test_a_failed_deploy_check_still_writes_the_report(tmp_path, shared_designs, monkeypatch):
    # shared_designs before monkeypatch: the patch below is undone first, then the memo
    # the real deploy, its outcome marked as one with collisions (a real collision case is not cheap)
    from dataclasses import replace

    from fabkiri.api import deploy

    real = deploy.deploy_pattern

    def colliding(pattern, **kw):
        out = real(pattern, **kw)
        return replace(out, problems=["2 tile overlaps at t = 0.4"])

    monkeypatch.setattr(deploy, "deploy_pattern", colliding)
    result = fabkiri.make(
        "circle", size=60, material="acrylic-3", tiles=(6, 6), output=tmp_path / "o"
    )
    assert not result.ok and result.exit_code == 1 and result.failed.name == "deploy"
    assert [(s.name, s.ok) for s in result.steps] == [
        ("design", True),
        ("cut", True),
        ("deploy", False),
        ("report", True),
    ]
    assert (tmp_path / "o" / "report.html").is_file() and (tmp_path / "o" / "deploy").is_dir()
    text = "\n".join(result.summary())
    assert "make: deploy failed (exit 1)" in text and "report.html documents the design" in text
    assert "2 tile overlaps at t = 0.4" in text and "next:" not in text
    record = json.loads((tmp_path / "o" / "make.json").read_text())
    assert record["failed_step"] == "deploy" and record["exit_code"] == 1


def _limits(material=None, printer=None) -> FabricationLimits:
    fab, _ = design_limits.resolve(material, None, printer, None, None, None, None)
    assert fab is not None
    return fab


def test_tiles_are_the_most_that_stay_comfortably_wide():
    acrylic = _limits(material="acrylic-3")
    feature = maker_tiles.min_feature_mm(acrylic)
    assert feature == pytest.approx(3.0)  # the tape hinge's web
    chosen = []
    for size in (40, 60, 100, 150, 300):
        t = load_target("circle", size)
        c = maker_tiles.choose_tiles(t, acrylic, "acrylic-3 tape")
        n = c.tiles[0]
        assert c.tile_width_mm >= maker_tiles.COMFORT * feature
        bigger = [m for m in maker_tiles.STANDARD_TILES if n < m <= maker_tiles.MAX_AUTO]
        if bigger:  # the next count up would be too thin
            w = maker_tiles.tile_width_mm(t, min(bigger) ** 2)
            assert w < maker_tiles.COMFORT * feature
        chosen.append(n)
    assert chosen == sorted(chosen) and chosen[0] == 4 and chosen[-1] == maker_tiles.MAX_AUTO
    # a printed strip's seam (4 mm strip + 0.4 mm gap) is the printer's thinnest feature
    assert maker_tiles.min_feature_mm(_limits(printer="prusa-mk4")) == pytest.approx(4.4)


def test_tiles_when_none_is_comfortable():
    acrylic = _limits(material="acrylic-3")
    c = maker_tiles.choose_tiles(load_target("circle", 25), acrylic, "acrylic-3 tape")
    assert c.tiles == (4, 4) and "keeps them widest" in c.reason  # 3.9 mm: under 2 x 3 mm
    c = maker_tiles.choose_tiles(load_target("circle", 5), acrylic, "acrylic-3 tape")
    assert c.tiles == (4, 4) and "the smallest size that could work is --size" in c.reason


# ------------------------------------------------------------------ bad input: one line, exit 2, nothing written

BAD = {
    "missing target": (["nothere.csv", "--size", "100", "--material", "acrylic-3"], "nothere.csv"),
    "both processes": (
        ["circle", "--size", "100", "--material", "acrylic-3", "--printer", "prusa-mk4"],
        "not allowed with",
    ),
    "neither process": (["circle", "--size", "100"], "--material"),
    "negative size": (["circle", "--size", "-5", "--material", "acrylic-3"], "positive"),
    "unknown material": (["circle", "--size", "100", "--material", "unobtainium"], "unknown"),
    "hinge with a printer": (
        ["circle", "--size", "100", "--printer", "prusa-mk4", "--hinge", "tape"],
        "--hinge needs --material",
    ),
    "too small for the material": (
        ["circle", "--size", "5", "--material", "acrylic-3"],
        "smallest size that could work is --size",
    ),
    "too many tiles": (
        ["circle", "--size", "3000", "--material", "acrylic-3", "--tiles", "200x200"],
        "is the largest tested",
    ),
    "bad shape tolerance": (
        ["circle", "--size", "100", "--material", "acrylic-3", "--shape-tol", "close"],
        "close",
    ),
    "opening floor not a fraction": (
        ["circle", "--size", "100", "--material", "acrylic-3", "--min-opening", "1.5"],
        "--min-opening is a deployed hole fraction in (0, 1)",
    ),
    "output is a file": (["circle", "--size", "100", "--material", "acrylic-3"], "not a folder"),
    "output is the target": (["t.csv", "--size", "100", "--material", "acrylic-3"], "input"),
}


@pytest.mark.parametrize("case", sorted(BAD))
def test_bad_input_writes_nothing(case, tmp_path, monkeypatch, run_cli, capsys):
    argv, words = BAD[case]
    (tmp_path / "t.csv").write_text("x,y\n0,0\n40,0\n40,30\n0,30\n")
    (tmp_path / "file").write_text("not a folder")
    monkeypatch.chdir(tmp_path)
    out = {"output is a file": "file", "output is the target": "t.csv"}.get(case, "out")
    before = snapshot(tmp_path)
    try:
        code, _, err = run_cli("make", *argv, "-o", out)
    except SystemExit as exc:  # argparse's own usage errors
        code, err = exc.code, capsys.readouterr().err
    lines = err.strip().splitlines()
    assert code == 2 and len(lines) == 1 and words in err, err
    assert "Traceback" not in err and "internal error" not in err
    assert snapshot(tmp_path) == before and not os.path.exists(tmp_path / "out")
