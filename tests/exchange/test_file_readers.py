"""Every file fabkiri writes, read by the tools a maker opens it with: DXF with ezdxf (as written and
re-saved binary, the binary copy verified too) and LibreCAD, SVG with Inkscape, 3MF with lib3mf's strict
reader. A tool that is not installed skips its test with the reason."""

from __future__ import annotations

import io
import shutil
import subprocess
from pathlib import Path

import ezdxf
import numpy as np
import pytest
from ezdxf import bbox, recover
from fabkiri.exchange.file_formats import read_cut_file
from fabkiri.exchange.pattern_json import write_pattern
from fabkiri.mechanics.contract import with_contracted_states
from fabkiri.pattern import standard_pattern
from fabkiri.pattern.kinds.kagome.lattice import standard_kagome
from fabkiri.verify import verify_layout

# the module fixtures (cut folders of every hinge kind) are made on one worker, not on both
pytestmark = pytest.mark.xdist_group("file-readers")

HINGES = ("tape", "separate", "ligament")


def _cli(*argv) -> None:
    from fabkiri.cli.main import main

    assert main([str(a) for a in argv]) == 0, argv


@pytest.fixture(scope="module")
def std(tmp_path_factory):
    root = tmp_path_factory.mktemp("readers")
    src = root / "std.json"
    write_pattern(with_contracted_states(standard_pattern(3, 3, tile_size=10.0)), src)
    return src


@pytest.fixture(scope="module")
def cut_dirs(std):
    """`fabkiri cut` of a standard 3x3 pattern, one folder per hinge kind."""
    out = {}
    for h in HINGES:
        d = std.parent / f"cut-{h}"
        _cli("cut", std, "--hinge", h, "--material", "pp-0.5", "--formats", "dxf,svg", "-o", d)
        out[h] = d
    return out


@pytest.fixture(scope="module")
def written_dirs(std, cut_dirs):
    """Folders of every kind of laser file fabkiri writes: cut sheets (each hinge kind), a tube's flat
    sheet, the laser coupon, the strips' laser files (print --marks)."""
    root = std.parent
    _cli("new", "--tiles", "4x6", "--tube", "-o", root / "tube.json")
    _cli("cut", root / "tube.json", "--hinge", "tape", "--material", "pp-0.5", "-o", root / "tube")
    _cli("coupon", "--material", "pp-0.5", "-o", root / "coupon")
    _cli("print", std, "--style", "strips", "--marks", "-o", root / "marks")
    return [*cut_dirs.values(), root / "tube", root / "coupon", root / "marks"]


@pytest.fixture(scope="module")
def written_dxfs(written_dirs):
    files = [f for d in written_dirs for f in sorted(d.rglob("*.dxf"))]
    assert len(files) >= 5, files
    return files


def _binary_copy(src: Path, dst_dir: Path) -> Path:
    """``src`` re-saved by ezdxf as binary DXF into ``dst_dir``, with the manifest beside it."""
    dst_dir.mkdir(parents=True, exist_ok=True)
    dst = dst_dir / src.name
    ezdxf.readfile(src).saveas(dst, fmt="bin")
    assert dst.read_bytes().startswith(b"AutoCAD Binary DXF")
    if (src.parent / "manifest.json").exists():
        shutil.copy(src.parent / "manifest.json", dst_dir / "manifest.json")
    return dst


def test_binary_dxf_re_save_is_read_and_verified(std, cut_dirs, tmp_path):
    """A binary re-save of a cut sheet reads as the ASCII file does, and passes the verifier."""
    from fabkiri.exchange.pattern_json import read_pattern

    pattern = read_pattern(std)
    src = next(cut_dirs["tape"].glob("*.dxf"))
    dst = _binary_copy(src, tmp_path / "bin")
    a, b = read_cut_file(src), read_cut_file(dst)
    assert len(a.polylines) == len(b.polylines) > 0
    assert np.abs(np.concatenate(a.polylines) - np.concatenate(b.polylines)).max() < 1e-9
    rep = verify_layout(pattern, dst)
    assert rep.ok, rep.to_text()


