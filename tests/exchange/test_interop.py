"""FOLD and PyKirigami export: field names and the checks the other tools make, and round trips."""

from __future__ import annotations

import json

import numpy as np
import pytest
from fabkiri.exchange.pattern_json import read_pattern

from ..conftest import TEMPLATES

# every property name FOLD 1.2 defines (edemaine/fold doc/spec.md); anything else must carry a colon
FOLD_SPEC_NAMES = {
    "file_spec",
    "file_creator",
    "file_author",
    "file_title",
    "file_description",
    "file_classes",
    "file_frames",
    "frame_title",
    "frame_description",
    "frame_author",
    "frame_classes",
    "frame_attributes",
    "frame_unit",
    "frame_parent",
    "frame_inherit",
    "vertices_coords",
    "vertices_vertices",
    "vertices_edges",
    "vertices_faces",
    "edges_vertices",
    "edges_faces",
    "edges_assignment",
    "edges_foldAngle",
    "edges_length",
    "edges_edges",
    "faces_vertices",
    "faces_edges",
    "faces_faces",
    "faceOrders",
    "edgeOrders",
}
FOLD_ASSIGNMENTS = {"B", "M", "V", "F", "U", "C", "J"}
FOLD_FILE_ONLY = {k for k in FOLD_SPEC_NAMES if k.startswith("file_")}


def _source(name: str):
    """``data/NAME`` (tests/data) or ``patterns/NAME`` (templates/patterns), as a pattern file."""
    where, stem = name.split("/")
    root = TEMPLATES.parent / "tests" / "data" if where == "data" else TEMPLATES / "patterns"
    return root / f"{stem}.json"


def _names_ok(d: dict, top: bool) -> list[str]:
    bad = [k for k in d if k not in FOLD_SPEC_NAMES and ":" not in k]
    if not top:
        bad += [k for k in d if k in FOLD_FILE_ONLY]
    return bad


@pytest.mark.parametrize("name", ["data/heart-16x16-rigid", "patterns/circle-8x8"])
def test_fold_export_follows_the_spec(run_cli, tmp_path, name):
    out = tmp_path / "p.fold"
    code, _, err = run_cli("export", _source(name), "--format", "fold", "-o", out)
    assert code == 0, err
    d = json.loads(out.read_text())
    assert _names_ok(d, True) == []
    assert isinstance(d["file_spec"], (int, float)) and 1 <= d["file_spec"] < 2
    assert isinstance(d["file_creator"], str)
    V = np.asarray(d["vertices_coords"])
    E = np.asarray(d["edges_vertices"])
    F = np.asarray(d["faces_vertices"])
    assert V.ndim == 2 and V.shape[1] in (2, 3)
    assert E.shape[1] == 2 and 0 <= E.min() and E.max() < len(V)
    assert 0 <= F.min() and F.max() < len(V)
    assert set(d["edges_assignment"]) <= FOLD_ASSIGNMENTS and len(d["edges_assignment"]) == len(E)
    # faces counter-clockwise, as the spec asks
    x, y = V[F][..., 0], V[F][..., 1]
    assert ((x * np.roll(y, -1, 1) - np.roll(x, -1, 1) * y).sum(1) > 0).all()
    # every face edge is listed once, and each edge's face holds it
    for e, (f,) in zip(E.tolist(), d["edges_faces"]):
        k = F[f].tolist().index(e[0])
        assert F[f][(k + 1) % 4] == e[1]
    frames = d["file_frames"]
    assert [f["fabkiri:state"] for f in frames] == [1, 2]
    for fr in frames:
        assert _names_ok(fr, False) == []
        assert fr["frame_parent"] == 0 and fr["frame_inherit"] is True
        assert np.asarray(fr["vertices_coords"]).shape == V.shape


