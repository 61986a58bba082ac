"""What session 56 left and session 57 found (docs/bad-input.md, "Session 57 (hard57)"): a pattern with a
tile removed by hand, a FOLD whose key frame is a folded form, DXF files with nothing fabkiri reads.
"""

from __future__ import annotations

import json
import os

import pytest
from fabkiri.errors import CheckFailed
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