@pytest.mark.slow  # every DXF kind; the quick loop re-saves and verifies one cut sheet above
def test_every_written_dxf_reads_in_ascii_and_binary(std, cut_dirs, written_dxfs, tmp_path):
    from fabkiri.exchange.pattern_json import read_pattern

    pattern = read_pattern(std)
    for k, f in enumerate(written_dxfs):
        doc, auditor = recover.readfile(f)
        assert not auditor.has_errors, (f, [e.message for e in auditor.errors][:3])
        assert doc.header["$INSUNITS"] == 4
        dst = _binary_copy(f, tmp_path / str(k))
        again = ezdxf.readfile(dst)
        assert len(again.modelspace()) == len(doc.modelspace()), f
    for h, d in cut_dirs.items():
        for f in d.glob("*.dxf"):
            rep = verify_layout(pattern, _binary_copy(f, tmp_path / f"verify-{h}"))
            assert rep.ok, (h, rep.to_text())


def _header(data: bytes):
    return ezdxf.read(io.StringIO(data.decode("ascii")))


def test_dxf_header_is_set_from_the_drawing(std, cut_dirs):
    """$EXTMIN/$EXTMAX are the drawing's extents, $LIMMIN/$LIMMAX hold the sheet and the drawing, the
    paper-space viewport scale is not 0 (LibreCAD's dxf2pdf prints a blank page), and NOTES does not
    plot (CAM tools make no toolpath of the sheet frame)."""
    for h, d in cut_dirs.items():
        for f in d.glob("*.dxf"):
            doc = _header(f.read_bytes())
            ext = bbox.extents(doc.modelspace())
            lo, hi = doc.header["$EXTMIN"], doc.header["$EXTMAX"]
            assert np.allclose(lo[:2], (ext.extmin.x, ext.extmin.y), atol=1e-6), (h, lo)
            assert np.allclose(hi[:2], (ext.extmax.x, ext.extmax.y), atol=1e-6), (h, hi)
            lmin, lmax = doc.header["$LIMMIN"], doc.header["$LIMMAX"]
            assert lmin[0] <= lo[0] and lmin[1] <= lo[1] and lmax[0] >= hi[0] and lmax[1] >= hi[1]
            assert doc.header["$PSVPSCALE"] != 0
            plot = {layer.dxf.name: layer.dxf.get("plot", 1) for layer in doc.layers}
            assert plot["NOTES"] == 0 and plot["CUT"] != 0 and plot["ENGRAVE"] != 0, plot


def _dark_pixels(pdf: Path) -> int:
    png = pdf.with_suffix(".png")
    subprocess.run(
        ["gs", "-q", "-dSAFER", "-dBATCH", "-dNOPAUSE", "-sDEVICE=pnggray", "-r30"]
        + [f"-sOutputFile={png}", str(pdf)],
        check=True,
        timeout=120,
    )
    from PIL import Image

    return int((np.asarray(Image.open(png)) < 128).sum())


@pytest.mark.slow  # starts LibreCAD (a few seconds)
@pytest.mark.skipif(shutil.which("librecad") is None, reason="LibreCAD is not installed")
@pytest.mark.skipif(
    shutil.which("gs") is None, reason="Ghostscript (to rasterise the PDF) is absent"
)
def test_librecad_dxf2pdf_prints_the_sheet(cut_dirs, tmp_path):
    src = next(cut_dirs["tape"].glob("*.dxf"))
    shutil.copy(src, tmp_path / src.name)
    run = subprocess.run(
        ["librecad", "dxf2pdf", src.name],
        cwd=tmp_path,
        capture_output=True,
        text=True,
        timeout=300,
        env={**__import__("os").environ, "QT_QPA_PLATFORM": "offscreen"},
    )
    pdf = tmp_path / (src.stem + ".pdf")
    if run.returncode != 0 or not pdf.exists():
        pytest.skip(f"librecad could not print here: {run.stderr[-200:]}")
    assert _dark_pixels(pdf) > 50  # the tiles and labels are on the page


