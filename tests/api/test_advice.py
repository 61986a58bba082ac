"""Refusals that lead somewhere (issue 32, item 3): a ``cut`` or ``print`` refusal names every option that
passes the same checks at the size asked for, each line runs, and the refusal exits 1 whatever the flags."""

from __future__ import annotations

import json
import re
import shlex
from pathlib import Path

import pytest
from fabkiri.api.advice import CUT_GATE, DESIGN_GATE, PRINT_GATE, Refused, alternatives
from fabkiri.api.cut import cut_files
from fabkiri.api.print import PrintOptions, print_pattern
from fabkiri.exchange.pattern_json import read_pattern
from fabkiri.fabricate import fabricability as fb
from fabkiri.fabricate.cut.materials import load_material
from fabkiri.fabricate.cut.sheets import CutOptions
from fabkiri.fabricate.print.printers import load_printer
from fabkiri.templates import template_dir

PATTERNS = template_dir("patterns")
DATA = Path(__file__).parents[1] / "data"


def _options(out: str, err: str) -> list[list[str]]:
    """The suggested command lines of a refusal (stdout), as argument lists without the leading
    ``fabkiri``; the refusal itself stays one line on stderr."""
    assert len(err.strip().splitlines()) == 1 and err.startswith("fabkiri: error: "), err
    lines = out.strip().splitlines()
    assert lines[0].startswith("# options (each passes the same checks")
    cmds = [ln.split("    # ")[0].strip() for ln in lines[1:]]
    assert cmds and all(c.startswith("fabkiri ") for c in cmds), lines
    return [shlex.split(c)[1:] for c in cmds]


def _with_output(argv: list[str], out) -> list[str]:
    i = argv.index("-o")
    return [*argv[: i + 1], str(out), *argv[i + 2 :]]


@pytest.mark.slow
def test_every_cut_option_named_under_a_refusal_cuts(run_cli, tmp_path):
    """The 8x8 heart at 100 mm is too thin for acrylic-3: the refusal (exit 1) names acrylic-3 at its
    smallest scale and the materials that cut it at this size; each line, run, cuts (exit 0)."""
    src = DATA / "heart-8x8.json"
    code, out, err = run_cli("cut", src, "--formats", "dxf", "-o", tmp_path / "no")
    assert code == 1 and not (tmp_path / "no").exists()
    runs = [a for a in _options(out, err) if a[0] == "cut"]
    assert any("7.378" in a for a in runs) and any("pp-0.5" in a for a in runs)
    for k, argv in enumerate(runs):
        assert "--formats" in argv  # the flags given are kept
        code, _, out = run_cli(*_with_output(argv, tmp_path / f"ok{k}"))
        assert code == 0, (argv, out)


def test_cut_alternatives_pass_the_rules_and_the_asked_one_does_not():
    p = read_pattern(DATA / "heart-8x8.json")
    got = alternatives(p, "cut", 1.0)
    assert got and {a.checked for a in got} <= {CUT_GATE, DESIGN_GATE}
    c = p.contracted[1]
    assert fb.cut_minimum(c, load_material("acrylic-3"), "tape").scale > 1.0
    for a in got:
        ch = a.changes
        if a.what == "material":
            assert fb.cut_minimum(c, load_material(ch["material"]), ch["hinge"]).scale <= 1.0
            assert a.command.startswith("fabkiri cut pattern.json --material ")
        elif a.what == "scale":
            assert ch["scale"] == fb.cut_minimum(c, load_material("acrylic-3"), "tape").scale
    assert [a.what for a in got][0] == "scale" and got[-1].what == "design"
    assert [a.command for a in alternatives(p, "cut", size_mm=100.0)] == [a.command for a in got]
    assert "--tiles 8x8 --target heart --size 100 --material acrylic-3" in got[-1].command


def test_a_ligament_refusal_exits_1_with_and_without_scale_auto(run_cli, tmp_path):
    """acrylic-3 cannot be cut as a ligament sheet at any scale: it used to exit 2 at a given scale
    (the ligament kind's own error) and 1 with --scale auto; now 1 both ways, with the same options."""
    src = PATTERNS / "circle-8x8.json"
    errs = []
    for scale in ("10", "auto"):
        code, out, err = run_cli(
            "cut", src, "--hinge", "ligament", "--scale", scale, "-o", tmp_path / scale
        )
        assert code == 1 and not (tmp_path / scale).exists(), err
        errs.append(err)
        runs = [" ".join(a) for a in _options(out, err)]
        assert any("card-0.3 --hinge ligament" in r for r in runs)
        assert any("acrylic-3 --hinge tape" in r for r in runs)
    with pytest.raises(Refused) as exc:
        cut_files(
            read_pattern(src),
            CutOptions(material=load_material("acrylic-3"), hinge="ligament", scale=10.0),
        )
    assert exc.value.exit_code == 1 and all(a.checked == CUT_GATE for a in exc.value.alternatives)


