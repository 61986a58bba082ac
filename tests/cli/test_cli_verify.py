"""``fabkiri verify``: exit codes, table and JSON output, layouts, bad input."""

from __future__ import annotations

import json

import numpy as np
import pytest
from fabkiri.exchange.pattern_json import write_pattern

from .. import layout_fixtures as lf
from ..conftest import TEMPLATES, ref


def test_valid_pattern_exits_0(run_cli):
    code, out, err = run_cli("verify", TEMPLATES / "patterns" / "standard-8x8.json")
    assert code == 0, err
    assert out.splitlines()[-1].startswith("verdict: PASS")


def test_reference_bow_tie_exits_1_failures_first(run_cli):
    code, out, err = run_cli("verify", ref("compact_reconfigurable_design"))
    assert code == 1
    rows = out.splitlines()
    assert rows[2].startswith("FAIL") and "tiles simple" in rows[2] and "tile 2" in rows[2]
    assert "verification failed: tiles simple" in err
    # the contracted files beside the design were picked up as stored states
    assert "state 1: stored state matches computed" in out


def test_json_output(run_cli):
    code, out, _ = run_cli("verify", ref("non-contractible_design"), "--json")
    assert code == 1
    d = json.loads(out)
    assert not d["ok"] and "state 1: loop closure" in d["failed"]


def test_layout_ok_and_mutated(run_cli, tmp_path):
    p = lf.distinct_pattern()
    pj = tmp_path / "p.json"
    write_pattern(p, pj)
    good = lf.write_layout(
        tmp_path / "good", p, lf.in_place_corners(p, 1, 0.7), hinge="tape", fmt="dxf"
    )
    code, out, err = run_cli("verify", pj, "--layout", good)
    assert code == 0, out + err
    assert "layout: (c) state 2 from cut tiles: loop closure" in out
    bad = lf.write_layout(
        tmp_path / "bad",
        p,
        lf.scale_tile(lf.exploded_corners(p, np.random.default_rng(1)), 4, 1.01),
        hinge="separate",
        fmt="svg",
        kerf_offset=0.1,
    )
    code, out, err = run_cli("verify", pj, "--layout", bad, "--json")
    assert code == 1
    d = json.loads(out)
    assert "layout: (a) cut tiles congruent to design" in d["failed"]
    # a looser tolerance accepts the 1 % tile (0.2 mm at most on a 20 mm tile)
    code, _, _ = run_cli("verify", pj, "--layout", bad, "--tol-mm", "0.5")
    assert code == 0


def test_bad_input_exits_2(run_cli, tmp_path):
    code, _, err = run_cli("verify", tmp_path / "missing.json")
    assert code == 2 and "no such file" in err
    pj = tmp_path / "p.json"
    write_pattern(lf.distinct_pattern(), pj)
    code, _, err = run_cli("verify", pj, "--layout", tmp_path / "nope.dxf")
    assert code == 2 and "no such layout file" in err
    junk = tmp_path / "junk.dxf"
    junk.write_text("this is not a DXF\n")
    code, _, err = run_cli("verify", pj, "--layout", junk)
    assert code == 2 and "junk.dxf" in err and len(err.strip().splitlines()) == 1
    import ezdxf

    ezdxf.new("R2010", units=4).saveas(tmp_path / "empty.dxf")
    code, _, err = run_cli("verify", pj, "--layout", tmp_path / "empty.dxf")
    assert code == 2 and "no cut geometry" in err
    txt = tmp_path / "cut.txt"
    txt.write_text("x")
    code, _, err = run_cli("verify", pj, "--layout", txt)
    assert code == 2 and ".dxf or .svg" in err
    with pytest.raises(SystemExit) as exc:  # argparse rejects it before any work
        run_cli("verify", pj, "--tol-mm", "-1")
    assert exc.value.code == 2
    svg = tmp_path / "bad.svg"
    svg.write_text("<svg")
    code, _, err = run_cli("verify", pj, "--layout", svg)
    assert code == 2 and "bad.svg" in err
    lay = lf.write_layout(
        tmp_path / "m",
        lf.distinct_pattern(),
        lf.in_place_corners(lf.distinct_pattern()),
        hinge="tape",
        fmt="dxf",
    )
    (lay.parent / "manifest.json").write_text('{"hinge": "staples"}')
    code, _, err = run_cli("verify", pj, "--layout", lay)
    assert code == 2 and "unknown hinge kind" in err
