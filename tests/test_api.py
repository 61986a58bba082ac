"""The design front door: `fabkiri design` is `design_pattern` plus argument parsing and printing."""

from __future__ import annotations

import json

import pytest
from fabkiri.api import DesignOutcome, PatternRequest, design_pattern
from fabkiri.errors import InputError


def test_design_pattern_returns_the_judged_design(tmp_path, run_cli):
    notes = []
    out = design_pattern(PatternRequest(tiles=(4, 4), target="circle", rigid=True, shape_tol="5%"), notify=notes.append)
    assert isinstance(out, DesignOutcome) and out.success and out.exit_code == 0 and out.status == "ok"
    assert out.report["max_equality_residual"] < 1e-10 and out.report["attempts"]
    assert out.pattern.design["report"] is out.report and set(out.pattern.contracted) == {1, 2}
    assert out.report["fabricability"]["thinnest_tile_mm"] > 0
    assert notes == out.messages
    files = out.files(tmp_path / "p.json")
    assert set(files) == {tmp_path / "p.json", tmp_path / "p.png"} and files[tmp_path / "p.png"][:4] == b"\x89PNG"
    # the CLI writes the same pattern (timings apart)
    code, _, _ = run_cli("design", "--tiles", "4x4", "--target", "circle", "--rigid", "--shape-tol", "5%",
                         "--no-preview", "-o", str(tmp_path / "cli.json"))
    assert code == 0
    cli = json.loads((tmp_path / "cli.json").read_text())
    assert cli["nodes"] == json.loads(files[tmp_path / "p.json"])["nodes"]


def test_a_missed_shape_is_returned_not_raised():
    out = design_pattern(PatternRequest(tiles=(4, 4), target="heart", rigid=True, init="rescaled", shape_tol="0.1%"))
    assert out.valid and not out.shape_met and out.status == "shape missed" and out.exit_code == 1


@pytest.mark.parametrize("kw, words", [
    (dict(tiles=(1, 4), target="circle"), "at least 2x2"),
    (dict(tiles=(4, 4)), "give --target"),
    (dict(tiles=(4, 4), target="circle", style="pinned"), "--style needs --printer"),
])
def test_bad_requests_raise_input_errors(kw, words):
    with pytest.raises(InputError, match=words):
        design_pattern(PatternRequest(**kw))


def test_a_seed_starts_the_full_solver_elsewhere():
    import numpy as np

    base = dict(tiles=(4, 4), target="heart", init="rescaled", solver="full", shape_tol="25%")
    a = design_pattern(PatternRequest(**base))
    b = design_pattern(PatternRequest(**base, seed=3))
    assert a.valid and b.valid  # both converge to a reconfigurable design
    assert b.pattern.design["options"]["seed"] == 3 and "seed" not in a.pattern.design["options"]
    assert not np.allclose(a.pattern.nodes, b.pattern.nodes, atol=1e-6)  # from another start, another design