@pytest.mark.slow
def test_a_print_refusal_exits_1_with_and_without_scale_auto(run_cli, tmp_path):
    """The 8x8 heart at 100 mm: prusa-mk4 tiles-and-strips needs more scale than its bed takes. Without
    --scale auto this exited 2, with it 1: now 1 both ways."""
    src = DATA / "heart-8x8.json"
    for extra in ((), ("--scale", "auto")):
        code, out, err = run_cli("print", src, *extra, "-o", tmp_path / "no")
        assert code == 1 and "the bed of prusa-mk4 takes at most" in err, err
        assert not (tmp_path / "no").exists()
        assert any(a[0] == "print" and "strips" in a for a in _options(out, err))


@pytest.mark.slow
def test_every_print_option_named_under_a_refusal_prints(run_cli, tmp_path):
    """A 3x3 standard pattern of 3 mm tiles is too small to print on prusa-mk4: the refusal names its
    smallest scale and every printer and style that prints it at this size (none: then at the smallest
    scale each accepts); each line, run, prints (exit 0)."""
    from fabkiri.exchange import pattern_json as io
    from fabkiri.mechanics import with_contracted_states
    from fabkiri.pattern import standard_pattern

    src = tmp_path / "small.json"
    io.write_pattern(with_contracted_states(standard_pattern(3, 3, tile_size=3.0)), src)
    code, out, err = run_cli("print", src, "-o", tmp_path / "no")
    assert code == 1 and "print at --scale ≥" in err and not (tmp_path / "no").exists()
    runs = [a for a in _options(out, err) if a[0] == "print"]
    assert len(runs) >= 4 and {a[a.index("--printer") + 1] for a in runs} >= {
        "prusa-mk4",
        "prusa-xl",
    }
    for k, argv in enumerate(runs):
        code, _, got = run_cli(*_with_output(argv, tmp_path / f"ok{k}"))
        assert code == 0, (argv, got)


def test_print_alternatives_pass_the_plan_checks():
    p = read_pattern(PATTERNS / "circle-8x8.json")
    got = alternatives(p, "print", 5.0, options=PrintOptions(printer="prusa-mk4"))
    assert got and {a.checked for a in got} <= {PRINT_GATE, DESIGN_GATE}
    for a in got:
        if a.what in ("printer", "scale"):
            ch = a.changes
            pr = load_printer(ch["printer"])
            assert fb.print_refusal(p, ch["style"], pr, 1, ch["scale"]) == ""
    assert fb.print_refusal(p, "tiles-and-strips", load_printer("prusa-mk4"), 1, 5.0) != ""


@pytest.mark.slow
def test_scale_auto_names_the_limit_at_the_scale_it_reached(run_cli, tmp_path):
    """A strip pad that no scale makes large enough (a 28.5° hinge corner: the pad of a fixed-size strip
    stays below 4 mm²) is reported at the largest scale tried, not with its scale-1 area (0.00 mm²)."""
    src = DATA / "heart-16x16-rigid.json"
    pr = load_printer("prusa-mk4")
    need = fb.print_minimum(read_pattern(src), "tiles-and-strips", pr)
    assert need.min_scale is None and "at --scale 512:" in need.limit
    area = float(re.search(r"\(([0-9.]+) mm² < 4\.00 mm²\)", need.limit).group(1))
    assert 3.0 < area < 4.0
    code, _, err = run_cli("print", src, "--scale", "auto", "-o", tmp_path / "no")
    assert code == 1 and "at --scale 512:" in err and "0.00 mm²" not in err


@pytest.mark.slow
def test_the_design_line_under_a_refusal_designs_a_pattern_that_cuts(run_cli, tmp_path):
    """A 6x6 circle at 40 mm designed without a material is too thin for acrylic-3; the refusal names
    `fabkiri design ... --size 40 --material acrylic-3`, which designs (exit 0) a pattern that cuts with
    no flags at its size."""
    src = tmp_path / "c66.json"
    code, _, err = run_cli(
        "design", "--tiles", "6x6", "--target", "circle", "--size", "40", "--no-preview", "-o", src
    )
    assert code == 0, err
    code, out, err = run_cli("cut", src, "-o", tmp_path / "no")
    assert code == 1
    design = [a for a in _options(out, err) if a[0] == "design"]
    assert len(design) == 1 and "--size" in design[0] and "acrylic-3" in design[0]
    code, _, err = run_cli(*design[0], "--no-preview")
    assert code == 0, err
    made = design[0][design[0].index("-o") + 1]
    fab = json.loads(open(made).read())["design"]["options"]["fabrication"]
    assert fab["material"] == "acrylic-3" and fab["size_mm"] == 40.0
    code, _, err = run_cli("cut", made, "-o", tmp_path / "ok")
    assert code == 0, err


def test_print_refusal_from_the_api_carries_the_options():
    p = read_pattern(DATA / "heart-8x8.json")
    with pytest.raises(Refused) as exc:
        print_pattern(p, PrintOptions())
    assert exc.value.exit_code == 1 and exc.value.alternatives
    assert str(exc.value) == exc.value.reason and "\n" not in exc.value.reason
    lines = exc.value.option_lines()
    assert len(lines) == len(exc.value.alternatives) + 1
    assert all(ln.startswith("fabkiri ") for ln in lines[1:])


