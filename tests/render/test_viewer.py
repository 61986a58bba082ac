"""The deployment viewer (render/viewer.py, viewer.js), ``fabkiri view`` and the report's copy.

The browser tests drive Debian's chromium through Playwright's Python package (no browser download:
``executable_path``) and read back what the page draws: each tile is a ``<polygon data-tile>`` whose
points must be the ``deploy`` front door's frame within 0.01 mm. Every request that is not ``file://``
is aborted and recorded; there must be none. With ``FABKIRI_VIEWER_SHOTS=DIR`` the tests also save
1400 px wide screenshots there.
"""

from __future__ import annotations

import json
import os
import re
import shutil
import subprocess
import sys
import urllib.request
from pathlib import Path

import numpy as np
import pytest
from fabkiri.api.deploy import deploy_pattern
from fabkiri.exchange.pattern_json import read_pattern, write_pattern
from fabkiri.mechanics.contract import with_contracted_states
from fabkiri.pattern.kinds.periodic.sheet import seam_of, standard_tube, tube_tiles
from fabkiri.pattern.kinds.tessellation import tessellation
from fabkiri.render.viewer import SCRIPT, viewer_data, viewer_page

from ..conftest import TEMPLATES

DATA = Path(__file__).parents[1] / "data"

CHROMIUM = next(
    (p for p in ("/usr/bin/chromium", shutil.which("chromium") or "") if p and Path(p).exists()),
    None,
)
try:
    from playwright.sync_api import sync_playwright
except ImportError:  # the test extra brings it
    sync_playwright = None  # type: ignore[assignment]
FLAGS = [
    "--no-sandbox",
    "--disable-gpu",
    "--disable-background-networking",
    "--disable-component-update",
    "--no-first-run",
    "--disable-sync",
]
SHOTS = os.environ.get("FABKIRI_VIEWER_SHOTS")
TOL_MM = 0.01
_skip = pytest.mark.skipif(
    CHROMIUM is None or sync_playwright is None,
    reason="needs chromium (Debian package 'chromium') and playwright (pip, the test extra)",
)


def needs_browser(test):
    """A browser test: skipped without chromium or playwright; slow (a page and a browser each). The
    browser tests share one xdist_group, so --dist loadgroup makes the module's pages and browser on one
    worker, not on both."""
    return pytest.mark.xdist_group("viewer-pages")(pytest.mark.slow(_skip(test)))


def _patterns() -> dict:
    """A quad design (with its target), a kagome design and a quad tube."""
    return {
        "quad": read_pattern(TEMPLATES / "patterns" / "circle-8x8-rigid.json"),
        "kagome": read_pattern(
            DATA / "kagome-heart-6x11.json"
        ),  # a kagome design (design --lattice kagome)
        "tube": with_contracted_states(standard_tube(4, 8, tile_size=10.0, name="tube 4x8")),
    }


@pytest.fixture(scope="module")
def pages(tmp_path_factory):
    """``fabkiri view`` of each pattern (and the quad's report): ``{kind: (page, pattern)}``."""
    from fabkiri.cli.main import main

    d = tmp_path_factory.mktemp("viewer")
    out = {}
    for kind, pattern in _patterns().items():
        src = d / f"{kind}.json"
        write_pattern(pattern, src)
        assert main(["view", str(src), "-o", str(d / f"{kind}.html")]) == 0
        out[kind] = (d / f"{kind}.html", pattern)
    quad = str(out["quad"][0].with_suffix(".json"))
    assert main(["cut", quad, "--width", "300", "-o", str(d / "cut")]) == 0
    assert main(["report", quad, "--cut", str(d / "cut"), "-o", str(d / "r.html")]) == 0
    out["report"] = (d / "r.html", out["quad"][1])
    assert main(["view", quad, "--cut", str(d / "cut"), "-o", str(d / "cut.html")]) == 0
    out["cut"] = (d / "cut.html", out["quad"][1])
    return out


