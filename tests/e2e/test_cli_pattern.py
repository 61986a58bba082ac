"""End-to-end: new, import, info, export."""

from __future__ import annotations

import json

import numpy as np
from fabkiri.exchange.obj import read_obj
from fabkiri.exchange.pattern_json import read_pattern

from ..conftest import ref


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
    code, _, err = run_cli(
        "import",
        ref("compact_reconfigurable_design"),
        "--contracted",
        ref("compact_reconfigurable_contracted1"),
        ref("compact_reconfigurable_contracted2"),
        "--scale",
        "10",
        "-o",
        out,
    )
    assert code == 0, err
    code, text, _ = run_cli("info", out)
    assert code == 0 and "self-intersecting tiles: [2]" in text
    code, js, _ = run_cli("info", out, "--json", "--check")
    d = json.loads(js)
    assert code == 0 and all(s["supplied_matches"] for s in d["states"])


def test_usage_errors_are_one_line(run_cli, tmp_path):
    for argv in (
        ["new", "--tiles", "0x4", "-o", tmp_path / "x.json"],
        ["new", "--tiles", "banana", "-o", tmp_path / "x.json"],
        ["new", "--tiles", "3x3", "--angle", "120", "-o", tmp_path / "x.json"],
        ["info", tmp_path / "missing.json"],
        ["new", "--tiles", "3x3", "-o", tmp_path / "nofolder" / "x.json"],
    ):
        code, _, err = run_cli(*argv)
        assert code == 2 and err.count("\n") == 1, (argv, err)
    assert not (tmp_path / "x.json").exists()


def test_a_pattern_format_is_one_registered_strategy(tmp_path, run_cli, monkeypatch, capsys):
    """A format registered from outside (as a new format's module would) is read by its suffix,
    written by ``export --format NAME`` (with the closed state it asks for contracted first) and
    listed among the choices; an unknown name is refused in one line naming the known formats."""
    import pytest
    from fabkiri.api.patterns import export_pattern
    from fabkiri.errors import InputError
    from fabkiri.exchange import file_formats as formats
    from fabkiri.exchange import pattern_json as io
    from fabkiri.pattern import standard_pattern

    monkeypatch.setattr(
        formats._REGISTRIES["pattern"], "members", dict(formats._REGISTRIES["pattern"].members)
    )
    assert formats.format_names(writable=True) == ("obj", "fold", "pykirigami")
    assert formats.format_of(tmp_path / "p.FOLD", "json").name == "fold"
    assert formats.format_of(tmp_path / "p.txt", "obj").name == "obj"

    def write(pattern, state, unit):  # closed state 2's tile centres, one per line
        return "".join(f"{x!r} {y!r}\n" for x, y in pattern.contracted[2].mean(1).tolist())

    def read(path, scale):
        return io.read_pattern(path.with_suffix(".json"))

    formats.register_format(
        formats.PatternFormat(
            "centres",
            (".ctr",),
            read=read,
            write=write,
            closed_states=lambda state: (2,),
            adopt_labels=False,
            said=lambda p, s, out, u: f"wrote {out}: {p.n_tiles} centres",
        )
    )
    src = tmp_path / "p.json"
    io.write_pattern(
        standard_pattern(2, 3), src
    )  # no closed states stored: export contracts state 2
    code, _, err = run_cli("export", src, "--format", "centres", "-o", tmp_path / "p.ctr")
    assert code == 0 and f"wrote {tmp_path / 'p.ctr'}: 6 centres" in err, err
    assert len((tmp_path / "p.ctr").read_text().splitlines()) == 6
    code, out, err = run_cli("info", tmp_path / "p.ctr")  # read by its suffix
    assert code == 0 and "6" in out, err
    with pytest.raises(
        InputError, match=r"^unknown pattern format 'stl'; known: obj, fold, pykirigami, centres$"
    ):
        export_pattern(standard_pattern(2, 2), "stl")
    with pytest.raises(SystemExit) as exc:  # the parser's one line, exit 2
        run_cli("export", src, "--format", "stl", "-o", tmp_path / "p.stl")
    err = capsys.readouterr().err
    assert exc.value.code == 2 and len(err.splitlines()) == 1 and not (tmp_path / "p.stl").exists()
    assert (
        "invalid choice: 'stl' (choose from 'obj', 'fold', 'pykirigami', 'centres', 'tube3d')"
        in err
    )