@pytest.mark.slow  # one Inkscape run over every SVG (several seconds)
@pytest.mark.skipif(shutil.which("inkscape") is None, reason="Inkscape is not installed")
def test_every_written_svg_opens_in_inkscape_at_true_size(written_dirs, tmp_path):
    """Inkscape renders every SVG fabkiri writes (cut sheets, laser coupon, the strips' laser files) at
    1 px per mm: the page is the sheet in mm, not blank."""
    import re

    from PIL import Image

    svgs = sorted(f for d in written_dirs for f in d.rglob("*.svg"))
    assert len(svgs) >= 5, svgs
    for k, f in enumerate(svgs):
        shutil.copy(f, tmp_path / f"{k}.svg")
    names = [str(tmp_path / f"{k}.svg") for k in range(len(svgs))]
    run = subprocess.run(
        ["inkscape", *names, "--export-type=png", "--export-dpi=25.4", "--export-area-page"],
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert run.returncode == 0, run.stderr[-500:]
    for k, f in enumerate(svgs):
        text = f.read_text()
        w = float(re.search(r'width="([\d.]+)mm"', text).group(1))
        h = float(re.search(r'height="([\d.]+)mm"', text).group(1))
        img = np.asarray(Image.open(tmp_path / f"{k}.png").convert("LA"))
        assert abs(img.shape[1] - w) <= 1 and abs(img.shape[0] - h) <= 1, (f.name, img.shape, w, h)
        assert (img[..., 1] > 0).sum() > 50, f.name  # strokes drawn


# ------------------------------------------------------------------ 3MF


def lib3mf_problems(data: bytes) -> list[str]:
    """What lib3mf's strict reader says of a 3MF: its exception, or every warning it records."""
    lib3mf = pytest.importorskip("lib3mf", reason="lib3mf (the test extra) is not installed")
    model = lib3mf.get_wrapper().CreateModel()
    reader = model.QueryReader("3mf")
    reader.SetStrictModeActive(True)
    try:
        reader.ReadFromBuffer(bytearray(data))
    except Exception as exc:  # lib3mf raises its own exception type, from its wrapper module
        return [f"{type(exc).__name__}: {exc}"]
    return [str(reader.GetWarning(i)) for i in range(reader.GetWarningCount())]


def test_3mf_writers_pass_the_strict_reader():
    """The project 3MF (one object, volumes, slicer metadata) and the plain one (objects) hold only
    core-spec attributes in the core namespace: lib3mf's strict reader has nothing to say."""
    from fabkiri.fabricate.print.printers import load_printer
    from fabkiri.fabricate.print.threemf import LayerChange, Part, objects_3mf, project_3mf

    v = np.array([[0, 0, 0], [10, 0, 0], [0, 10, 0], [0, 0, 10]], float)
    f = np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])
    for preset in ("prusa-mk4", "prusa-xl-2t"):
        pr = load_printer(preset)
        parts = [Part("tile", pr.tile_material, v, f), Part("strip", pr.strip_material, v + 20, f)]
        data = project_3mf("p", parts, pr, [LayerChange(0.8, "colour-change", pr.tile_material)])
        assert lib3mf_problems(data) == [], preset
    assert lib3mf_problems(objects_3mf({"a": (v, f), "b": (v + 20, f)})) == []


@pytest.mark.slow  # prints five jobs and a coupon; the quick loop reads both writers above
def test_every_written_3mf_passes_the_strict_reader(std, tmp_path):
    """Every 3MF `print` and `coupon` write: quad tiles-and-strips (one and two extruders), strips,
    pinned, kagome tiles-and-strips and the printer coupon."""
    from fabkiri.exchange import pattern_json as io

    pinned = tmp_path / "sq23.json"
    write_pattern(with_contracted_states(standard_pattern(2, 3, tile_size=12.0)), pinned)
    kagome = tmp_path / "k75.json"
    io.write_pattern(with_contracted_states(standard_kagome(7, 5, tile_size=10.0)), kagome)
    runs = {
        "ts-1": (std, []),
        "ts-2t": (std, ["--printer", "prusa-xl-2t"]),
        "strips": (std, ["--style", "strips"]),
        "pinned": (pinned, ["--style", "pinned"]),
        "kagome": (kagome, ["--scale", "auto"]),
    }
    for name, (src, args) in runs.items():
        _cli("print", src, *args, "-o", tmp_path / name)
    _cli("coupon", "--printer", "prusa-mk4", "-o", tmp_path / "coupon")
    files = sorted(tmp_path.rglob("*.3mf"))
    assert {f.parent.name for f in files} == {*runs, "coupon"}
    bad = {str(f.relative_to(tmp_path)): p for f in files if (p := lib3mf_problems(f.read_bytes()))}
    assert not bad, bad
