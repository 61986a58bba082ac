"""A fast subset of bench/verify_mutations.py: valid variants of real cut files are accepted,
breakages rejected with the tile, hinge or sheet at fault named; real re-saves by Inkscape and ezdxf."""

from __future__ import annotations

import shutil
import subprocess

import numpy as np
import pytest
from fabkiri.exchange.pattern_json import read_pattern, write_pattern
from fabkiri.mechanics.contract import with_contracted_states
from fabkiri.pattern import standard_pattern
from fabkiri.verify import verify_layout

from .. import layout_fixtures as lf
from .. import layout_mutations as lm
from ..conftest import TEMPLATES

# the module fixtures (cut folders of every hinge kind) are made on one worker, not on both
pytestmark = pytest.mark.xdist_group("verify-variants")

VALID = [
    "re-save R2018",
    "LINE segments",
    "in a block, INSERT moved and turned 30°",
    "flipped OCS (extrusion -Z)",
    "colour only, all on layer 0",
    "declared inches",
    "Inkscape layers (inkscape:label only)",
    "colour only, no groups",
    "group transform (rigid)",
    "px user units",
    "turned 33°",
    "every segment a separate piece",
    "rounded to 0.001 mm",
    "NOTES layer removed",
]
BROKEN = [
    "corner moved 0.1 mm",
    "tile scaled 1%",
    "tile turned 0.5°",
    "tile mirrored",
    "tile missing",
    "sheet scaled 1%",
    "sheet mirrored",
    "mirrored through the OCS",
    "inch-for-mm",
    "viewBox 1% off",
    "slit shortened 10 µm",
    "slit cut halfway",
    "extra cut halfway into a tile",
    "a ligament severed",
    "undeclared kerf",
    "a ligament cut halfway",
    "a tape mark missing",
    "a tape mark moved off its corner",
]
KINDS = {k.name: k for k in lm.VALID + lm.BROKEN}


@pytest.fixture(scope="module")
def bases(tmp_path_factory):
    """Real `fabkiri cut` files of a chiral pattern at scale 1 (so a file without manifest can be checked)."""
    from fabkiri.cli.main import main

    root = tmp_path_factory.mktemp("variants")
    p = lf.distinct_pattern()
    pj = root / "p.json"
    write_pattern(p, pj)
    p = read_pattern(pj)
    out = {}
    for h in ("tape", "separate", "ligament"):
        d = root / h
        assert (
            main(
                [
                    "cut",
                    str(pj),
                    "--hinge",
                    h,
                    "--material",
                    "pp-0.5",
                    *(["--gap", "1.5"] if h == "ligament" else []),  # read by ligaments only
                    "--formats",
                    "dxf,svg",
                    "--no-verify",
                    "-o",
                    str(d),
                ]
            )
            == 0
        )
        for fmt in ("dxf", "svg"):
            out[h, fmt] = lm.load_base(d, fmt, p)
    return out


def _cases(names):
    return [
        (n, h, m) for n in names for h in ("tape", "separate", "ligament") for m in (True, False)
    ]


def _verify_case(bases, tmp_path, name, hinge, with_manifest):
    kind = KINDS[name]
    b = bases[hinge, "svg" if kind.fmt == "svg" else "dxf"]
    path = lm.make_case(b, kind, tmp_path / "c", with_manifest)
    if path is None:
        pytest.skip("not applicable")
    return verify_layout(b.pattern, path)


@pytest.mark.parametrize("name,hinge,with_manifest", _cases(VALID))
def test_valid_variant_accepted(bases, tmp_path, name, hinge, with_manifest):
    rep = _verify_case(bases, tmp_path, name, hinge, with_manifest)
    assert rep.ok, rep.to_text()


@pytest.mark.parametrize("name,hinge,with_manifest", _cases(BROKEN))
def test_breakage_rejected_and_named(bases, tmp_path, name, hinge, with_manifest):
    rep = _verify_case(bases, tmp_path, name, hinge, with_manifest)
    assert not rep.ok, f"{name} accepted"
    worst = [c.worst or "" for c in rep.failed()]
    assert any(w.startswith(("tile", "hinge")) for w in worst), worst


def test_slit_short_names_the_joined_tiles(bases, tmp_path):
    b = bases["tape", "dxf"]
    path = lm.make_case(b, KINDS["slit shortened 10 µm"], tmp_path / "s", False)
    chk = verify_layout(b.pattern, path).get("layout: cuts run their full length")
    assert not chk.ok and chk.worst.startswith("tiles ") and "stay joined" in chk.detail


def test_no_manifest_reference_square_and_frame_set_aside(bases, tmp_path):
    for h in ("tape", "separate"):
        b = bases[h, "dxf"]
        path = lm.make_case(b, KINDS["colour only, all on layer 0"], tmp_path / h, False)
        rep = verify_layout(b.pattern, path)
        assert rep.ok and rep.meta["reference_square_mm"] == [pytest.approx(50.0, abs=1e-6)], (
            rep.to_text()
        )