@pytest.fixture(scope="module")
def browser():
    if CHROMIUM is None or sync_playwright is None:
        pytest.skip("needs chromium and playwright")
    with sync_playwright() as pw:
        b = pw.chromium.launch(executable_path=CHROMIUM, headless=True, args=FLAGS)
        yield b
        b.close()


class Opened:
    """A page open in chromium, with its console errors and every non-file request (aborted)."""

    def __init__(self, browser, path: Path):
        self.errors: list[str] = []
        self.requests: list[str] = []
        self.page = browser.new_page(viewport={"width": 1400, "height": 1000})
        self.page.on("console", lambda m: self.errors.append(m.text) if m.type == "error" else None)
        self.page.on("pageerror", lambda e: self.errors.append(str(e)))
        self.page.route("**/*", self._route)
        self.page.goto(path.as_uri())
        self.page.wait_for_function("window.fabkiriViewer !== undefined")

    def _route(self, route) -> None:
        if route.request.url.startswith("file://"):
            route.continue_()
        else:
            self.requests.append(route.request.url)
            route.abort()

    def slide(self, t: float) -> int:
        """Move the slider to ``t`` as a user's drag does (its value, then an input event); the frame."""
        self.page.eval_on_selector(
            "#fkv-t", "(e, t) => { e.value = String(t); e.dispatchEvent(new Event('input')); }", t
        )
        return int(self.page.get_attribute("#fabkiri-viewer", "data-frame"))

    def drawn(self) -> np.ndarray:
        """The tile corners as drawn: every ``polygon[data-tile]``'s points, in tile order."""
        got = self.page.eval_on_selector_all(
            "#fkv-tiles polygon[data-tile]",
            "ps => ps.map(p => [Number(p.dataset.tile), p.getAttribute('points')])",
        )
        got.sort(key=lambda x: x[0])
        assert [i for i, _ in got] == list(range(len(got)))
        return np.array([[[float(v) for v in c.split(",")] for c in s.split()] for _, s in got])

    def shot(self, name: str) -> None:
        if SHOTS:
            Path(SHOTS).mkdir(parents=True, exist_ok=True)
            self.page.screenshot(path=str(Path(SHOTS) / f"{name}.png"), full_page=True)

    def clean(self) -> None:
        assert self.errors == [], self.errors
        assert self.requests == [], self.requests


@needs_browser
@pytest.mark.parametrize("kind", ["quad", "kagome", "tube", "report"])
def test_slider_draws_the_deploy_front_doors_frames(pages, browser, kind):
    page, pattern = pages[kind]
    path = deploy_pattern(pattern, 40, frames=False).path  # the front door `fabkiri deploy` calls
    o = Opened(browser, page)
    drawn = {}
    for t in (0.0, 0.5, 1.0):
        f = o.slide(t)
        assert path.t[f] == pytest.approx(t, abs=1e-12)
        drawn[t] = o.drawn()
        assert drawn[t].shape == path.corners[f].shape
        assert np.abs(drawn[t] - path.corners[f]).max() <= TOL_MM
        o.shot(f"{kind}-t{t:.1f}")
    # the slider moves the tiles (a page that ignored it would pass the deployed-frame check only)
    assert np.abs(drawn[0.0] - drawn[0.5]).max() > 1.0
    assert np.abs(drawn[1.0] - drawn[0.5]).max() > 1.0
    o.clean()