def test_fold_round_trip(run_cli, tmp_path):
    src = _source("data/heart-16x16-rigid")
    run_cli("export", src, "--format", "fold", "-o", tmp_path / "p.fold")
    code, _, err = run_cli("import", tmp_path / "p.fold", "-o", tmp_path / "back.json")
    assert code == 0, err
    a, b = read_pattern(src), read_pattern(tmp_path / "back.json")
    assert np.array_equal(a.tiles, b.tiles) and np.array_equal(a.nodes, b.nodes)
    for s in (1, 2):  # closed states: each node at its first tile's copy, so equal to the stored
        assert np.abs(a.contracted[s] - b.contracted[s]).max() < 1e-9 * a.tile_size
    code, out, _ = run_cli("info", tmp_path / "back.json", "--check")
    assert code == 0


def _pykirigami_loader_checks(folder, max_distance=0.05):
    """What PyKirigami's utils/config.py checks when it loads a model (our reading of it)."""

    def tiles(name):
        rows = []
        for line in (folder / name).read_text().splitlines():
            vals = [float(v) for v in line.split()]
            assert len(vals) % 3 == 0 and vals, f"{name}: a line is not x y z triplets"
            rows.append(np.reshape(vals, (-1, 3)))
        return rows

    start, target = tiles("vertices.txt"), tiles("target.txt")
    assert len(start) == len(target)
    cons = [
        list(map(int, line.split()))
        for line in (folder / "constraints.txt").read_text().splitlines()
    ]
    assert all(len(c) == 5 and c[4] in (1, 2, 3) for c in cons)
    keys = sorted(tuple(c) for c in cons)
    assert all(keys[i] != keys[i - 1] for i in range(1, len(keys))), "duplicate constraint"
    worst = 0.0
    for verts in (start, target):
        for f1, v1, f2, v2, _ in cons:
            assert 0 <= f1 < len(verts) and 0 <= f2 < len(verts), "face index out of bounds"
            assert 0 <= v1 < len(verts[f1]) and 0 <= v2 < len(verts[f2]), (
                "vertex index out of bounds"
            )
            worst = max(worst, float(np.linalg.norm(verts[f1][v1] - verts[f2][v2])))
    assert worst <= max_distance
    return len(start), len(cons), worst


@pytest.mark.parametrize("name", ["data/heart-16x16-rigid", "patterns/circle-8x8"])
def test_pykirigami_export_passes_its_loader_checks(run_cli, tmp_path, name):
    src = _source(name)
    code, _, err = run_cli("export", src, "--format", "pykirigami", "-o", tmp_path / "m")
    assert code == 0, err
    p = read_pattern(src)
    n_tiles, n_cons, worst = _pykirigami_loader_checks(tmp_path / "m")
    assert (n_tiles, n_cons) == (p.n_tiles, p.topology.n_hinges)
    assert worst < 1e-9  # hinge copies coincide in both files, far inside the loader's 0.05
    # unit tiles, as in its examples
    t = np.array(
        [
            list(map(float, line.split()))
            for line in (tmp_path / "m" / "target.txt").read_text().splitlines()
        ]
    )
    edge = np.linalg.norm(t[:, 3:5] - t[:, 0:2], axis=1)
    assert 0.3 < edge.mean() < 3


def test_pykirigami_round_trip(run_cli, tmp_path):
    src = TEMPLATES / "patterns" / "circle-8x8.json"
    a = read_pattern(src)
    run_cli("export", src, "--format", "pykirigami", "--unit", "1", "-o", tmp_path / "m")
    code, _, err = run_cli("import", tmp_path / "m", "-o", tmp_path / "back.json")
    assert code == 0, err
    b = read_pattern(tmp_path / "back.json")
    assert np.array_equal(a.tiles, b.tiles)  # nodes numbered by first corner, as the lattice does
    assert np.abs(a.nodes - b.nodes).max() < 1e-12 * a.tile_size
    assert np.abs(a.contracted[1] - b.contracted[1]).max() < 1e-12 * a.tile_size


def test_pykirigami_import_rejects_bad_folder(run_cli, tmp_path):
    (tmp_path / "m").mkdir()
    (tmp_path / "m" / "vertices.txt").write_text("0 0 0 1 0 0 1 1 0 0 1 0\n")
    code, _, err = run_cli("import", tmp_path / "m", "-o", tmp_path / "x.json")
    assert code == 2 and "missing" in err and not (tmp_path / "x.json").exists()