def test_ezdxf_r2018_round_trip(bases, tmp_path):
    import ezdxf

    for h in ("tape", "separate", "ligament"):
        b = bases[h, "dxf"]
        dst = tmp_path / h
        shutil.copytree(b.folder, dst)
        path = dst / b.manifest["sheets"][0]["dxf"]
        doc = ezdxf.readfile(path)
        doc.dxfversion = "R2018"
        doc.saveas(path)
        assert ezdxf.readfile(path).dxfversion == "AC1032"
        assert verify_layout(b.pattern, path).ok
        (dst / "manifest.json").unlink()
        assert verify_layout(b.pattern, path).ok


@pytest.mark.skipif(shutil.which("inkscape") is None, reason="inkscape is not installed")
@pytest.mark.parametrize("hinge", ["tape", "separate", "ligament"])
def test_inkscape_plain_svg_export(bases, tmp_path, hinge):
    b = bases[hinge, "svg"]
    src = b.folder / b.manifest["sheets"][0]["svg"]
    dst = tmp_path / src.name
    run = subprocess.run(
        ["inkscape", str(src), "--export-plain-svg", f"--export-filename={dst}"],
        capture_output=True,
        text=True,
        timeout=300,
    )
    if run.returncode != 0 or not dst.exists():
        pytest.skip(f"inkscape could not export here: {run.stderr[-200:]}")
    assert b"inkscape:label" not in dst.read_bytes()  # plain SVG: Inkscape's namespace is gone
    rep = verify_layout(b.pattern, dst)  # no manifest beside it: the file alone
    assert rep.ok, rep.to_text()
    shutil.copy(b.folder / "manifest.json", tmp_path / "manifest.json")
    assert verify_layout(b.pattern, dst).ok


def test_standard_pattern_mirror_is_no_breakage():
    """The bench skips a mirror of a mirror-symmetric sheet: the standard lattice is one."""
    p = with_contracted_states(standard_pattern(4, 4, tile_size=10.0))
    assert lm._mirror_symmetric(p.contracted[1])
    assert not lm._mirror_symmetric(lf.distinct_pattern().contracted[1])
    assert np.isfinite(p.tile_size)


def _named(bases, tmp_path, hinge, change, check, with_manifest, seed=0):
    """Write ``change`` of the DXF base; the check ``check`` fails naming what the change broke."""
    b = bases[hinge, "dxf"]
    sh, what = change(b, np.random.default_rng(seed))
    out = tmp_path / f"{hinge}-{int(with_manifest)}-{seed}"
    out.mkdir()
    path = out / b.manifest["sheets"][0]["dxf"]
    lm.write_dxf(sh, path)
    if with_manifest:
        shutil.copy(b.folder / "manifest.json", out / "manifest.json")
    chk = verify_layout(b.pattern, path).get(check)
    assert chk is not None and not chk.ok and chk.worst == what, (what, chk)


@pytest.mark.parametrize("with_manifest", [True, False])
@pytest.mark.parametrize("change", [lm.ligament_severed(False), lm.ligament_cut_into])
def test_cut_ligament_names_its_hinge(bases, tmp_path, change, with_manifest):
    for seed in range(3):
        _named(
            bases,
            tmp_path,
            "ligament",
            change,
            "layout: every ligament present and unsevered",
            with_manifest,
            seed,
        )


@pytest.mark.parametrize("with_manifest", [True, False])
@pytest.mark.parametrize("change", [lm.tape_mark_missing, lm.tape_mark_moved])
def test_missing_tape_mark_names_its_hinge(bases, tmp_path, change, with_manifest):
    for seed in range(3):
        _named(
            bases,
            tmp_path,
            "tape",
            change,
            "layout: tape marks at every hinge",
            with_manifest,
            seed,
        )


def test_every_mark_removed_needs_the_manifest_to_tell(bases, tmp_path):
    """With the manifest (the layout is labelled) every hinge lacks its mark; without it, a layout with
    no marks at all is a layout without marks, and the check is not made."""
    b = bases["tape", "dxf"]
    sh, _ = lm.tape_marks_removed(b, np.random.default_rng(0))
    path = tmp_path / b.manifest["sheets"][0]["dxf"]
    lm.write_dxf(sh, path)
    assert not any("tape marks" in c.name for c in verify_layout(b.pattern, path).checks)
    shutil.copy(b.folder / "manifest.json", tmp_path / "manifest.json")
    chk = verify_layout(b.pattern, path).get("layout: tape marks at every hinge")
    assert not chk.ok and chk.value == len(lm._marked_hinges(b))


# ------------------------------------------------------------------ standard lattices: square tiles


def _cut_bases(root, pattern, hinges=("tape", "separate", "ligament"), args=()):
    """Real `fabkiri cut` DXF bases of ``pattern`` (scale 1), one per hinge kind."""
    from fabkiri.cli.main import main

    pj = root / "p.json"
    write_pattern(pattern, pj)
    p = read_pattern(pj)
    out = {}
    for h in hinges:
        d = root / h
        gap = ["--gap", "1"] if h == "ligament" else []  # read by ligaments only
        argv = ["cut", str(pj), "--hinge", h, "--material", "pp-0.5", *gap, *args]
        assert main([*argv, "--formats", "dxf", "--no-verify", "-o", str(d)]) == 0
        out[h] = lm.load_base(d, "dxf", p)
    return out


