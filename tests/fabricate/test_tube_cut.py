"""Laser files of a tube: the flat sheet, the seam note, read-back verification, refusal of an open seam."""

from __future__ import annotations

import json

import numpy as np
import pytest
from fabkiri.exchange.pattern_json import read_pattern, write_pattern
from fabkiri.fabricate.tube.sheet import seam_hinges
from fabkiri.mechanics.contract import with_contracted_states
from fabkiri.pattern.kinds.periodic.sheet import (
    flat_sheet,
    lattice_seam,
    seam_of,
    standard_tube,
    with_seam,
)

from tests.designs import reconfigurable_design


def test_flat_sheet_holds_every_tube_tile_once():
    tube = with_contracted_states(standard_tube(6, 8))
    seam = seam_of(tube)
    sheet = flat_sheet(tube, seam)
    assert sheet.n_tiles == 48 and sheet.lattice["cols"] == 8 and "seam" not in sheet.lattice
    assert sheet.topology.n_holes == 5 * 7  # the seam holes straddle the cut
    for s in (1, 2):  # the tube's own closed tiles, in tube order
        keep = np.setdiff1d(np.arange(tube.n_tiles), seam.copy)
        assert np.array_equal(sheet.contracted[s], tube.contracted[s][keep])
    hinges = seam_hinges(tube, seam)
    assert len(hinges) == 6  # one per row: column 7 to column 0
    assert {(h["tile"] % 8, h["joins_tile"] % 8) for h in hinges} == {(7, 0)}


@pytest.mark.slow
def test_cut_a_tube_writes_the_flat_sheet_and_the_seam_note(tmp_path, run_cli):
    src = tmp_path / "tube.json"
    code, _, _ = run_cli("new", "--tiles", "6x8", "--tube", "-o", src)
    assert code == 0
    out = tmp_path / "cut"
    code, _, err = run_cli("cut", src, "-o", out)
    assert code == 0, err
    note = (out / "seam.txt").read_text()
    assert note.count("<->") == 6 and "circumference" in note and "S6:" in note
    # both ends of every seam hinge engraved: S1..S6 twice each beside the tile labels
    from fabkiri.exchange.file_formats import read_cut_file

    flat = tmp_path / "flat.json"  # the same sheet as a plain pattern: no seam, no marks
    write_pattern(flat_sheet(read_pattern(src), seam_of(read_pattern(src))), flat)
    code, _, _ = run_cli("cut", flat, "-o", tmp_path / "plain", "--formats", "dxf")
    assert code == 0
    marked = read_cut_file(out / "tube.dxf", "ENGRAVE").polylines
    plain = read_cut_file(tmp_path / "plain" / "flat.dxf", "ENGRAVE").polylines
    assert (
        len(marked) - len(plain) >= 12 * 2
    )  # a tick and at least a letter at each of the 12 corners
    assert read_cut_file(out / "tube.dxf").polylines  # the CUT layer is still there
    man = json.loads((out / "manifest.json").read_text())
    assert man["seam"]["columns"] == 8 and len(man["seam"]["hinges"]) == 6
    code, text, err = run_cli("verify", src, "--layout", out / "tube.dxf")
    assert code == 0, err
    assert "state 1: seam closes by a pure translation" in text


def test_cut_refuses_a_tube_whose_seam_does_not_close(tmp_path, run_cli):
    sheet = reconfigurable_design(4, 5, seed=3, amplitude=0.08)
    broken = with_contracted_states(with_seam(sheet, lattice_seam(4, 4)))
    src = tmp_path / "broken.json"
    write_pattern(broken, src)
    out = tmp_path / "cut"
    code, _, err = run_cli("cut", src, "-o", out)
    assert (
        code == 1
        and "does not close across its seam" in err
        and "seam closes by a pure translation" in err
    )
    assert not out.exists()
