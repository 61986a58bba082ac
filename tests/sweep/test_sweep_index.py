"""The sweep's ``index.html``: every status row gets a colour, the filter and the sort work.

(The page used to style ``tr.shape\\ missed``, a selector no ``class="shape missed"`` row matches, and had
no style for "cut failed": the rows were white. The static test reads the CSS and the rows; the browser
test asks chromium for each row's computed colour.)
"""

from __future__ import annotations

import re

import pytest
from fabkiri.sweep.report import STATUS_COLOURS, gallery_html, status_class

from ..render.test_viewer import CHROMIUM, FLAGS, sync_playwright

STATUSES = [
    *STATUS_COLOURS,
    "checks failed",
    None,
]  # the last two: statuses without a colour of their own


def _rows() -> list[dict]:
    return [
        {"id": f"job{i}", "p_tiles": f"{4 + i}x4", "status": s, "hausdorff_rel": 0.01 * i}
        for i, s in enumerate(STATUSES)
    ]


def _styled_classes(page: str) -> dict[str, str]:
    css = re.search(r"<style>(.*?)</style>", page, re.S)
    assert css is not None
    return dict(re.findall(r"tr\.([\w-]+) td \{ background: ([^;]+); \}", css.group(1)))


def test_every_status_row_gets_a_style(tmp_path):
    page = gallery_html(_rows(), tmp_path)
    styled = _styled_classes(page)
    rows = re.findall(r'<tr class="([^"]+)" data-status="([^"]*)"', page)
    assert len(rows) == len(STATUSES)
    for cls, status in rows:
        assert re.fullmatch(r"[\w-]+", cls), cls  # one class, a valid CSS identifier
        assert cls in styled, (status, cls)
    assert status_class("shape missed") == "status-shape-missed"
    assert status_class("cut failed") == "status-cut-failed"
    # statuses that mean different things look different
    assert styled["status-ok"] != styled["status-error"] != styled["status-shape-missed"]
    assert styled["status-cut-failed"] not in (styled["status-ok"], styled["status-error"])


@pytest.mark.slow
@pytest.mark.skipif(
    CHROMIUM is None or sync_playwright is None, reason="needs chromium and playwright"
)
def test_chromium_colours_every_row_and_filters(tmp_path):
    (tmp_path / "index.html").write_text(gallery_html(_rows(), tmp_path))
    assert sync_playwright is not None and CHROMIUM is not None
    with sync_playwright() as pw:
        b = pw.chromium.launch(executable_path=CHROMIUM, headless=True, args=FLAGS)
        page = b.new_page(viewport={"width": 1400, "height": 900})
        errors: list[str] = []
        page.on("pageerror", lambda e: errors.append(str(e)))
        page.goto((tmp_path / "index.html").as_uri())
        colours = page.eval_on_selector_all(
            "#t tbody tr",
            "rs => rs.map(r => [r.dataset.status, getComputedStyle(r.cells[1]).backgroundColor])",
        )
        assert len(colours) == len(STATUSES)
        for status, colour in colours:
            assert colour not in ("rgba(0, 0, 0, 0)", "rgb(255, 255, 255)"), status
        page.select_option("#status", "cut failed")
        shown = page.eval_on_selector_all(
            "#t tbody tr",
            "rs => rs.filter(r => r.offsetParent !== null).map(r => r.dataset.status)",
        )
        assert shown == ["cut failed"]
        page.select_option("#status", "")
        page.fill("#q", "6x4")
        assert page.inner_text("#shown") == "1 shown"
        page.fill("#q", "")
        page.click("#t th:nth-child(2)")  # sort by id, then reversed
        page.click("#t th:nth-child(2)")
        ids = page.eval_on_selector_all("#t tbody tr", "rs => rs.map(r => r.cells[1].textContent)")
        assert ids == sorted(ids, reverse=True)
        b.close()
    assert errors == []
