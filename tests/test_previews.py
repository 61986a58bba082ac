"""Pictures a person reads: SVG strokes that render, --no-notes, the GIF and the energy plot."""

from __future__ import annotations

import shutil
import subprocess

import ezdxf
import numpy as np
import pytest
from PIL import Image

from .conftest import TEMPLATES

STD = TEMPLATES / "patterns" / "standard-8x8.json"


def test_no_notes_leaves_out_frame_and_caption(run_cli, tmp_path):
    code, _, err = run_cli("cut", STD, "--no-notes", "-o", tmp_path / "a")
    assert code == 0 and "verifier passed" in err
    code, _, _ = run_cli("cut", STD, "-o", tmp_path / "b")
    notes = {}
    for k in ("a", "b"):
        doc = ezdxf.readfile(tmp_path / k / "standard-8x8.dxf")
        notes[k] = len(doc.modelspace().query("*[layer=='NOTES']"))
        svg = (tmp_path / k / "standard-8x8.svg").read_text()
        assert ('inkscape:label="NOTES" stroke="#00FF00" stroke-linejoin="round" stroke-width="0.1" />' in svg) \
            == (k == "a")  # an empty NOTES group
    assert notes["a"] == 0 and notes["b"] > 0


@pytest.mark.skipif(shutil.which("inkscape") is None, reason="inkscape is not installed")
def test_svg_renders_visible_in_inkscape(run_cli, tmp_path):
    code, _, _ = run_cli("cut", STD, "--formats", "svg", "-o", tmp_path)
    png = tmp_path / "r.png"
    subprocess.run(["inkscape", str(tmp_path / "standard-8x8.svg"), "--export-type=png", f"--export-filename={png}",
                    "--export-background=white", "--export-background-opacity=1"], check=True,
                   capture_output=True, timeout=300)
    a = np.asarray(Image.open(png).convert("RGB")).astype(int)
    dark = a.min(axis=2) < 230
    assert dark.mean() > 1e-3  # lines drawn, not an all-white page
    red = a[..., 0] - np.maximum(a[..., 1], a[..., 2]) > 40  # reddish, antialiased at 0.38 px
    assert red.sum() > 1000  # the CUT colour survives (laser convention: red cuts)
