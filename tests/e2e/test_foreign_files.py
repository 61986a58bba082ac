"""Files other tools write: outlines from spreadsheets and editors, FOLD files from other programs.

Each is read as the numbers it holds or refused with one line (exit 2, nothing written); never read
as another shape or size than the file says (session 55's hardening, docs/bad-input.md).
"""

from __future__ import annotations

import json

import numpy as np
import pytest
from fabkiri.api.patterns import import_pattern
from fabkiri.design.targets.lookup import load_target
from fabkiri.errors import InputError, PatternError
from fabkiri.exchange.fold import fold_text, loads_fold
from fabkiri.exchange.obj import read_obj
from fabkiri.exchange.pattern_json import dumps
from fabkiri.mechanics import with_contracted_states
from fabkiri.pattern import standard_pattern
from fabkiri.pattern.kinds.kagome.lattice import standard_kagome
from fabkiri.verify.pattern_checks import topology_checks

SQUARE = [[0, 0], [40, 0], [40, 30], [0, 30]]
ROWS = "0,0\n40,0\n40,30\n0,30\n"

# name: file text (bytes for encodings); each reads as the 40 x 30 rectangle
OUTLINES = {
    "bom.csv": b"\xef\xbb\xbf" + ROWS.encode(),  # the first row was taken for a header
    "bom.json": b"\xef\xbb\xbf" + json.dumps(SQUARE).encode(),
    "id-column.csv": "id,x,y\n1,0,0\n2,40,0\n3,40,30\n4,0,30\n",  # was read as (id, x)
    "units-header.csv": "Y [mm];X [mm];Z\n0;0;5\n0;40;5\n30;40;5\n30;0;5\n",
    "decimal-comma.csv": "x;y\n0,0;0,0\n40,0;0,0\n40,0;30,0\n0,0;30,0\n",  # was 0,0 / 40,0 ...
    "quoted.csv": '"x","y"\n"0","0"\n"40","0"\n"40","30"\n"0","30"\n',
    "crlf-closed.csv": "x,y\r\n0,0\r\n40,0\r\n40,30\r\n0,30\r\n0,0\r\n",
}

SVG = '<svg xmlns="http://www.w3.org/2000/svg" {}>{}</svg>'
OUTLINES |= {
    # scaled by a group's and its own transform: was read as 40 x 30 (as if untransformed)
    "transformed.svg": SVG.format(
        'width="100mm" height="100mm" viewBox="0 0 100 100"',
        '<g transform="translate(5,5)"><path transform="scale(0.5,1)" d="M0 0H80V30H0Z"/></g>',
    ),
    # 1 user unit = 0.2646 mm (a 96 dpi viewBox in a mm-sized page): was read as 151.2 x 113.4
    "px-viewbox.svg": SVG.format(
        'width="400mm" height="400mm" viewBox="0 0 1511.811 1511.811"',
        '<path d="M0 0H151.1811V113.3858H0Z"/>',
    ),
    "inch.svg": SVG.format(
        'width="4in" height="3in" viewBox="0 0 4 3"', '<path d="M0 0H1.5748V1.1811H0Z"/>'
    ),
}

# name: (file text, words of the refusal)
BAD_OUTLINES = {
    "xyz.csv": ("0,0,5\n40,0,5\n40,30,5\n0,30,5\n", "3 numbers"),  # was read as its x, y
    "thousands.csv": ("0,0\n1 000,0\n1 000,750\n0,750\n", "3 numbers"),
    "empty.csv": ("x,y\n", "no x,y rows"),
    "kilometres.csv": ("0,0\n1e7,0\n1e7,1e7\n0,1e7\n", "from the origin"),  # 10 km: a unit mistake
    "micrometres.csv": ("0,0\n4e-6,0\n4e-6,3e-6\n0,3e-6\n", "give a size"),
    "utf16.csv": (("x,y\n" + ROWS).encode("utf-16"), "not a UTF-8 text file"),
}


def _write(path, text):
    if isinstance(text, bytes):
        path.write_bytes(text)
    else:
        path.write_text(text, newline="")
    return path


@pytest.mark.parametrize("name", sorted(OUTLINES))
def test_an_outline_reads_as_the_shape_its_file_holds(name, tmp_path):
    tgt = load_target(str(_write(tmp_path / name, OUTLINES[name])))
    assert len(tgt.points) == 4
    assert np.allclose(np.ptp(tgt.points, axis=0), [40.0, 30.0], rtol=1e-5)


@pytest.mark.parametrize("name", sorted(BAD_OUTLINES))
def test_an_outline_that_cannot_be_read_exactly_is_refused(name, tmp_path):
    text, words = BAD_OUTLINES[name]
    with pytest.raises(InputError, match=words):
        load_target(str(_write(tmp_path / name, text)))