@needs_browser
@pytest.mark.parametrize("kind", ["quad", "kagome", "tube", "report"])
def test_hovering_a_tile_shows_its_number(pages, browser, kind):
    page, pattern = pages[kind]
    o = Opened(browser, page)
    tip = o.page.locator("#fkv-tip")
    assert not tip.is_visible()
    for tile in (len(pattern.tiles) // 2 + 1, 3):
        o.page.hover(f'#fkv-tiles polygon[data-tile="{tile}"]')
        assert tip.is_visible()
        text = tip.inner_text()
        assert text.splitlines()[0] == f"tile {tile}", text
        assert "thinnest width" in text
    o.shot(f"{kind}-hover")
    o.clean()


@needs_browser
@pytest.mark.parametrize("kind", ["cut", "report"])
def test_hinges_name_their_tiles_and_assembly_piece(pages, browser, kind):
    page, pattern = pages[kind]
    pieces = json.loads((page.parent / "cut" / "manifest.json").read_text())["assembly_pieces"]
    o = Opened(browser, page)
    o.slide(0.5)
    piece = pieces[len(pieces) // 2]
    h = piece["hinge"]
    a, b = (int(x) for x in pattern.topology.hinge_tiles[h])
    o.page.hover(f'circle[data-hinge="{h}"]')
    lines = o.page.inner_text("#fkv-tip").splitlines()
    assert lines[0] == f"hinge {h}" and lines[1] == f"joins tiles {a} and {b}"
    assert f"assembly piece {piece['piece']}" in lines[2]
    # the tile's pieces too
    o.page.hover(f'#fkv-tiles polygon[data-tile="{a}"]')
    assert str(piece["piece"]) in o.page.inner_text("#fkv-tip")
    o.clean()


@needs_browser
def test_cut_sheets_are_shown_at_true_scale(pages, browser):
    o = Opened(browser, pages["cut"][0])
    o.page.select_option("#fkv-view", "sheet")
    img = o.page.locator("#fkv-sheet img")
    assert img.count() == 1
    w_mm = float(o.page.evaluate("document.querySelector('#fkv-sheet img').style.width")[:-2])
    assert w_mm >= 300.0  # the sheet holds the 300 mm wide pattern
    px = img.bounding_box()["width"]
    assert px == pytest.approx(w_mm * 96 / 25.4, rel=1e-3)  # CSS millimetres: 96 px per inch
    assert o.page.evaluate("document.querySelector('#fkv-sheet img').naturalWidth") > 0
    o.shot("cut-sheet")
    o.clean()


@needs_browser
def test_target_and_worst_fit_are_drawn_on_the_deployed_state_only(pages, browser):
    o = Opened(browser, pages["quad"][0])
    o.slide(0.5)
    assert o.page.locator("#fkv-target").count() == 1 and o.page.locator("#fkv-worst").count() == 1
    pts = o.page.get_attribute("#fkv-target", "points")
    assert len(pts.split()) >= 3
    o.slide(0.0)
    assert o.page.locator("#fkv-target").count() == 0
    o.page.uncheck("#fkv-overlay")
    o.slide(0.5)
    assert o.page.locator("#fkv-target").count() == 0
    o.clean()


@needs_browser
def test_colour_switch_and_legend(pages, browser):
    o = Opened(browser, pages["quad"][0])
    o.slide(0.5)
    fills = o.page.eval_on_selector_all(
        "#fkv-tiles polygon", "ps => ps.map(p => p.getAttribute('fill'))"
    )
    assert len(set(fills)) == 2  # turn angle, rigid checkerboard: two colours, one per turn sense
    assert "turn angle" in o.page.inner_text("#fkv-legend")
    o.page.select_option("#fkv-colour", "energy")
    assert o.page.get_attribute("#fabkiri-viewer", "data-colour") == "energy"
    assert "spring energy" in o.page.inner_text("#fkv-legend")
    o.page.select_option("#fkv-view", "sheet")
    width = o.page.get_attribute("#fkv-sheet", "width")
    assert width.endswith("mm") and float(width[:-2]) > 0  # true scale: sized in millimetres
    assert "mm" in o.page.text_content("#fkv-sheet text")  # the scale bar
    o.shot("quad-sheet")
    o.clean()


@needs_browser
def test_play_advances_and_pause_stops(pages, browser):
    o = Opened(browser, pages["kagome"][0])
    o.slide(0.0)
    o.page.click("#fkv-play")
    o.page.wait_for_function("fabkiriViewer.frame() >= 3")
    o.page.click("#fkv-play")
    f = o.page.evaluate("fabkiriViewer.frame()")
    o.page.wait_for_timeout(300)
    assert o.page.evaluate("fabkiriViewer.frame()") == f
    o.page.focus("#fkv-t")  # arrow keys step one computed frame
    o.page.keyboard.press("ArrowRight")
    assert o.page.evaluate("fabkiriViewer.frame()") == f + 1
    o.page.keyboard.press("ArrowLeft")
    o.page.keyboard.press("ArrowLeft")
    assert o.page.evaluate("fabkiriViewer.frame()") == f - 1
    o.clean()


@needs_browser
def test_tube_turns_in_3d(pages, browser):
    page, pattern = pages["tube"]
    o = Opened(browser, page)
    o.page.select_option("#fkv-view", "3d")
    polys = o.page.locator("polygon[data-tile3d]")
    shown = polys.evaluate_all("ps => ps.map(p => Number(p.dataset.tile3d))")
    assert sorted(shown) == sorted(int(i) for i in tube_tiles(pattern, seam_of(pattern)))
    before = o.page.get_attribute('polygon[data-tile3d="0"]', "points")
    box = o.page.locator("svg.fkv-main").bounding_box()
    x, y = box["x"] + box["width"] / 2, box["y"] + box["height"] / 2
    o.page.mouse.move(x, y)
    o.page.mouse.down()
    o.page.mouse.move(x + 120, y + 40, steps=5)
    o.page.mouse.up()
    assert o.page.get_attribute('polygon[data-tile3d="0"]', "points") != before
    o.shot("tube-3d")
    o.clean()


def test_page_is_self_contained_and_its_data_cannot_end_the_script(tmp_path):
    pattern = with_contracted_states(
        tessellation("quad").standard(3, 3, tile_size=10.0, name="a </script><b>name")
    )
    path = deploy_pattern(pattern, 8, frames=False).path
    page = viewer_page(viewer_data(pattern, path), "t")
    assert not re.search(r'(src|href)="(https?:)?//', page)
    script = SCRIPT.read_text()
    for network in ("fetch(", "XMLHttpRequest", "import(", "WebSocket", "<link"):
        assert network not in script and network not in page
    blob = re.search(r'id="fabkiri-viewer-data">(.*?)</script>', page, re.S)
    assert blob is not None
    data = json.loads(blob.group(1))
    assert data["name"] == "a </script><b>name"
    assert np.abs(np.array(data["corners"]) - path.corners).max() <= 1e-4


def test_view_refuses_bad_requests(run_cli, tmp_path):
    src = TEMPLATES / "patterns" / "standard-8x8.json"
    code, _, err = run_cli("view", src, "-o", tmp_path / "v.txt")
    assert code == 2 and ".html" in err and len(err.strip().splitlines()) == 1
    code, _, err = run_cli("view", src)
    assert code == 2 and "--port" in err
    code, _, err = run_cli("view", tmp_path / "missing.json", "-o", tmp_path / "v.html")
    assert code == 2
    assert list(tmp_path.iterdir()) == []


@pytest.mark.slow
def test_view_serves_the_page_on_localhost(tmp_path):
    src = TEMPLATES / "patterns" / "standard-8x8.json"
    env = {**os.environ, "PYTHONPATH": str(Path(__file__).resolve().parents[2])}
    proc = subprocess.Popen(
        [sys.executable, "-m", "fabkiri.cli.main", "view", str(src), "--port", "0", "--steps", "8"],
        stderr=subprocess.PIPE,
        text=True,
        env=env,
    )
    try:
        assert proc.stderr is not None
        url = None
        for line in proc.stderr:
            m = re.search(r"serving (http://127\.0\.0\.1:\d+/)", line)
            if m:
                url = m.group(1)
                break
        assert url, "no address printed"
        with urllib.request.urlopen(url, timeout=30) as r:
            body = r.read().decode()
        assert 'id="fabkiri-viewer-data"' in body and "fabkiriViewer" in body
    finally:
        proc.terminate()
        proc.wait(timeout=30)
