"""The layout verifier on files written by ``fabkiri cut`` (the real writers), and edits of them."""

from __future__ import annotations

import json
import shutil

import ezdxf
import numpy as np
import pytest
from fabkiri.exchange.pattern_json import read_pattern
from fabkiri.verify import verify_layout

from ..conftest import TEMPLATES

# the module fixtures (cut folders of every hinge kind) are made on one worker, not on both
pytestmark = pytest.mark.xdist_group("verify-cut-files")

PATTERN = TEMPLATES / "patterns" / "circle-8x8.json"


@pytest.fixture(scope="module")
def cut_dirs(tmp_path_factory):
    from fabkiri.cli.main import main

    root = tmp_path_factory.mktemp("cut")
    out = {}
    for hinge, material in (
        ("tape", "acrylic-3"),
        ("separate", "acrylic-3"),
        ("ligament", "pp-0.5"),
    ):
        d = root / hinge
        code = main(
            [
                "cut",
                str(PATTERN),
                "--material",
                material,
                "--hinge",
                hinge,
                "--width",
                "300",
                "--formats",
                "dxf,svg",
                "--no-verify",
                "-o",
                str(d),
            ]
        )
        assert code == 0
        out[hinge] = d
    return out


@pytest.fixture(scope="module")
def pattern():
    return read_pattern(PATTERN)


@pytest.mark.parametrize("hinge", ["tape", "separate", "ligament"])
@pytest.mark.parametrize("fmt", ["dxf", "svg"])
def test_real_cut_files_verify(cut_dirs, pattern, hinge, fmt):
    path = next(cut_dirs[hinge].glob(f"*.{fmt}"))
    rep = verify_layout(pattern, path)
    assert rep.ok, rep.to_text()
    assert rep.get("layout: tiles recovered").value == pattern.n_tiles
    assert rep.get("layout: (a) cut tiles congruent to design").value < 0.01
    names = rep.names()
    assert any(n.startswith("layout: (b)") for n in names) == (hinge != "separate")
    assert any(n.startswith("layout: (c) state 2") for n in names)


def _edit_dxf(src, dst, edit):
    shutil.copytree(src, dst)
    path = next(dst.glob("*.dxf"))
    doc = ezdxf.readfile(path)
    cut = [e for e in doc.modelspace() if e.dxf.layer == "CUT" and e.dxftype() == "LWPOLYLINE"]
    edit(cut, doc)
    doc.saveas(path)
    return path


@pytest.mark.slow
def test_edited_real_files_are_rejected(cut_dirs, pattern, tmp_path):
    src = cut_dirs["separate"]
    ref = json.loads((src / "manifest.json").read_text())["reference_square"]["corners"]

    def tiles_only(cut):
        return [
            e
            for e in cut
            if len(e) != 4
            or not np.allclose(
                np.sort(np.array(e.get_points("xy")), 0), np.sort(np.array(ref), 0), atol=1e-6
            )
        ]

    def scale_sheet(cut, doc):
        for e in cut:
            e.set_points([(x * 1.01, y * 1.01) for x, y in e.get_points("xy")], format="xy")

    def mirror_one(cut, doc):
        e = tiles_only(cut)[5]
        pts = np.array(e.get_points("xy"))
        cx = pts[:, 0].mean()
        e.set_points([(2 * cx - x, y) for x, y in pts[::-1]], format="xy")

    def drop_one(cut, doc):
        doc.modelspace().delete_entity(tiles_only(cut)[7])

    def move_corner(cut, doc):
        e = tiles_only(cut)[11]
        pts = np.array(e.get_points("xy"))
        pts[0] += [0.1, 0.0]
        e.set_points([tuple(p) for p in pts], format="xy")

    for name, edit, failing in (
        ("scale", scale_sheet, "layout: (a) cut tiles congruent to design"),
        ("mirror", mirror_one, "layout: (a) cut tiles congruent to design"),
        ("drop", drop_one, "layout: tiles recovered"),
        ("corner", move_corner, "layout: (a) cut tiles congruent to design"),
    ):
        path = _edit_dxf(src, tmp_path / name, edit)
        rep = verify_layout(pattern, path)
        assert not rep.ok and failing in {c.name for c in rep.failed()}, (name, rep.to_text())
    # undeclared kerf: the outlines are kerf/2 too big everywhere
    m = json.loads((src / "manifest.json").read_text())
    assert m["kerf_offset_mm"] > 0.05
    m["kerf_offset_mm"] = 0.0
    rep = verify_layout(pattern, next(src.glob("*.dxf")), manifest=m)
    assert not rep.get("layout: (a) cut tiles congruent to design").ok


def test_real_in_place_file_with_a_line_removed_is_rejected(cut_dirs, pattern, tmp_path):
    def drop_outline_piece(cut, doc):
        longest = max(cut, key=lambda e: len(e))
        doc.modelspace().delete_entity(longest)

    path = _edit_dxf(cut_dirs["tape"], tmp_path / "tape", drop_outline_piece)
    rep = verify_layout(pattern, path)
    assert not rep.get("layout: tiles recovered").ok
