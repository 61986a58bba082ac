"""The top-level doors (fabkiri.standard, load, save, design, contract, deploy, verify, cut,
print_pattern, make): plain values in, one result type out, the commands' bytes written."""

from __future__ import annotations

import subprocess
import sys

import fabkiri
import numpy as np
import pytest
from fabkiri.api.design import PatternRequest
from fabkiri.errors import InputError
from fabkiri.fabricate.cut.materials import load_material
from fabkiri.pattern.tilecount import tile_count

PNG = b"\x89PNG\r\n\x1a\n"


@pytest.mark.parametrize(
    "given, rows_cols",
    [("8x8", (8, 8)), (" 8 X 12 ", (8, 12)), ("3×4", (3, 4)), ((8, 12), (8, 12)), ([3, 4], (3, 4))],
)
def test_tiles_as_text_or_pair(given, rows_cols):
    assert tile_count(given) == rows_cols
    assert tile_count((np.int64(rows_cols[0]), rows_cols[1])) == rows_cols


@pytest.mark.parametrize(
    "bad", ["8", "8x", "axb", "8x8x8", (8,), (8, 8, 8), (0, 3), (True, 2), 8, 8.5, (8.5, 2), None]
)
def test_bad_tiles_are_one_sentence(bad):
    with pytest.raises(InputError) as err:
        tile_count(bad)
    assert "\n" not in str(err.value) and "tiles" in str(err.value)


def test_pattern_request_takes_rxc_text():
    assert PatternRequest(tiles="8x8").tiles == (8, 8)
    assert PatternRequest(tiles=(6, 4)).tiles == (6, 4)
    assert PatternRequest(tiles=None, kind="kagome").tiles is None
    with pytest.raises(InputError, match="ROWSxCOLS"):
        PatternRequest(tiles="eight")  # was "too many values to unpack"


def test_make_takes_rxc_text_and_refuses_bad_tiles():
    with pytest.raises(InputError, match="ROWSxCOLS"):
        fabkiri.make("circle", 100, material="acrylic-3", tiles="8 by 8")
    with pytest.raises(InputError, match="2x2"):
        fabkiri.make("circle", 100, material="acrylic-3", tiles="1x8")
    with pytest.raises(InputError, match="no option 'colour'"):
        fabkiri.make("circle", 100, material="acrylic-3", colour="red")


