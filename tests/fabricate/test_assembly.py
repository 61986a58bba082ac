"""Assembly map and bill of materials in the cut and print manifests."""

from __future__ import annotations

import json

import numpy as np
import pytest
from fabkiri.exchange.pattern_json import read_pattern
from PIL import Image

from ..conftest import TEMPLATES

STD = TEMPLATES / "patterns" / "standard-8x8.json"


def test_cut_manifest_numbers_every_tape_piece_in_join_order(run_cli, tmp_path):
    code, _, err = run_cli("cut", STD, "-o", tmp_path)
    assert code == 0, err
    m = json.loads((tmp_path / "manifest.json").read_text())
    p = read_pattern(STD)
    pieces = m["assembly_pieces"]
    assert [r["piece"] for r in pieces] == list(range(1, p.topology.n_hinges + 1))
    assert sorted(r["hinge"] for r in pieces) == list(range(p.topology.n_hinges))
    faces = {h["hinge"]: h["face"] for h in m["hinges"]}
    assert all(r["face"] == faces[r["hinge"]] for r in pieces)
    f = [r["face"] for r in pieces]
    assert f == sorted(f, key=lambda x: x != "T")  # every top piece before any bottom piece
    # on each face the spanning-tree joins come first, in breadth-first order
    tree = list(p.topology.spanning_tree(0).hinges)
    for face in "TB":
        hs = [r["hinge"] for r in pieces if r["face"] == face]
        in_tree = [h in tree for h in hs]
        assert in_tree == sorted(in_tree, reverse=True)
        t = [h for h in hs if h in tree]
        assert t == sorted(t, key=tree.index)
    bom = m["bill_of_materials"]
    assert bom["tape_pieces"] == len(pieces) == bom["tape_top"] + bom["tape_bottom"]
    assert bom["tape_length_mm"] == pytest.approx(sum(r["length_mm"] for r in pieces), abs=1e-3)
    assert all(
        0 < r["length_mm"] <= 2 * 8.0 + 1e-9 for r in pieces
    )  # a corner each side, 8 mm reach at most
    assert bom["sheet_area_mm2"] == 600 * 400 and 0 < bom["parts_area_mm2"] < bom["sheet_area_mm2"]
    assert m["assembly"]["map"] == "assembly.png"
    im = Image.open(tmp_path / "assembly.png")
    assert im.size[0] >= 600


@pytest.mark.slow
def test_ligament_sheet_has_nothing_to_join(run_cli, tmp_path):
    code, _, err = run_cli(
        "cut",
        TEMPLATES / "patterns" / "circle-8x8.json",
        "--material",
        "pp-0.5",
        "--width",
        "300",
        "-o",
        tmp_path,
    )
    assert code == 0, err
    m = json.loads((tmp_path / "manifest.json").read_text())
    assert m["assembly_pieces"] == [] and m["bill_of_materials"]["ligaments"] == len(m["hinges"])
    assert not (tmp_path / "assembly.png").exists()


@pytest.mark.slow
def test_print_manifest_has_strips_and_filament(run_cli, tmp_path):
    code, _, err = run_cli(
        "print",
        TEMPLATES / "patterns" / "circle-8x8-rigid.json",
        "--scale",
        "3",
        "--style",
        "strips",
        "-o",
        tmp_path,
    )
    assert code == 0, err
    m = json.loads((tmp_path / "manifest.json").read_text())
    bom = m["bill_of_materials"]
    assert bom["strips"] == len(m["hinges"]) == bom["strips_top"] + bom["strips_bottom"]
    total = sum(b["volume_mm3"] for b in bom["bodies"])
    assert sum(f["volume_mm3"] for f in bom["filament"].values()) == pytest.approx(
        total, rel=1e-6, abs=0.01
    )
    for f in bom["filament"].values():
        assert f["length_m"] == pytest.approx(f["volume_mm3"] / (np.pi * 0.875**2) / 1000, rel=1e-3)
    pieces = m["assembly_pieces"]
    assert sorted(r["hinge"] for r in pieces) == list(range(len(m["hinges"])))
    assert (tmp_path / "assembly.png").exists()
