"""The design front door: `fabkiri design` is `design_pattern` plus argument parsing and printing."""

from __future__ import annotations

import json

import pytest
from fabkiri.api import DesignOutcome, PatternRequest, design_pattern
from fabkiri.errors import InputError


@pytest.mark.slow
def test_design_pattern_returns_the_judged_design(tmp_path, run_cli):
    notes = []
    out = design_pattern(
        PatternRequest(tiles=(4, 4), target="circle", rigid=True, shape_tol="5%"),
        notify=notes.append,
    )
    assert (
        isinstance(out, DesignOutcome) and out.success and out.exit_code == 0 and out.status == "ok"
    )
    assert out.report["max_equality_residual"] < 1e-10 and out.report["attempts"]
    assert out.pattern.design["report"] is out.report and set(out.pattern.contracted) == {1, 2}
    assert out.report["fabricability"]["thinnest_tile_mm"] > 0
    assert notes == out.messages
    files = out.files(tmp_path / "p.json")
    assert (
        set(files) == {tmp_path / "p.json", tmp_path / "p.png"}
        and files[tmp_path / "p.png"][:4] == b"\x89PNG"
    )
    # the CLI writes the same pattern (timings apart)
    code, _, _ = run_cli(
        "design",
        "--tiles",
        "4x4",
        "--target",
        "circle",
        "--rigid",
        "--shape-tol",
        "5%",
        "--no-preview",
        "-o",
        str(tmp_path / "cli.json"),
    )
    assert code == 0
    cli = json.loads((tmp_path / "cli.json").read_text())
    assert cli["nodes"] == json.loads(files[tmp_path / "p.json"])["nodes"]


@pytest.mark.slow
def test_a_missed_shape_is_returned_not_raised():
    out = design_pattern(
        PatternRequest(tiles=(4, 4), target="heart", rigid=True, init="rescaled", shape_tol="0.1%")
    )
    assert out.valid and not out.shape_met and out.status == "shape missed" and out.exit_code == 1


@pytest.mark.parametrize(
    "kw, words",
    [
        (dict(tiles=(1, 4), target="circle"), "at least 2x2"),
        (dict(tiles=(4, 4)), "give target"),  # the library's words (the CLI's: give --target)
        (dict(tiles=(4, 4), target="circle", style="pinned"), "style needs printer"),
    ],
)
def test_bad_requests_raise_input_errors(kw, words):
    with pytest.raises(InputError, match=words):
        design_pattern(PatternRequest(**kw))


@pytest.mark.slow
def test_a_seed_starts_the_full_solver_elsewhere():
    import numpy as np

    base = dict(tiles=(4, 4), target="heart", init="rescaled", solver="full", shape_tol="25%")
    a = design_pattern(PatternRequest(**base))
    b = design_pattern(PatternRequest(**base, seed=3))
    assert a.valid and b.valid  # both converge to a reconfigurable design
    assert b.pattern.design["options"]["seed"] == 3 and "seed" not in a.pattern.design["options"]
    assert not np.allclose(
        a.pattern.nodes, b.pattern.nodes, atol=1e-6
    )  # from another start, another design


def test_the_design_front_door_is_chosen_by_the_tessellation_kind(tmp_path, run_cli, monkeypatch):
    """``design --lattice KIND`` and :func:`design_by_kind` hand the request to the front door registered
    for the kind: a front door registered from outside (as a new kind's module would) is called with the
    parsed request, and what it writes and says is what the CLI writes and prints; quad-only options
    refused by the kagome door, an unknown kind named with the known ones."""
    from dataclasses import dataclass
    from pathlib import Path

    from fabkiri.api import designers
    from fabkiri.api.design import design_pattern
    from fabkiri.api.kagome import design_kagome_pattern

    assert (
        designers.designer("quad") is design_pattern
        and designers.designer("kagome") is design_kagome_pattern
    )
    with pytest.raises(InputError, match="--holes is not available for kagome designs yet"):
        designers.design_by_kind(PatternRequest(tiles=(2, 2), holes="parallelogram", kind="kagome"))
    with pytest.raises(
        InputError, match=r"no design front door for 'hexagon' patterns; choose one of quad, kagome"
    ):
        designers.design_by_kind(PatternRequest(tiles=(2, 2), kind="hexagon"))

    @dataclass
    class Echo:
        report: dict
        exit_code: int = 1

        def write(self, path, preview=True):
            Path(path).write_text(f"preview {preview}")

        def summary(self, path):
            return [f"echoed {self.report['tiles']} to {Path(path).name}"]

    monkeypatch.setattr(designers._DESIGNERS, "members", dict(designers._DESIGNERS.members))
    designers.register_designer(
        "echo", lambda request, notify=None: Echo({"tiles": list(request.tiles)})
    )
    code, out, err = run_cli(
        "design",
        "--lattice",
        "echo",
        "--tiles",
        "3x5",
        "--no-preview",
        "--json",
        "-o",
        tmp_path / "e.json",
    )
    assert code == 1 and "echoed [3, 5] to e.json" in err and json.loads(out) == {"tiles": [3, 5]}
    assert (tmp_path / "e.json").read_text() == "preview False"
