"""``fabkiri report``: a self-contained page with every section, loaded clean by headless Chromium."""

from __future__ import annotations

import re
import shutil
import subprocess

import numpy as np
import pytest
from fabkiri.render.report import SECTIONS
from PIL import Image

from ..conftest import TEMPLATES

PATTERN = TEMPLATES / "patterns" / "circle-8x8-rigid.json"
CHROMIUM = shutil.which("chromium") or shutil.which("chromium-browser")
FLAGS = [
    "--headless",
    "--no-sandbox",
    "--disable-gpu",
    "--disable-quic",
    "--no-first-run",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
]


@pytest.fixture(scope="module")
def report(tmp_path_factory):
    from fabkiri.cli.main import main

    d = tmp_path_factory.mktemp("report")
    assert main(["cut", str(PATTERN), "--width", "200", "-o", str(d / "cut")]) == 0
    assert (
        main(
            [
                "deploy",
                str(PATTERN),
                "--steps",
                "8",
                "--plot",
                "--gif",
                "--gif-frames",
                "5",
                "--no-frames",
                "-o",
                str(d / "deploy"),
            ]
        )
        == 0
    )
    assert main(["tolerance", str(PATTERN), "--n", "50", "-o", str(d / "tol")]) == 0
    out = d / "report.html"
    assert (
        main(
            [
                "report",
                str(PATTERN),
                "--cut",
                str(d / "cut"),
                "--deploy",
                str(d / "deploy"),
                "--tolerance",
                str(d / "tol"),
                "-o",
                str(out),
            ]
        )
        == 0
    )
    return out


@pytest.mark.xdist_group("render-report")  # one worker makes the module's report
def test_every_section_is_there_and_self_contained(report):
    page = report.read_text()
    for s in SECTIONS:
        assert f'<section id="{s}">' in page, s
    assert not re.search(r'(src|href)="(https?:)?//', page)  # nothing fetched from the network
    srcs = re.findall(r'<img[^>]* src="([^"]+)"', page)
    assert srcs and all(s.startswith("data:image/") for s in srcs)
    assert (
        "data:image/gif;base64," in page and "data:image/svg+xml;base64," in page
    )  # animation, cut sheet
    # what was not given says so
    assert "not provided: run fabkiri print" in page
    # fabricability is computed as `fabkiri info` computes it (it used to say "not computed" here)
    from fabkiri.exchange.pattern_json import read_pattern
    from fabkiri.fabricate.fabricability import summary

    fab = page.split('<section id="fabricability">')[1].split("</section>")[0]
    s = summary(read_pattern(PATTERN))
    assert f"{s['thinnest_tile_mm']:.3g} mm (tile {s['thinnest_tile']})" in fab
    tape = s["cut"]["acrylic-3"]["tape"]
    assert f"≥ {tape['min_scale']:g}× ({tape['min_width_mm']:g} mm)" in fab


def test_missing_folder_is_bad_input(run_cli, tmp_path):
    code, _, err = run_cli("report", PATTERN, "--cut", tmp_path / "nope", "-o", tmp_path / "r.html")
    assert code == 2 and "no such folder" in err and not (tmp_path / "r.html").exists()


def _chromium(args, tmp_path, timeout=180):
    return subprocess.run(
        [CHROMIUM, *FLAGS, f"--user-data-dir={tmp_path / 'profile'}", *args],
        capture_output=True,
        text=True,
        timeout=timeout,
    )


def _dom(page, tmp_path):
    r = _chromium(["--dump-dom", "--virtual-time-budget=5000", page.as_uri()], tmp_path)
    return r.stdout


@pytest.mark.skipif(
    CHROMIUM is None, reason="chromium is not installed (Debian package 'chromium')"
)
@pytest.mark.slow
@pytest.mark.xdist_group("render-report")  # one worker makes the module's report
def test_chromium_loads_it_clean_and_draws_it(report, tmp_path):
    dom = _dom(report, tmp_path)
    assert 'data-loaded="1"' in dom  # the page's script ran to the end
    m = re.search(r'id="console-errors" data-count="(\d+)"', dom)
    assert m and m.group(1) == "0", dom[-500:]
    shot = tmp_path / "shot.png"
    _chromium(["--window-size=1280,3000", f"--screenshot={shot}", report.as_uri()], tmp_path)
    a = np.asarray(Image.open(shot).convert("RGB"))
    assert a.shape[0] >= 3000 and a.std() > 20  # not a blank page
    assert len(np.unique(a.reshape(-1, 3)[::7], axis=0)) > 200  # pictures, not just text


@pytest.mark.slow
@pytest.mark.skipif(
    CHROMIUM is None, reason="chromium is not installed (Debian package 'chromium')"
)
@pytest.mark.xdist_group("render-report")  # one worker makes the module's report
def test_error_hook_counts_a_script_error(report, tmp_path):
    # the check can fail: the same page with a broken script reports it
    bad = tmp_path / "bad.html"
    bad.write_text(
        report.read_text().replace("</body>", "<script>undefinedFunction();</script></body>")
    )
    m = re.search(r'id="console-errors" data-count="(\d+)"', _dom(bad, tmp_path))
    assert m and int(m.group(1)) >= 1
