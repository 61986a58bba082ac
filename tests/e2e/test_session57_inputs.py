"""What session 56 left and session 57 found (docs/bad-input.md, "Session 57 (hard57)"): a pattern with a
tile removed by hand, a FOLD whose key frame is a folded form, DXF files with nothing fabkiri reads, a
viewer page over another pattern's cut, a print coupon's laser notes, an earlier run's files left beside.
"""

from __future__ import annotations

import json
import os

import ezdxf
import pytest
from fabkiri.errors import CheckFailed, PatternError
from fabkiri.exchange.fold import fold_text, loads_fold
from fabkiri.exchange.pattern_json import dumps
from fabkiri.mechanics import with_contracted_states
from fabkiri.mechanics.info import describe
from fabkiri.mechanics.path import closed_states
from fabkiri.pattern import standard_pattern
from fabkiri.pattern.model import Pattern

PATTERN = with_contracted_states(standard_pattern(4, 4, tile_size=10.0))


def _one_line(err: str) -> str:
    lines = err.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in err, err
    return lines[0]


def _without_tile(k: int = 5) -> Pattern:
    """The 4x4 lattice with tile ``k`` deleted from the file, as by hand (its closed states too)."""
    d = json.loads(dumps(PATTERN))
    del d["tiles"][k]
    for s in d["contracted"]:
        del d["contracted"][s][k]
    return d


# ------------------------------------------------------------------ a tile removed by hand


def test_info_says_a_pattern_with_a_tile_removed_forms_no_lattice(tmp_path, run_cli):
    (tmp_path / "p.json").write_text(json.dumps(_without_tile()))
    code, out, _ = run_cli("info", tmp_path / "p.json")
    # was: "verdict closes in both states" while verify failed its topology
    assert code == 0 and "closes in both states" not in out
    assert "form no kirigami lattice" in out and "expects 9 holes" in out
    code, _, err = run_cli("info", "--check", tmp_path / "p.json")
    assert code == 1 and "form no kirigami lattice" in err


def test_deploy_refuses_a_pattern_with_a_tile_removed(tmp_path, run_cli):
    (tmp_path / "p.json").write_text(json.dumps(_without_tile()))
    code, _, err = run_cli("deploy", tmp_path / "p.json", "-o", tmp_path / "d")
    # was: exit 0, 41 frames of a pattern whose closed states hold a tile-sized gap
    assert code == 1 and "form no kirigami lattice" in _one_line(err)
    assert sorted(os.listdir(tmp_path)) == ["p.json"]


def test_every_reader_judges_the_lattice_as_verify_does():
    from fabkiri.exchange.pattern_json import loads

    broken = loads(json.dumps(_without_tile()))
    assert not describe(broken).closes_both and describe(PATTERN).closes_both
    with pytest.raises(CheckFailed, match="form no kirigami lattice"):
        closed_states(broken)


# ---------------------------------------------------------------------- FOLD folded form


def _fold(**changes) -> dict:
    return json.loads(fold_text(PATTERN)) | changes


def test_a_fold_whose_key_frame_is_a_folded_form_is_refused():
    flat = {"frame_classes": ["creasePattern"], "vertices_coords": _fold()["vertices_coords"]}
    d = _fold(frame_classes=["foldedForm"])
    with pytest.raises(
        PatternError, match="key frame is a foldedForm"
    ):  # was read as the flat sheet
        loads_fold(json.dumps(d), "f.fold")
    d["file_frames"].append(flat)
    with pytest.raises(PatternError, match="frame 3 is a creasePattern"):
        loads_fold(json.dumps(d), "f.fold")
    loads_fold(json.dumps(_fold(frame_classes=["creasePattern", "foldedForm"])), "f.fold")


# -------------------------------------------------------------------- DXF without curves


def test_an_empty_dxf_names_inkscapes_r12_export(tmp_path, run_cli):
    # Inkscape's R12 export of an <ellipse>: a header and an empty ENTITIES section
    (tmp_path / "e.dxf").write_text(
        "0\nSECTION\n2\nHEADER\n9\n$ACADVER\n1\nAC1009\n0\nENDSEC\n0\nSECTION\n2\nENTITIES\n"
        "0\nENDSEC\n0\nEOF\n"
    )
    code, _, err = run_cli(
        "design", "--tiles", "4x4", "--target", tmp_path / "e.dxf", "-o", tmp_path / "o.json"
    )
    assert code == 2 and "is empty" in _one_line(err) and "R14" in err


def test_a_dxf_of_text_and_notes_says_what_it_holds(tmp_path, run_cli):
    doc = ezdxf.new()
    msp = doc.modelspace()
    msp.add_text("outline")
    msp.add_point((1, 2))
    msp.add_lwpolyline([(0, 0), (10, 0), (10, 10)], close=True, dxfattribs={"layer": "NOTES"})
    doc.saveas(tmp_path / "t.dxf")
    code, _, err = run_cli(
        "design", "--tiles", "4x4", "--target", tmp_path / "t.dxf", "-o", tmp_path / "o.json"
    )
    assert code == 2 and "holds 1 TEXT, 1 POINT, 1 NOTES-layer curve" in _one_line(err)


# ----------------------------------------------------------------------- view --cut


def test_view_refuses_the_cut_folder_of_another_pattern(tmp_path, run_cli):
    (tmp_path / "p.json").write_text(dumps(PATTERN))
    (tmp_path / "q.json").write_text(dumps(standard_pattern(3, 3, tile_size=10.0)))
    assert (
        run_cli("cut", tmp_path / "p.json", "--material", "card-0.3", "-o", tmp_path / "c")[0] == 0
    )
    code, _, err = run_cli(
        "view", tmp_path / "q.json", "--cut", tmp_path / "c", "-o", tmp_path / "v.html"
    )
    # was: exit 0, a page showing the 4x4's sheets and pieces as the 3x3's
    assert code == 2 and "made from another pattern" in _one_line(err)
    assert not (tmp_path / "v.html").exists()


def test_a_print_coupon_refuses_the_laser_notes(tmp_path, run_cli):
    code, _, err = run_cli("coupon", "--printer", "prusa-mk4", "--notes", "-o", tmp_path / "c")
    assert code == 2 and "--notes" in _one_line(err)  # was: exit 0, --notes read by nothing
    assert not (tmp_path / "c").exists()


def test_a_cut_into_the_folder_of_an_earlier_cut_names_its_files(tmp_path, run_cli):
    for name, n in (("p", 3), ("q", 2)):
        (tmp_path / f"{name}.json").write_text(dumps(standard_pattern(n, n, tile_size=20.0)))
    out = tmp_path / "out"
    assert run_cli("cut", tmp_path / "p.json", "--material", "card-0.3", "-o", out)[0] == 0
    code, _, err = run_cli("cut", tmp_path / "q.json", "--material", "card-0.3", "-o", out)
    # was: p.dxf, p.png and p.svg silently beside q's files and q's manifest
    assert code == 0 and "also holds p.dxf, p.png, p.svg of an earlier run" in err
    assert (out / "p.dxf").exists()  # named, not deleted: they are the user's files
