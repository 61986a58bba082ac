"""The file-format registry (fabkiri.exchange.file_formats): every format named once, each one that
both writes and reads gives back what it wrote, unknown names refused in one line, and a new format
is one module plus one line of the table."""

from __future__ import annotations

import textwrap

import numpy as np
import pytest
from fabkiri.errors import InputError, VerifyError
from fabkiri.exchange import file_formats as ff
from fabkiri.exchange.drawing import SheetDrawing
from fabkiri.mechanics.contract import with_contracted_states
from fabkiri.pattern import standard_pattern


@pytest.fixture(scope="module")
def closed_pattern():
    return with_contracted_states(standard_pattern(3, 2))


def _corners(p):
    """Every state's tile corners: the node numbering a format may change, the geometry it may not."""
    out = {"deployed": p.nodes[p.tiles]}
    out.update({s: np.asarray(c) for s, c in p.contracted.items()})
    return out


def test_every_format_is_named_once_with_its_family():
    assert ff.known_formats() == {
        "json": "pattern",
        "obj": "pattern",
        "fold": "pattern",
        "pykirigami": "pattern",
        "dxf": "drawing",
        "svg": "drawing",
        "3mf": "solid",
        "stl": "solid",
        "step": "solid",
    }
    for name, family in ff.known_formats().items():
        fmt = ff.file_format(name)
        assert fmt.name == name and fmt.family == family


def test_the_stable_names_are_importable_from_exchange():
    from fabkiri.exchange import dumps, loads, read_pattern, write_pattern
    from fabkiri.exchange.pattern_json import dumps as d

    assert dumps is d and callable(loads) and callable(read_pattern) and callable(write_pattern)


def test_json_round_trips(closed_pattern, tmp_path):
    from fabkiri.exchange import read_pattern, write_pattern

    path = write_pattern(closed_pattern, tmp_path / "p.json")
    back = ff.format_of(path, "obj").read(path, 1.0)
    assert back.kind == closed_pattern.kind
    for state, corners in _corners(closed_pattern).items():
        assert np.array_equal(_corners(back)[state], corners), state
    assert read_pattern(path).n_tiles == closed_pattern.n_tiles


@pytest.mark.parametrize("name", ff.format_names(writable=True))
def test_every_writable_pattern_format_round_trips(name, closed_pattern, tmp_path):
    fmt = ff.pattern_format(name, writable=True)
    assert fmt.read is not None, f"{name} writes but cannot read"
    unit = 2.5  # mm per file unit: the reader's scale undoes the writer's
    written = fmt.write(closed_pattern, "deployed", unit)
    path = tmp_path / f"p{fmt.suffixes[0] if fmt.suffixes else ''}"
    if isinstance(written, dict):
        path.mkdir()
        for file_name, text in written.items():
            (path / file_name).write_text(text)
    else:
        path.write_text(written)
    assert ff.format_of(path, "json") is fmt  # chosen by its suffix (or as a folder)
    scale = 1.0 if name in ("obj", "fold") else unit  # OBJ and FOLD are written in mm
    back = fmt.read(path, scale)
    got, want = _corners(back), _corners(closed_pattern)
    assert back.n_tiles == closed_pattern.n_tiles and set(got) <= set(want)
    for state in got:
        assert np.allclose(got[state], want[state], rtol=0, atol=1e-9), (name, state)


def _sheet():
    sheet = SheetDrawing(1, 40.0, 30.0)
    sheet.add("CUT", np.array([[1.0, 1.0], [11.0, 1.0], [11.0, 6.5], [1.0, 6.5]]), True)
    sheet.add("CUT", np.array([[2.0, 20.0], [30.25, 20.0], [30.25, 25.125]]), False)
    sheet.add("ENGRAVE", np.array([[5.0, 5.0], [6.0, 7.0]]), False, group=0)
    sheet.add("NOTES", np.array([[0.0, 0.0], [40.0, 0.0], [40.0, 30.0], [0.0, 30.0]]), True)
    return sheet


@pytest.mark.parametrize("name", ["dxf", "svg"])
def test_every_drawing_format_round_trips(name, tmp_path):
    fmt = ff.drawing_format(name)
    sheet = _sheet()
    path = tmp_path / f"sheet{fmt.suffixes[0]}"
    path.write_bytes(fmt.write(sheet, "default"))
    for layer in ("CUT", "ENGRAVE"):
        lw = ff.read_cut_file(path, layer)
        want = sheet.layers[layer]
        assert lw.layer_found and lw.closed == [c for _, c in want], (name, layer)
        for got, (pts, _) in zip(lw.polylines, want, strict=True):
            assert np.allclose(got, pts, rtol=0, atol=1e-9), (name, layer)