@pytest.fixture(scope="module")
def std_bases(tmp_path_factory):
    """A standard 3x3 lattice: every tile a square, like the reference square."""
    p = with_contracted_states(standard_pattern(3, 3, tile_size=10.0))
    return _cut_bases(tmp_path_factory.mktemp("std"), p)


@pytest.fixture(scope="module")
def std50_bases(tmp_path_factory):
    """50 mm tiles: the tiles are the reference square's size."""
    p = with_contracted_states(standard_pattern(2, 2, tile_size=50.0))
    return _cut_bases(tmp_path_factory.mktemp("std50"), p, args=("--sheet", "800x800"))


def _verify_kind(base, kind, tmp_path, with_manifest, seed=0):
    path = lm.make_case(base, kind, tmp_path / f"c{int(with_manifest)}", with_manifest, seed)
    assert path is not None
    return verify_layout(base.pattern, path)


@pytest.mark.parametrize("with_manifest", [True, False])
@pytest.mark.parametrize("hinge", ["tape", "separate", "ligament"])
def test_an_extra_copy_of_a_tile_is_found(std_bases, tmp_path, hinge, with_manifest):
    """A copy of a square tile beside the parts is an extra piece, not a second reference square."""
    rep = _verify_kind(
        std_bases[hinge], KINDS["a copy of a tile beside the parts"], tmp_path, with_manifest
    )
    chk = rep.get("layout: tiles recovered")
    assert not rep.ok and not chk.ok and "1 unmatched cut regions" in chk.detail, chk
    assert chk.worst.startswith("tile "), (
        chk
    )  # named: the design tile the extra piece is shaped like


def test_every_ligament_cut_away_is_rejected(std_bases, tmp_path):
    """Tiles cut apart in place are no ligament sheet: every ligament the manifest declares is missing."""
    b = std_bases["ligament"]
    rep = _verify_kind(b, KINDS["every ligament cut away"], tmp_path, True)
    chk = rep.get("layout: every ligament present and unsevered")
    assert chk is not None and not chk.ok, rep.to_text()
    assert chk.value == len(b.manifest["hinge_features"]) and chk.worst.startswith("hinge")


MOVES = ["translated", "turned 33°", "turned 90°", "rounded to 0.001 mm"]


@pytest.mark.parametrize("with_manifest", [True, False])
@pytest.mark.parametrize("hinge", ["tape", "separate", "ligament"])
def test_reference_sized_tiles_moved_or_turned_are_accepted(
    std50_bases, tmp_path, hinge, with_manifest
):
    """50 mm tiles: the reference square is the one square beside the parts (uncompensated, apart),
    not whichever square is left after matching by shape."""
    for k, name in enumerate(MOVES):
        rep = _verify_kind(std50_bases[hinge], KINDS[name], tmp_path / str(k), with_manifest)
        assert rep.ok, (name, rep.to_text())
        assert rep.meta.get("reference_square_mm", [50.0]) == [pytest.approx(50.0, abs=1e-2)]


@pytest.mark.parametrize("name", ["turned 33°", "turned 90°", "translated"])
def test_symmetric_ligament_sheet_moved_is_accepted(std_bases, tmp_path, name):
    """A standard lattice fits a quarter-turned motion as well as the true one: the declared ligaments
    are moved by the motion that puts them on the material."""
    rep = _verify_kind(std_bases["ligament"], KINDS[name], tmp_path, True)
    assert rep.ok, rep.to_text()
    assert "moved with the sheet" in rep.meta["recovery"][0]


@pytest.mark.slow  # a 64-tile heart at its smallest ligament scale (the quick loop: the 3x3 above)
def test_ligament_sheet_with_a_thin_tile_moved_is_accepted(tmp_path):
    """Tiles narrower than a ligament: an opening cuts them short, the declared strips moved with the
    sheet do not."""
    p = read_pattern(TEMPLATES.parent / "tests" / "data" / "heart-8x8.json")
    b = _cut_bases(tmp_path, p, ("ligament",), ("--scale", "auto", "--sheet", "3000x3000"))
    b = b["ligament"]
    for k, name in enumerate(["turned 33°", "translated", "rounded to 0.001 mm"]):
        rep = _verify_kind(b, KINDS[name], tmp_path / str(k), True)
        assert rep.ok, (name, rep.to_text())
    sh, _ = lm.tile_moved(0.2)(
        b, np.random.default_rng(0)
    )  # a breakage in a turned sheet still fails
    path = tmp_path / "broken" / b.manifest["sheets"][0]["dxf"]
    path.parent.mkdir()
    lm.write_dxf(sh.map_points(lm.rigid(0.5, (30.0, -20.0))), path)
    shutil.copy(b.folder / "manifest.json", path.parent / "manifest.json")
    assert not verify_layout(b.pattern, path).ok
