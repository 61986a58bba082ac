"""What session 55's hardening left (docs/bad-input.md, "Session 56 (hard56)"): a target too small for its
tiles, a Y-up OBJ, a FOLD state tag written as a string, an interrupt after the files are in place,
and output folders that take no files (read-only, a file, another file system).
"""

from __future__ import annotations

import errno
import json
import os

import numpy as np
import pytest
from fabkiri import fileio
from fabkiri.errors import PatternError
from fabkiri.exchange.fold import fold_text, loads_fold
from fabkiri.exchange.obj import import_obj, obj_text
from fabkiri.exchange.pattern_json import dumps
from fabkiri.mechanics import with_contracted_states
from fabkiri.pattern import standard_pattern

PATTERN = with_contracted_states(standard_pattern(3, 3, tile_size=10.0))


def _one_line(err: str) -> str:
    lines = err.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in err, err
    return lines[0]


# ------------------------------------------------------------------------ a target too small


def test_a_design_under_a_micrometre_is_refused_not_written(tmp_path, run_cli):
    (tmp_path / "t.csv").write_text("0,0\n0.04,0\n0.04,0.03\n0,0.03\n")
    out = tmp_path / "o.json"
    code, _, err = run_cli("design", "--tiles", "4x4", "--target", tmp_path / "t.csv", "-o", out)
    # was: exit 0, a pattern with 0.56 µm edges that every later command refused
    assert code == 2 and "the design's tile" in _one_line(err) and "--size" in err
    assert sorted(os.listdir(tmp_path)) == ["t.csv"]


def test_tiles_under_a_micrometre_are_refused_before_the_solve(tmp_path, run_cli):
    (tmp_path / "t.csv").write_text("0,0\n4,0\n4,3\n0,3\n")
    code, _, err = run_cli(
        "design",
        "--tiles",
        "8x8",
        "--target",
        tmp_path / "t.csv",
        "--size",
        "0.005",
        "-o",
        tmp_path / "o.json",
    )
    assert code == 2 and "would be under 0.001 mm" in _one_line(err)
    assert sorted(os.listdir(tmp_path)) == ["t.csv"]


# ------------------------------------------------------------------------------- Y-up OBJ


def test_a_y_up_obj_reads_as_its_z_up_twin(tmp_path):
    (tmp_path / "z.obj").write_text(obj_text(PATTERN))
    rows = [
        f"v {x!r} 0.0 {-y!r}" for x, y in PATTERN.nodes.tolist()
    ]  # Blender's default export: x, y -> x, -z
    faces = [ln for ln in obj_text(PATTERN).splitlines() if ln.startswith("f ")]
    (tmp_path / "y.obj").write_text("\n".join(rows + faces) + "\n")
    z, y = import_obj(tmp_path / "z.obj"), import_obj(tmp_path / "y.obj")  # y was refused
    assert np.array_equal(y.nodes, z.nodes) and np.array_equal(y.tiles, z.tiles)
    assert y.design["source"]["up_axis"].startswith("y")


def test_an_obj_off_both_planes_is_refused(tmp_path):
    (tmp_path / "t.obj").write_text("v 0 0 0\nv 1 0 1\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n")
    with pytest.raises(PatternError, match="line 2: vertex has z = 1"):
        import_obj(tmp_path / "t.obj")


# ------------------------------------------------------------------------ FOLD state tags


def _tagged(first) -> str:
    d = json.loads(fold_text(PATTERN))
    d["file_frames"][0]["fabkiri:state"] = first
    return json.dumps(d)


def test_a_fold_state_tag_written_as_a_string_is_read():
    pat = loads_fold(_tagged("1"), "t.fold")  # was skipped: state 1 silently lost
    assert sorted(pat.contracted) == [1, 2]
    assert np.allclose(pat.contracted[1], PATTERN.contracted[1])


@pytest.mark.parametrize("tag", [3, True, "closed", None])
def test_a_fold_state_tag_that_names_no_state_is_refused(tag):
    with pytest.raises(PatternError, match="fabkiri:state is"):
        loads_fold(_tagged(tag), "t.fold")