def _meshes():
    cube_v = np.array([[x, y, z] for x in (0, 1) for y in (0, 1) for z in (0, 1)], float) * 2.5
    cube_f = np.array(
        [
            [0, 2, 1],
            [1, 2, 3],
            [4, 5, 6],
            [5, 7, 6],
            [0, 1, 4],
            [1, 5, 4],
            [2, 6, 3],
            [3, 6, 7],
            [0, 4, 2],
            [2, 4, 6],
            [1, 3, 5],
            [3, 7, 5],
        ]
    )
    tet_v = np.array([[10, 0, 0], [11, 0, 0], [10, 1, 0], [10, 0, 1.25]], float)
    tet_f = np.array([[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]])
    return {"cube": (cube_v, cube_f), "tetra": (tet_v, tet_f)}


def _triangles(meshes):
    """Every triangle's corners, as a sorted set (vertex numbering and order are the file's)."""
    tris = np.concatenate([v[f] for _, v, f in meshes])
    return sorted(map(tuple, np.round(tris.reshape(len(tris), 9), 6).tolist()))


@pytest.mark.parametrize("name", ["3mf", "stl"])
def test_every_readable_solid_format_round_trips(name):
    fmt = ff.solid_format(name)
    assert fmt.read is not None
    meshes = _meshes()
    back = fmt.read(fmt.write(meshes))
    assert _triangles(back) == _triangles([(n, v, f) for n, (v, f) in meshes.items()])
    if name == "3mf":  # one named object per mesh
        assert [n for n, _, _ in back] == list(meshes)


def test_a_print_project_3mf_reads_back_as_its_volumes():
    from fabkiri.fabricate.print.printers import load_printer
    from fabkiri.fabricate.print.threemf import Part, project_3mf

    meshes = _meshes()
    parts = [Part(n, "PLA", v, f) for n, (v, f) in meshes.items()]
    back = ff.solid_format("3mf").read(project_3mf("bed", parts, load_printer("prusa-mk4")))
    assert [n for n, _, _ in back] == list(meshes)
    assert _triangles(back) == _triangles([(n, v, f) for n, (v, f) in meshes.items()])


def test_step_is_registered_as_written_only():
    fmt = ff.solid_format("step")
    assert fmt.read is None and callable(fmt.write) and ".step" in fmt.suffixes


@pytest.mark.parametrize(
    ("lookup", "message"),
    [
        (
            ff.file_format,
            r"^unknown file format 'xyz'; known: json, obj, fold, pykirigami, dxf, svg, 3mf, stl, step$",
        ),
        (ff.pattern_format, r"^unknown pattern format 'xyz'; known: json, obj, fold, pykirigami$"),
        (ff.drawing_format, r"^unknown drawing format 'xyz'; known: dxf, svg$"),
        (ff.solid_format, r"^unknown solid format 'xyz'; known: 3mf, stl, step$"),
    ],
)
def test_an_unknown_format_is_one_line(lookup, message):
    with pytest.raises(InputError, match=message):
        lookup("xyz")


def test_a_drawing_of_an_unknown_suffix_is_refused_in_one_line(tmp_path):
    path = tmp_path / "sheet.pdf"
    path.write_bytes(b"%PDF")
    with pytest.raises(VerifyError, match=r"sheet\.pdf: a layout must be a \.dxf or \.svg file$"):
        ff.read_cut_file(path)
    with pytest.raises(VerifyError, match="no such layout file"):
        ff.read_cut_file(tmp_path / "missing.dxf")


def test_a_new_format_is_one_module_and_one_table_line(tmp_path, monkeypatch, closed_pattern):
    """The module registers itself; the table's line names it, and every lookup finds it."""
    (tmp_path / "fabkiri_test_centres.py").write_text(
        textwrap.dedent(
            """
            from fabkiri.exchange.file_formats import PatternFormat, register_format

            def centres_text(pattern, state, unit):
                return "".join(f"{x!r} {y!r}\\n" for x, y in pattern.nodes[pattern.tiles].mean(1).tolist())

            register_format(PatternFormat("centres", (".ctr",), write=centres_text))
            """
        )
    )
    monkeypatch.syspath_prepend(str(tmp_path))
    reg = ff._REGISTRIES["pattern"]
    monkeypatch.setattr(reg, "members", dict(reg.members))  # undone after the test
    monkeypatch.delitem(__import__("sys").modules, "fabkiri_test_centres", raising=False)
    assert "centres" not in ff.known_formats()
    monkeypatch.setitem(ff.BUILTIN, "centres", ("pattern", "fabkiri_test_centres"))  # the one line
    assert ff.known_formats()["centres"] == "pattern"
    assert ff.format_names(writable=True)[-1] == "centres"
    text = ff.file_format("centres").write(closed_pattern, "deployed", None)
    assert len(text.splitlines()) == closed_pattern.n_tiles
