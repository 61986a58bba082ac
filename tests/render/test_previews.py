"""Pictures a person reads: SVG strokes that render, --no-notes, the GIF and the energy plot."""

from __future__ import annotations

import shutil
import subprocess

import ezdxf
import numpy as np
import pytest
from PIL import Image

from ..conftest import TEMPLATES

STD = TEMPLATES / "patterns" / "standard-8x8.json"


@pytest.mark.slow
def test_no_notes_leaves_out_frame_and_caption(run_cli, tmp_path):
    code, _, err = run_cli("cut", STD, "--no-notes", "-o", tmp_path / "a")
    assert code == 0 and "verifier passed" in err
    code, _, _ = run_cli("cut", STD, "-o", tmp_path / "b")
    notes = {}
    for k in ("a", "b"):
        doc = ezdxf.readfile(tmp_path / k / "standard-8x8.dxf")
        notes[k] = len(doc.modelspace().query("*[layer=='NOTES']"))
        svg = (tmp_path / k / "standard-8x8.svg").read_text()
        assert (
            'inkscape:label="NOTES" stroke="#00FF00" stroke-linejoin="round" stroke-width="0.1" />'
            in svg
        ) == (k == "a")  # an empty NOTES group
    assert notes["a"] == 0 and notes["b"] > 0


@pytest.mark.slow
@pytest.mark.skipif(shutil.which("inkscape") is None, reason="inkscape is not installed")
def test_svg_renders_visible_in_inkscape(run_cli, tmp_path):
    code, _, _ = run_cli("cut", STD, "--formats", "svg", "-o", tmp_path)
    png = tmp_path / "r.png"
    subprocess.run(
        [
            "inkscape",
            str(tmp_path / "standard-8x8.svg"),
            "--export-type=png",
            f"--export-filename={png}",
            "--export-background=white",
            "--export-background-opacity=1",
        ],
        check=True,
        capture_output=True,
        timeout=300,
    )
    a = np.asarray(Image.open(png).convert("RGB")).astype(int)
    dark = a.min(axis=2) < 230
    assert dark.mean() > 1e-3  # lines drawn, not an all-white page
    red = a[..., 0] - np.maximum(a[..., 1], a[..., 2]) > 40  # reddish, antialiased at 0.38 px
    assert red.sum() > 1000  # the CUT colour survives (laser convention: red cuts)


def _path(name, **kw):
    from fabkiri.exchange.pattern_json import read_pattern
    from fabkiri.mechanics.deploy import deployment_path

    shipped = TEMPLATES / "patterns" / f"{name}.json"  # else kept as test data (tests/data)
    src = shipped if shipped.exists() else TEMPLATES.parent / "tests" / "data" / f"{name}.json"
    return deployment_path(read_pattern(src), 12, **kw)


def test_gif_is_large_and_greys_out_energy_below_noise():
    from io import BytesIO

    from fabkiri.render.deployment import deployment_gif

    path = _path("circle-8x8-rigid")
    assert path.tile_energy.max() < 1e-12
    im = Image.open(BytesIO(deployment_gif(path, color="energy", max_frames=5)))
    assert min(im.size) >= 800 and im.n_frames == 5
    im.seek(2)
    a = np.asarray(im.convert("RGB")).astype(int)
    # no energy colour map on noise: every pixel is grey (R = G = B)
    assert (a.max(axis=2) - a.min(axis=2)).max() <= 6


def test_energy_zoom_axes_have_no_offset():
    from fabkiri.render.deployment import _energy_axes, _pyplot

    plt = _pyplot()
    path = _path("heart-8x8")
    fig, ax = plt.subplots()
    a, b = path.elastic_segments[-1]
    _energy_axes(ax, path, b - 1e-8, b, anchor=1.0)
    fig.canvas.draw()
    assert "+" not in ax.xaxis.get_offset_text().get_text()
    labels = [t.get_text() for t in ax.get_xticklabels()]
    assert all(len(s) <= 6 for s in labels), labels
    plt.close(fig)