# ------------------------------------------------------------------ interrupts and folders


def test_an_interrupt_after_the_move_names_the_files_on_disk(tmp_path, run_cli, monkeypatch):
    def interrupted(*args, **kwargs):  # the signal lands while the writer clears its scratch
        raise KeyboardInterrupt

    monkeypatch.setattr(fileio.shutil, "rmtree", interrupted)
    out = tmp_path / "p.json"
    code, _, err = run_cli("new", "--tiles", "2x2", "-o", out)
    assert code == 130 and out.exists()
    # was: "interrupted; nothing was written" with p.json written
    assert _one_line(err) == f"fabkiri: interrupted; {out} written (complete), nothing else"


def test_a_read_only_output_folder_is_refused_before_the_work(tmp_path, run_cli, monkeypatch):
    (tmp_path / "p.json").write_text(dumps(PATTERN))
    ro = str(tmp_path / "ro")
    os.mkdir(ro)
    real = os.access
    monkeypatch.setattr(fileio.os, "access", lambda p, m: str(p) != ro and real(p, m))

    def too_late(*args, **kwargs):
        raise AssertionError("the print was built before its folder was checked")

    monkeypatch.setattr(
        fileio, "check_output_folder", too_late
    )  # the writer's own check, at the end
    code, _, err = run_cli("print", tmp_path / "p.json", "-o", f"{ro}/P")
    assert code == 2 and "is not writable" in _one_line(err)


def test_an_output_under_a_file_says_so(tmp_path, run_cli):
    (tmp_path / "t.csv").write_text("x,y\n")
    code, _, err = run_cli("new", "--tiles", "2x2", "-o", tmp_path / "t.csv" / "p.json")
    assert code == 2 and "is a file, not a folder" in _one_line(err)  # was: "does not exist"


def test_an_output_folder_on_another_file_system_is_written(tmp_path, run_cli, monkeypatch):
    (tmp_path / "p.json").write_text(dumps(PATTERN))
    stick = tmp_path / "usb"  # a mount point: no rename reaches it from its parent's file system
    stick.mkdir()
    real = os.replace

    def replace(src, dst):
        if str(dst).startswith(str(stick)) != str(src).startswith(str(stick)):
            raise OSError(errno.EXDEV, os.strerror(errno.EXDEV))
        real(src, dst)

    monkeypatch.setattr(fileio.os, "replace", replace)
    code, _, err = run_cli("cut", tmp_path / "p.json", "--material", "card-0.3", "-o", stick)
    assert code == 0, err  # was: "cannot write .: Invalid cross-device link"
    assert {"p.dxf", "p.svg", "manifest.json"} <= set(os.listdir(stick))


def test_a_design_whose_preview_is_a_folder_writes_nothing(tmp_path, run_cli):
    (tmp_path / "o.png").mkdir()
    out = tmp_path / "o.json"
    code, _, err = run_cli("design", "--tiles", "2x2", "--target", "circle", "-o", out)
    # was: exit 3 (IsADirectoryError) with o.json written
    assert code == 2 and "o.png is a folder" in _one_line(err)  # now before the solve
    assert not out.exists()


def test_a_triangulated_mesh_is_refused_naming_its_file(tmp_path, run_cli):
    d = json.loads(fold_text(PATTERN))
    d["faces_vertices"] = [t for a, b, c, e in d["faces_vertices"] for t in ([a, b, c], [a, c, e])]
    d.pop("file_frames")
    (tmp_path / "tri.fold").write_text(json.dumps(d))  # a quad mesh another tool triangulated
    code, _, err = run_cli("import", tmp_path / "tri.fold", "-o", tmp_path / "o.json")
    line = _one_line(err)  # was: "node 4 is shared by 3 tiles ...", no file named
    assert code == 2 and f"{tmp_path / 'tri.fold'}: node" in line and "shared by" in line
