"""Periodic quad patterns (tubes): the seam, both closed states, verify, info and pattern.json."""

from __future__ import annotations

import json

import numpy as np
import pytest
from fabkiri.errors import PatternError
from fabkiri.exchange.pattern_json import read_pattern, write_pattern
from fabkiri.mechanics.contract import contract, with_contracted_states
from fabkiri.mechanics.info import describe
from fabkiri.mechanics.tube import tube_report
from fabkiri.pattern.kinds.periodic.sheet import (
    lattice_seam,
    seam_map,
    seam_of,
    standard_tube,
    with_seam,
)
from fabkiri.verify.pattern_checks import verify_pattern

from tests.designs import reconfigurable_design


@pytest.fixture(scope="module")
def tube68():
    return with_contracted_states(standard_tube(6, 8, tile_size=10.0))


def test_standard_tube_closes_with_a_pure_translation_seam(tube68):
    """Must-show: 8 columns x 6 rows closes in both states; each closed seam is a pure translation."""
    seam = seam_of(tube68)
    assert seam.columns == 8 and len(seam.pairs) == 6
    assert tube68.n_tiles == 6 * 9  # the seam copy column is stored
    for s in (1, 2):
        c = contract(tube68, s)
        assert c.max_closure <= 1e-10 * tube68.tile_size
        m = seam_map(c.corners, seam)
        assert m.translation_dev <= 1e-10 * tube68.tile_size
        assert abs(m.rotation) <= 1e-12
        # a closed state of unit squares: the circumference is 8 tile edges
        assert m.period == pytest.approx(80.0, rel=1e-12)
    dep = seam_map(tube68.corners(), seam)
    assert dep.period == pytest.approx(80.0 * np.sqrt(2.0), rel=1e-12)


def test_tube_report_radius_length_and_changes(tube68):
    rep = tube_report(tube68)
    closed = rep["states"]["1"]
    assert closed["shape"] == "cylinder"
    assert closed["radius_min_mm"] == pytest.approx(80.0 / (2 * np.pi), rel=1e-12)
    assert closed["length_mm"] == pytest.approx(60.0, rel=1e-12)
    dep = rep["states"]["deployed"]
    assert dep["length_mm"] == pytest.approx(60.0 * np.sqrt(2.0), rel=1e-12)
    ch = rep["changes_from_closed"]["2"]
    assert ch["axial"] == pytest.approx(np.sqrt(2.0), rel=1e-12)
    assert ch["radial_min"] == pytest.approx(np.sqrt(2.0), rel=1e-12)


def test_verify_passes_the_seam_checks(tube68):
    rep = verify_pattern(tube68)
    seam = [c for c in rep.checks if "seam" in c.name]
    assert len(seam) == 6  # translation + overlaps across the seam, deployed and both closed states
    assert all(c.ok for c in rep.checks), [c.name for c in rep.checks if not c.ok]
    closed = [c for c in seam if c.name.startswith("state") and "translation" in c.name]
    assert all(c.value <= 1e-10 * tube68.tile_size for c in closed)


def test_a_broken_seam_fails_verify_and_info_naming_the_seam():
    """A sheet that closes as a planar pattern but whose last column is no copy of the first."""
    sheet = reconfigurable_design(4, 5, seed=3, amplitude=0.08)
    assert describe(sheet).closes_both  # planar: fine
    broken = with_contracted_states(with_seam(sheet, lattice_seam(4, 4)))
    rep = verify_pattern(broken, rigid=False)  # the fixture is reconfigurable, not rigid
    failed = [c.name for c in rep.checks if not c.ok]
    assert "state 1: seam closes by a pure translation" in failed
    assert "state 2: seam closes by a pure translation" in failed
    assert all("seam" in name for name in failed), failed
    info = describe(broken)
    assert not info.closes_both
    assert any("seam does not close by a pure translation" in p for p in info.problems())


def test_seam_round_trips_through_pattern_json(tube68, tmp_path):
    path = tmp_path / "tube.json"
    write_pattern(tube68, path)
    back = read_pattern(path)
    a, b = seam_of(tube68), seam_of(back)
    assert np.array_equal(a.pairs, b.pairs) and a.columns == b.columns and a.deployed == b.deployed
    assert verify_pattern(back).ok


@pytest.mark.parametrize(
    "seam, message",
    [
        ({"columns": 8}, "'columns' and 'pairs'"),
        ({"columns": 8, "pairs": [[0, 999]]}, "names tile 999"),
        ({"columns": 7, "pairs": [[0, 8]]}, "even count"),
        ({"columns": 8, "pairs": [[0, 8], [0, 17]]}, "uses a tile twice"),
        ({"columns": 8, "pairs": [[0, 8]], "deployed": "sphere"}, "cylinder or cone"),
        ({"columns": 8, "pairs": [[0, 8]], "closed": "cone"}, "closed must be cylinder"),
    ],
)
def test_a_malformed_seam_record_is_one_line_bad_input(tube68, tmp_path, run_cli, seam, message):
    path = tmp_path / "bad.json"
    write_pattern(tube68, path)
    data = json.loads(path.read_text())
    data["lattice"]["seam"] = seam
    path.write_text(json.dumps(data))
    with pytest.raises(PatternError, match=message):
        seam_of(read_pattern(path))
    code, out, err = run_cli("info", path)
    assert code == 2 and message.split("'")[0] in err and len(err.strip().splitlines()) == 1


def test_cli_new_tube_info_and_verify(tmp_path, run_cli):
    out = tmp_path / "t.json"
    code, _, err = run_cli("new", "--tiles", "6x8", "--tube", "-o", out)
    assert code == 0 and "tube" in err
    code, text, _ = run_cli("info", out, "--check")
    assert code == 0
    assert "state 1   cylinder radius 12.73 mm, length 60 mm" in text
    code, text, _ = run_cli("verify", out)
    assert code == 0 and "state 2: seam closes by a pure translation" in text


def test_cli_new_tube_needs_even_columns(tmp_path, run_cli):
    out = tmp_path / "t.json"
    code, _, err = run_cli("new", "--tiles", "6x7", "--tube", "-o", out)
    assert code == 2 and "even number of columns" in err and not out.exists()