def test_a_refused_print_asks_the_bed_first_and_bisects_once(monkeypatch):
    """The refusal's advice asks the bed before the plan checks (a pinned 32x32 plan past the bed took
    5 s of geometry), and the smallest scale of the printer and style asked for is bisected once, for
    the refusal and its advice alike (issue 36: the 32x32 refusal did both twice)."""
    p = read_pattern(DATA / "heart-8x8.json")
    planned, minima = [], []
    refusal, minimum = fb.print_refusal, fb.print_minimum

    def spy_refusal(pattern, style, printer, state, scale, memo=None):
        planned.append((style, printer, state, scale))
        return refusal(pattern, style, printer, state, scale, memo)

    def spy_minimum(*args, **kw):
        minima.append(args[1:])
        return minimum(*args, **kw)

    monkeypatch.setattr(fb, "print_refusal", spy_refusal)
    monkeypatch.setattr(fb, "print_minimum", spy_minimum)
    with pytest.raises(Refused) as exc:
        print_pattern(p, PrintOptions())
    assert "the bed of prusa-mk4 takes at most" in exc.value.reason
    assert any(a.changes.get("style") == "strips" for a in exc.value.alternatives)
    assert len(minima) == 1, minima
    assert planned  # the plan checks still decide every print the bed takes
    for style, printer, state, scale in planned:
        top = fb.bed_scale(fb.scaled(p, scale), style, state, printer)
        assert top is None or top >= 1.0, (style, printer.name, scale)


# ---------------------------------------------------------------- the shipped templates (issue 32 must-show)
@pytest.mark.slow
@pytest.mark.parametrize("name", sorted(p.name for p in PATTERNS.glob("*.json")))
def test_every_shipped_template_cuts_in_acrylic_and_prints_on_prusa_mk4(name):
    """Every pattern in templates/patterns/ cuts with acrylic-3 and prints in tiles-and-strips on
    prusa-mk4 at --scale auto, through the front doors (read-back and print checks included)."""
    p = read_pattern(PATTERNS / name)
    cut = cut_files(
        p,
        CutOptions(material=load_material("acrylic-3"), scale="auto", formats=("dxf",)),
    )
    assert cut.readback.ok and cut.files
    out = print_pattern(
        p, PrintOptions(style="tiles-and-strips", printer="prusa-mk4", scale="auto")
    )
    assert out.mesh_report.ok and out.verifier.ok and out.files
    assert out.scale <= fb.print_minimum(p, "tiles-and-strips", load_printer("prusa-mk4")).max_scale


def test_cut_scale_auto_names_the_read_back_refusal_at_the_largest_scale_tried():
    """When the read-back refuses every scale --scale auto steps through, the refusal quotes the last
    one (it used to re-raise the refusal at the first scale)."""
    from fabkiri.api import cut as api_cut
    from fabkiri.errors import CheckFailed

    def never(k: float):
        raise CheckFailed(f"{api_cut.READBACK_REFUSED}: 16 pieces at --scale {k:g}")

    first = CheckFailed(f"{api_cut.READBACK_REFUSED}: 16 pieces at --scale 0.5")
    with pytest.raises(CheckFailed) as exc:
        api_cut._read_back_scale(never, 0.5, first)
    top = 0.5
    for _ in range(api_cut.AUTO_STEPS):
        top = fb.ceil_sig(top * api_cut.AUTO_STEP)
    text = exc.value.cli_message()  # the command line's words; str() is the library's
    assert text.startswith(f"--scale auto: refused from --scale 0.5 up to {top:g}")
    assert text.endswith(f"16 pieces at --scale {top:g}") and exc.value.exit_code == 1
    assert str(exc.value).startswith(f"scale='auto': refused from scale=0.5 up to {top:g}")


def test_a_design_line_is_named_only_where_the_design_would_not_refuse_it_up_front():
    # circle-8x8-rigid printed on prusa-mk4 at half size: 8x8 tiles of a 50 mm circle are about 3.9 mm
    # wide, narrower than the 8.7 mm the style needs; the design refuses them before solving, so no
    # design line (nor its make line) is named, while the room check alone would pass it
    from fabkiri.api.print_tiles import narrow_tiles
    from fabkiri.design.targets.lookup import load_target

    p = read_pattern(PATTERNS / "circle-8x8-rigid.json")
    got = alternatives(p, "print", 0.5, options=PrintOptions(printer="prusa-mk4"))
    assert got and not [a for a in got if a.what in ("design", "make")]
    assert narrow_tiles(load_target("circle", 50), (8, 8), "prusa-mk4", "tiles-and-strips")
    # cut at the same size: acrylic-3's web passes the room check, and the design line stays
    cut = alternatives(p, "cut", 0.5, options=None)
    assert [a.changes["size"] for a in cut if a.what == "design"] == [50.0]