def test_a_design_of_an_outline_in_the_wrong_unit_writes_nothing(tmp_path, run_cli):
    _write(tmp_path / "km.csv", BAD_OUTLINES["kilometres.csv"][0])
    out = tmp_path / "o.json"
    code, _, err = run_cli("design", "--tiles", "4x4", "--target", tmp_path / "km.csv", "-o", out)
    err = err.strip().splitlines()
    assert code == 2 and len(err) == 1 and "from the origin" in err[0]
    assert not out.exists()


def test_a_pattern_with_sub_micrometre_edges_is_refused_not_crashed_on(tmp_path, run_cli):
    small = standard_pattern(2, 2, tile_size=5e-4)  # verify and cut raised AttributeError on it
    (tmp_path / "small.json").write_text(dumps(small))
    code, _, err = run_cli("verify", tmp_path / "small.json")
    err = err.strip().splitlines()
    assert code == 2 and len(err) == 1 and "at least 0.001 mm" in err[0]


# ------------------------------------------------------------------------------------------ FOLD

PATTERN = with_contracted_states(standard_pattern(2, 2, tile_size=10.0))


def _fold(**changes) -> dict:
    d = json.loads(fold_text(PATTERN))
    d.update(changes)
    return d


def _read(d: dict, scale: float = 1.0):
    text = json.dumps(d)
    return loads_fold(text, "t.fold") if scale == 1.0 else loads_fold(text, "t.fold", scale)


@pytest.mark.parametrize(("unit", "mm"), [("in", 25.4), ("cm", 10.0), ("m", 1000.0)])
def test_a_fold_file_is_read_in_its_frame_unit(unit, mm):
    pat = _read(_fold(frame_unit=unit))  # was read as mm whatever the unit
    assert np.allclose(pat.nodes, PATTERN.nodes * mm)
    assert np.allclose(pat.contracted[1], PATTERN.contracted[1] * mm)


def test_a_fold_file_without_a_unit_takes_the_scale():
    assert np.allclose(_read(_fold(frame_unit="unit"), 2.0).nodes, PATTERN.nodes * 2.0)


@pytest.mark.parametrize(
    ("changes", "scale", "words"),
    [
        ({"frame_unit": "in"}, 2.0, "frame_unit is 'in'"),
        ({"frame_unit": "furlong"}, 1.0, "unknown frame_unit"),
        ({"vertices_coords": [[True, False]] + _fold()["vertices_coords"][1:]}, 1.0, "numbers"),
    ],
    ids=["unit and scale", "unknown unit", "booleans"],
)
def test_a_fold_file_that_cannot_be_read_exactly_is_refused(changes, scale, words):
    with pytest.raises(PatternError, match=words):
        _read(_fold(**changes), scale)


def test_a_folded_3d_frame_of_another_tool_is_no_closed_state():
    d = _fold()
    folded = {
        "frame_classes": ["foldedForm"],
        "frame_attributes": ["3D"],
        "vertices_coords": [[x, y, 1.0 + i] for i, (x, y) in enumerate(d["vertices_coords"])],
    }
    for f in d["file_frames"]:
        f.pop("fabkiri:state")
    d["file_frames"].insert(0, folded)  # was read as closed state 1 with its z dropped
    pat = _read(d)
    assert sorted(pat.contracted) == [1, 2]
    assert np.allclose(pat.contracted[1], PATTERN.contracted[1])


def test_clockwise_fold_faces_are_turned_as_obj_faces_are():
    pat = _read(_fold(faces_vertices=[f[::-1] for f in _fold()["faces_vertices"]]))
    assert np.array_equal(pat.tiles, PATTERN.tiles)  # verify failed "tiles counter-clockwise"
    assert np.allclose(pat.contracted[2], PATTERN.contracted[2])


def test_a_kagome_fold_file_keeps_its_kind_at_a_scale(tmp_path):
    kagome = with_contracted_states(standard_kagome(3, 3, tile_size=10.0))
    d = json.loads(fold_text(kagome)) | {"frame_unit": "unit"}
    (tmp_path / "k.fold").write_text(json.dumps(d))
    pat = import_pattern(str(tmp_path / "k.fold"), scale=2.0)  # was: "every tile must be a quad"
    assert pat.kind == "kagome" and np.allclose(pat.nodes, kagome.nodes * 2.0)


@pytest.mark.parametrize("tiles", [(1, 4), (2, 2), (3, 2)])
def test_a_kagome_lattice_without_holes_passes_its_topology_check(tiles):
    # new --lattice kagome --tiles 2x2 wrote a pattern verify failed and export refused
    checks = topology_checks(standard_kagome(*tiles, tile_size=10.0))
    assert [c.ok for c in checks] == [True], checks[0].detail


def test_obj_faces_may_count_vertices_back_from_the_last(tmp_path):
    square = "v 0 0 0\nv 10 0 0\nv 10 10 0\nv 0 10 0\n"
    (tmp_path / "rel.obj").write_text(square + "f -4 -3 -2 -1\n")  # was: "references vertex -4"
    (tmp_path / "abs.obj").write_text(square + "f 1 2 3 4\n")
    assert np.array_equal(read_obj(tmp_path / "rel.obj")[1], read_obj(tmp_path / "abs.obj")[1])