def test_import_fabkiri_stays_cheap_and_doors_share_package_names():
    code = (
        "import sys, fabkiri\nheavy = [m for m in ('numpy', 'scipy', 'PIL') if m in sys.modules]\n"
        "import fabkiri.design.quad.solve, fabkiri.verify.report\n"
        "print(heavy, callable(fabkiri.design), callable(fabkiri.verify), "
        "fabkiri.design.quad.solve.__name__, fabkiri.verify.Report.__name__)"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.split() == ["[]", "True", "True", "fabkiri.design.quad.solve", "Report"]


@pytest.fixture(scope="module")
def square():
    return fabkiri.standard("4x4")


def test_standard_pattern_shows_itself(square):
    assert sorted(square.contracted) == [1, 2] and len(square.tiles) == 16
    assert "array(" not in repr(square) and square._repr_png_().startswith(PNG)
    kagome = fabkiri.standard((2, 3), "kagome")
    assert kagome.kind == "kagome" and sorted(kagome.contracted) == [1, 2]
    with pytest.raises(InputError, match="tessellation"):
        fabkiri.standard("4x4", "hexagon")
    with pytest.raises(InputError, match="at least one row"):
        fabkiri.standard("0x4")


def _check_result(result, folder, names):
    """What every result has: ok, a one-line summary, a repr without arrays or bytes, a picture,
    and write() writing its files named after the pattern."""
    assert result.ok
    line = result.summary()
    assert isinstance(line, str) and "\n" not in line and line in repr(result)
    assert "array(" not in repr(result) and "\\x" not in repr(result)
    assert result._repr_png_().startswith(PNG)
    written = result.write(folder)
    assert {p.name for p in written} >= set(names)
    assert all(p.read_bytes() for p in written)


def test_load_save_and_results_named_after_the_file(square, tmp_path):
    fabkiri.save(square, tmp_path / "sq.json")
    fabkiri.save(square, tmp_path / "sq.fold")
    fabkiri.save(square, tmp_path / "sq-model", file_format="pykirigami")
    with pytest.raises(InputError, match="file_format"):
        fabkiri.save(square, tmp_path / "sq.xyz")
    assert not (tmp_path / "sq.xyz").exists() and (tmp_path / "sq-model").is_dir()
    loaded, folded = fabkiri.load(tmp_path / "sq.json"), fabkiri.load(tmp_path / "sq.fold")
    assert np.allclose(loaded.nodes, square.nodes) and len(folded.tiles) == 16
    closed = fabkiri.contract(loaded)
    assert closed.stem == "sq" and "closes in both" in closed.summary()
    _check_result(closed, tmp_path / "out", ["sq.json"])
    checked = fabkiri.verify(tmp_path / "sq.json")
    _check_result(checked, tmp_path / "out", ["sq.verify.json"])
    assert checked.summary().endswith("checks, passed")


def test_write_never_replaces_the_input(square, tmp_path):
    fabkiri.save(square, tmp_path / "sq.json")
    before = (tmp_path / "sq.json").read_bytes()
    closed = fabkiri.contract(fabkiri.load(tmp_path / "sq.json"))
    with pytest.raises(InputError, match="input"):
        closed.write(tmp_path)
    assert (tmp_path / "sq.json").read_bytes() == before


def test_cut_is_the_bytes_fabkiri_cut_writes(square, tmp_path, run_cli):
    fabkiri.save(square, tmp_path / "sq.json")
    cut = fabkiri.cut(fabkiri.load(tmp_path / "sq.json"), material="acrylic-3", scale="auto")
    assert cut.n_sheets == 1 and cut.material == "acrylic-3" and "sq.dxf" in cut.files
    _check_result(cut, tmp_path / "door", ["sq.dxf", "sq.svg", "sq.png", "manifest.json"])
    code, _, err = run_cli("cut", tmp_path / "sq.json", "--scale", "auto", "-o", tmp_path / "cli")
    assert code == 0, err
    cli = {p.name: p.read_bytes() for p in (tmp_path / "cli").iterdir()}
    door = {p.name: p.read_bytes() for p in (tmp_path / "door").iterdir()}
    assert cli == door
    assert "array(" not in repr(cut.outcome) and "array(" not in repr(cut.outcome.result.sheets[0])


def test_cut_takes_a_material_object_and_refuses_strangers(square):
    by_name = fabkiri.cut(square, "acrylic-3", settings=["kerf_mm=0.1"])
    by_object = fabkiri.cut(square, load_material("acrylic-3"), settings=["kerf_mm=0.1"])
    assert by_name.files == by_object.files and by_name.stem == "standard-4x4"
    with pytest.raises(InputError, match="no option 'colour'"):
        fabkiri.cut(square, colour="red")
    with pytest.raises(InputError, match="WxH"):
        fabkiri.cut(square, sheet="A4")
    with pytest.raises(InputError, match="scale"):
        fabkiri.cut(square, scale=-1)


def test_design_reports_progress_and_writes_its_preview(tmp_path):
    heard = []
    result = fabkiri.design("circle", tiles="5x5", rigid=True, progress=lambda *a: heard.append(a))
    assert heard[0][:2] == ("design", 0.0) and heard[-1][:2] == ("design", 1.0)
    assert isinstance(result, fabkiri.DesignResult) and result.valid
    _check_result(result, tmp_path, ["circle-5x5-rigid.json", "circle-5x5-rigid.png"])
    assert fabkiri.load(tmp_path / "circle-5x5-rigid.json").name == result.pattern.name
    with pytest.raises(InputError, match="no option 'colour'"):
        fabkiri.design("circle", tiles="3x3", colour="red")


def test_deploy_shows_the_path(tmp_path):
    result = fabkiri.deploy(fabkiri.standard("3x3"), steps=8, frames=False)
    _check_result(result, tmp_path, ["energy.csv", "deploy.json"])
    assert "rigid path, 9 frames" in result.summary()


def test_api_names_every_front_door():
    import fabkiri.api as api

    assert {"cut_files", "print_pattern", "deploy_pattern", "load_pattern", "make"} <= set(
        api.__all__
    )
    for name in api.__all__:
        assert getattr(api, name).__name__ == name


@pytest.mark.slow
def test_make_reports_each_step_with_its_share(shared_designs):
    # shared_designs: the second make (the one-argument callback) deploys and designs nothing again
    heard = []
    result = fabkiri.make(
        "circle", 120, material="acrylic-3", tiles="6x6", progress=lambda *a: heard.append(a)
    )
    assert result.ok and result.tiles.tiles == (6, 6)
    assert [s for s, f, _ in heard if f == 1.0] == ["report"]
    ends = [(s, f) for s, f, text in heard if text.startswith(f"make: {s} ok")]
    assert ends == [("design", 0.25), ("cut", 0.5), ("deploy", 0.75), ("report", 1.0)]
    assert "array(" not in repr(result) and result._repr_png_().startswith(PNG)
    plain: list[str] = []  # a one-argument callback hears make's lines as they are
    again = fabkiri.make("circle", 120, material="acrylic-3", tiles="6x6", progress=plain.append)
    assert again.ok and plain[0] == heard[0][2] and len(plain) == len(heard)
    assert [t.split(" in ")[0] for t in plain] == [t.split(" in ")[0] for _, _, t in heard]


@pytest.mark.parametrize("size", [-3.0, 0.0, float("nan")])
def test_design_refuses_a_size_that_is_not_a_length(size):
    """The CLI checks --size; a library caller is refused by the target itself, before any design."""
    with pytest.raises(InputError, match="size must be a length"):
        fabkiri.design("circle", tiles="8x8", size=size)


def test_design_progress_hears_the_share_of_a_stage(monkeypatch):
    from fabkiri.api import front
    from fabkiri.design.core import stages

    real = front.design_by_kind

    def with_steps(request, notify):
        for k in range(3):
            stages.step("continuation", k, 2)
        return real(request, notify=notify)

    monkeypatch.setattr(front, "design_by_kind", with_steps)
    heard = []
    fabkiri.design("circle", tiles="3x3", rigid=True, progress=lambda *a: heard.append(a))
    shares = [a for a in heard if a[0] == "continuation"]
    assert shares == [
        ("continuation", 0.0, "continuation 0%"),
        ("continuation", 0.5, "continuation 50%"),
        ("continuation", 1.0, "continuation 100%"),
    ]
    stages.step("continuation", 1, 2)  # after the call nobody listens
    assert len([a for a in heard if a[0] == "continuation"]) == 3
