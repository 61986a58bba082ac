"""The report read as a page: fabricability as `info` computes it, in ✔/✖ tables (render/report_read.py)."""

from __future__ import annotations

from fabkiri.fabricate.fabricability import summary
from fabkiri.mechanics.contract import with_contracted_states
from fabkiri.pattern.kinds.tessellation import tessellation
from fabkiri.render.report import build_report


def _section(page: str, sid: str) -> str:
    return page.split(f'<section id="{sid}">')[1].split("</section>")[0]


def test_a_new_patterns_report_computes_fabricability_as_info_does():
    pattern = with_contracted_states(tessellation("quad").standard(4, 4, tile_size=10.0))
    page = build_report(pattern, viewer=False)
    fab = _section(page, "fabricability")
    assert "not computed" not in fab
    s = summary(pattern)
    assert f"{s['thinnest_tile_mm']:.3g} mm (tile {s['thinnest_tile']})" in fab
    for material, kinds in s["cut"].items():
        assert f"<th>{material}</th>" in fab
        for m in kinds.values():
            if m["min_scale"] is None:
                assert "✖ never" in fab
            elif m["min_scale"] <= 1:
                assert f"✔ from {m['min_scale']:g}×" in fab
            else:
                assert f"✖ ≥ {m['min_scale']:g}× ({m['min_width_mm']:g} mm)" in fab
    assert "<pre>" not in page  # no raw dumps anywhere
    assert "✔" in _section(page, "verification")


def test_kagome_report_says_why_fabricability_is_absent():
    pattern = with_contracted_states(tessellation("kagome").standard(3, 4, tile_size=10.0))
    page = build_report(pattern, viewer=False)
    assert "cut and print make quad patterns only" in _section(page, "fabricability")
    assert "not drawn" in _section(page, "viewer")
