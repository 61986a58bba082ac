"""Print-aware design (``design --printer``) makes designs that ``print`` accepts at their size (issue 32)."""

from __future__ import annotations

import pytest
from fabkiri.api.design import PatternRequest, design_pattern
from fabkiri.api.design_judge import _hausdorff
from fabkiri.fabricate import fabricability as fb
from fabkiri.fabricate.print.printers import load_printer


@pytest.mark.slow  # ~6 CPU s (main: 40 CPU s and a miss)
def test_star_150_for_prusa_mk4_meets_the_shape_and_prints_at_scale_1():
    """The 8x8 star at 150 mm (what ``make star --size 150 --printer prusa-mk4`` picks): the strip pad rows
    with the continuation's margin walled the fit in (3.80 %); without them, gated by print's own check, the
    steps meet the shape and print accepts the design at its size in the default style."""
    out = design_pattern(
        PatternRequest(tiles=(8, 8), target="star", size=150.0, printer="prusa-mk4", quiet=True)
    )
    assert out.success, out.problems
    assert _hausdorff(out.report) <= 0.02
    state = out.pattern.design["options"]["fabrication"]["state"]
    refusal = fb.print_refusal(
        out.pattern, "tiles-and-strips", load_printer("prusa-mk4"), state, 1.0
    )
    assert refusal == ""


def test_16x16_heart_200_for_prusa_mk4_says_the_limits_cost_the_shape():
    """At 16x16 a 200 mm heart's tiles are about 6.6 mm wide, and a tile holding its four strips on one face
    needs about 8.7 mm (print's own minimum on the standard pattern): the design now says so before solving
    (exit 1, as the miss it would be), with the figures, the count and the size at which the tiles are that
    wide (``api/print_tiles.py``); it took a minute of continuation to find out."""
    from fabkiri.errors import CheckFailed

    req = PatternRequest(
        tiles=(16, 16), target="heart", size=200.0, printer="prusa-mk4", quiet=True
    )
    with pytest.raises(CheckFailed) as exc:
        design_pattern(req)
    why = str(exc.value)
    assert exc.value.exit_code == 1
    assert "16x16 tiles of a 200 mm heart would be about 6.57 mm wide" in why
    assert "narrower than the 8.7 mm tile prusa-mk4 tiles-and-strips needs" in why
    assert "up to 12x12 tiles are that wide, and 16x16 would be from about 270 mm" in why
    assert "no size was checked" in why


@pytest.mark.slow
def test_16x16_circle_180_continuation_says_the_limits_cost_the_shape(monkeypatch):
    """The up-front refusal switched off, as the continuation still meets such limits (a cut at 16x16, tiles
    just wide enough): a 180 mm circle, refused up front as the heart above (7.05 mm tiles), takes the heart's
    route (docs/speed.md): the design without the rows meets the shape, the
    continuation's steps miss it more the more of the limits they take. The design says so, is not retried
    from the guesses (which start at the full limits) nor without the pad rows (the clearance rows cost it
    the shape), and exits 1."""
    from fabkiri.api import continuation
    from fabkiri.api import design as api_design

    monkeypatch.setattr(api_design, "check_tiles", lambda *a: None)
    monkeypatch.setattr(
        continuation, "_without_pads", lambda *a: pytest.fail("steps without the pad rows taken")
    )
    out = design_pattern(
        PatternRequest(tiles=(16, 16), target="circle", size=180.0, printer="prusa-mk4", quiet=True)
    )
    assert out.exit_code == 1 and out.valid and not out.shape_met
    cont = out.report["continuation"]
    tol = out.report["shape"]["deployed"]["tol_rel"]
    assert cont["free_hausdorff_rel"] <= tol and cont["shape_held_to"] is not None
    trace = cont["steps_hausdorff_rel"]
    assert trace[-1][0] == 1.0 and (trace[-1][1] is None or trace[-1][1] > tol)
    assert [a["init"] for a in out.report["attempts"]] == [cont["how"]]
    assert any("the limits cost the shape" in m for m in out.messages), out.messages


@pytest.mark.slow  # ~8 CPU s
def test_16x16_ellipse_340_for_prusa_xl_2t_is_made_and_prints():
    """At 340 mm a 16x16 ellipse's tiles are wide enough for their strips: the print-aware design meets the
    shape and its print passes every mesh check (the strips meet their tiles' pockets face to face; the
    round-off slivers they share, 1.3e-6 mm³ over the whole print, are no overlap)."""
    import fabkiri

    result = fabkiri.make("ellipse", size=340, printer="prusa-xl-2t", tiles=(16, 16))
    assert result.ok, [(s.name, s.figures) for s in result.steps]
    assert result.tiles.tiles == (16, 16)
