"""End-to-end: new, import, info, export."""

from __future__ import annotations

import json

import numpy as np
from fabkiri.pattern import read_pattern
from fabkiri.pattern.io import read_obj

from .conftest import ref


def test_new_info_export(tmp_path, run_cli):
    p = tmp_path / "p.json"
    code, _, err = run_cli("new", "--tiles", "7x5", "--tile-size", "12", "--angle", "30", "-o", p)
    assert code == 0, err
    code, out, _ = run_cli("info", p, "--json", "--check")
    info = json.loads(out)
    assert code == 0 and info["closes_both"] and info["tiles"] == 35 and info["holes"] == 24
    assert abs(info["tile_size_mm"] - 12) < 1e-9
    for state in ("deployed", "1", "2"):
        o = tmp_path / f"s{state}.obj"
        code, _, err = run_cli("export", p, "--state", state, "-o", o)
        assert code == 0, err
        v, f = read_obj(o)
        assert np.array_equal(f, read_pattern(p).tiles)


def test_import_reference_with_both_states(tmp_path, run_cli):
    out = tmp_path / "cr.json"
    code, _, err = run_cli("import", ref("compact_reconfigurable_design"), "--contracted",
                           ref("compact_reconfigurable_contracted1"), ref("compact_reconfigurable_contracted2"),
                           "--scale", "10", "-o", out)
    assert code == 0, err
    code, text, _ = run_cli("info", out)
    assert code == 0 and "self-intersecting tiles: [2]" in text
    code, js, _ = run_cli("info", out, "--json", "--check")
    d = json.loads(js)
    assert code == 0 and all(s["supplied_matches"] for s in d["states"])


def test_usage_errors_are_one_line(run_cli, tmp_path):
    for argv in (["new", "--tiles", "0x4", "-o", tmp_path / "x.json"],
                 ["new", "--tiles", "banana", "-o", tmp_path / "x.json"],
                 ["new", "--tiles", "3x3", "--angle", "120", "-o", tmp_path / "x.json"],
                 ["info", tmp_path / "missing.json"],
                 ["new", "--tiles", "3x3", "-o", tmp_path / "nofolder" / "x.json"]):
        code, _, err = run_cli(*argv)
        assert code == 2 and err.count("\n") == 1, (argv, err)
    assert not (tmp_path / "x.json").exists()
