"""pattern.json and OBJ: round trips and bad input."""

from __future__ import annotations

import json
import subprocess
import sys

import numpy as np
import pytest
from fabkiri.errors import PatternError
from fabkiri.exchange.obj import obj_text, parse_obj
from fabkiri.exchange.pattern_json import dumps, loads, read_pattern, schema
from fabkiri.mechanics import with_contracted_states
from fabkiri.pattern import Pattern, standard_pattern

from ..conftest import TEMPLATES, ref


def good_dict() -> dict:
    return json.loads(dumps(with_contracted_states(standard_pattern(2, 3))))


def test_json_round_trip_is_exact_and_deterministic():
    p = with_contracted_states(standard_pattern(3, 4, tile_size=7.5, angle_deg=33.0))
    text = dumps(p)
    q = loads(text)
    assert np.array_equal(p.nodes, q.nodes) and np.array_equal(p.tiles, q.tiles)
    for s in (1, 2):
        assert np.array_equal(p.contracted[s], q.contracted[s])
    assert dumps(q) == text
    assert q.lattice == p.lattice


def test_schema_ships_with_the_package():
    s = schema()
    assert s["properties"]["format"]["const"] == "fabkiri.pattern"


def test_obj_export_keeps_face_list_and_reimports(tmp_path):
    p = with_contracted_states(standard_pattern(3, 3))
    texts = {st: obj_text(p, st) for st in ("deployed", 1, 2)}
    faces = [parse_obj(t)[1] for t in texts.values()]
    assert all(np.array_equal(f, p.tiles) for f in faces)
    v1, f1 = parse_obj(texts[1])
    assert np.abs(v1[f1] - p.contracted[1]).max() <= 1e-12


def test_template_reads_and_closes():
    p = read_pattern(TEMPLATES / "patterns" / "standard-8x8.json")
    assert p.n_tiles == 64 and set(p.contracted) == {1, 2}


def mutate(fn):
    d = good_dict()
    fn(d)
    return json.dumps(d)


BAD_JSON = {
    "malformed": ('{"format": "fabkiri.pattern", "version": 1,', "malformed JSON"),
    "empty": ("", "empty"),
    "wrong format": (mutate(lambda d: d.update(format="other")), "not a fabkiri pattern"),
    "wrong version": (mutate(lambda d: d.update(version=7)), "unsupported pattern version 7"),
    "nan": (
        mutate(lambda d: None).replace(json.dumps(good_dict()["nodes"][0][0]), "NaN", 1),
        "non-finite",
    ),
    "infinite": (
        mutate(lambda d: None).replace(json.dumps(good_dict()["nodes"][0][0]), "Infinity", 1),
        "non-finite",
    ),
    "non-quad tile": (mutate(lambda d: d["tiles"][0].pop()), "tiles/0"),
    "three tiles at a node": (
        mutate(lambda d: d["tiles"][5].__setitem__(0, d["tiles"][0][2])),
        "shared by 3 tiles",
    ),
    "missing node": (mutate(lambda d: d["tiles"][0].__setitem__(0, 999)), "outside"),
    "unknown key": (mutate(lambda d: d.update(colour="red")), "colour"),
}


@pytest.mark.parametrize("case", sorted(BAD_JSON))
def test_bad_pattern_json_exit_2_one_line_nothing_written(case, tmp_path, run_cli):
    text, needle = BAD_JSON[case]
    src = tmp_path / "bad.json"
    src.write_text(text)
    out = tmp_path / "out.obj"
    for argv in (["info", src], ["export", src, "-o", out]):
        code, stdout, err = run_cli(*argv)
        assert code == 2, (case, err)
        assert err.count("\n") == 1 and err.startswith("fabkiri: error:"), err
        assert needle in err, err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["bad.json"]


BAD_OBJ = {
    "missing vertex": (
        "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1// 2// 3// 5//\n",
        "references vertex 5",
    ),
    "empty": ("", "no vertices"),
    "pentagon": (
        "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 2 0\nf 1 2 3 4 5\n",
        "tiles must be quads",
    ),
    "quads and triangles": (
        "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\nf 1 2 3\n",
        "all of one kind",
    ),
    "garbage": ("v a b c\n", "not numbers"),
    "not planar": ("v 0 0 1\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n", "planar"),
}


@pytest.mark.parametrize("case", sorted(BAD_OBJ))
def test_bad_obj_exit_2(case, tmp_path, run_cli):
    text, needle = BAD_OBJ[case]
    src = tmp_path / "bad.obj"
    src.write_text(text)
    code, _, err = run_cli("import", src, "-o", tmp_path / "p.json")
    assert code == 2 and needle in err and err.count("\n") == 1, err
    assert not (tmp_path / "p.json").exists()


def test_contracted_obj_with_other_faces_is_rejected(tmp_path, run_cli):
    other = tmp_path / "c.obj"
    other.write_text(
        ref("compact_reconfigurable_contracted1")
        .read_text()
        .replace("f 38// 7// 6// 10//", "f 7// 6// 10// 38//")
    )
    code, _, err = run_cli(
        "import",
        ref("compact_reconfigurable_design"),
        "--contracted",
        other,
        "-o",
        tmp_path / "p.json",
    )
    assert code == 2 and "face list differs" in err


def test_model_rejects_inconsistent_data():
    p = standard_pattern(2, 2)
    nodes = p.nodes.copy()
    nodes[3, 1] = np.nan
    with pytest.raises(PatternError, match="node 3 has a non-finite coordinate"):
        Pattern(nodes=nodes, tiles=p.tiles)
    with pytest.raises(PatternError, match="contracted state 1 must hold 4 corners per tile"):
        Pattern(nodes=p.nodes, tiles=p.tiles, contracted={1: np.zeros((3, 4, 2))})


@pytest.mark.slow  # two interpreters; the quick loop runs the CLI as a real process in test_bad_input.py and test_startup.py
def test_console_script_runs(tmp_path):
    out = tmp_path / "p.json"
    r = subprocess.run(
        [sys.executable, "-m", "fabkiri.cli.main", "new", "--tiles", "2x3", "-o", str(out)],
        capture_output=True,
        text=True,
    )
    assert r.returncode == 0, r.stderr
    r = subprocess.run(
        [sys.executable, "-m", "fabkiri.cli.main", "info", str(out), "--check", "--json"],
        capture_output=True,
        text=True,
    )
    assert r.returncode == 0 and json.loads(r.stdout)["closes_both"] is True


def test_written_files_are_readable_by_others(tmp_path):
    import os
    import stat

    from fabkiri.fileio import atomic_write, atomic_write_many

    old = os.umask(0o022)
    try:
        f = atomic_write(tmp_path / "a.txt", "x")
        g = atomic_write_many(tmp_path / "d", {"b.txt": "y"})[0]
    finally:
        os.umask(old)
    assert stat.S_IMODE(f.stat().st_mode) == 0o644
    assert stat.S_IMODE(g.stat().st_mode) == 0o644


def test_unwritable_output_is_a_one_line_error(run_cli, tmp_path):
    import os

    ro = tmp_path / "ro"
    ro.mkdir()
    ro.chmod(0o500)
    target = (
        "/proc/fabkiri-test.json" if os.geteuid() == 0 else str(ro / "p.json")
    )  # root ignores modes
    code, _, err = run_cli("new", "--tiles", "2x2", "-o", target)
    assert code == 2 and err.count("\n") == 1 and "write" in err, err
