"""The tile count a missed shape names is an estimate, worded as one, and checked where the run can check
it: withheld where the miss is no chord cut off between tips (the asymmetric U, whose misses do not fall
with tiles), from the measured trend where ``make`` designed several counts (docs/design-solver.md, adv54)."""

from __future__ import annotations

from dataclasses import asdict

import pytest
from fabkiri.api.shape_limits import annotate
from fabkiri.design.core.conformance import describe_miss, judge, tile_trend, trend_words
from fabkiri.design.targets.lookup import load_target
from fabkiri.fabricate import design_limits

TOL = (0.02, "rel")


def _measured(h_mm: float, spacing_mm: float, at=(0.0, 0.0)) -> dict:
    return {
        "hausdorff_mm": h_mm,
        "hausdorff_rel": h_mm / 100.0,
        "size_mm": 100.0,
        "spacing_mean_mm": spacing_mm,
        "worst": {"at": list(at)},
    }


def test_the_u_s_miss_names_no_tile_count_and_the_star_s_keeps_its_estimate():
    # make's first design of the U for card-0.3 at 6x6 (the lattice skips the hollow; 48x48 still misses)
    u = _measured(16.33, 16.91, (50.0, -0.8))
    j = judge(u, TOL, (6, 6))
    assert j.get("local_minimum") and "suggested_tiles" not in j
    line = describe_miss("deployed", j, u)
    assert (
        "50x50" not in line
        and "tiles would reach" not in line
        and "more tiles alone may not" in line
    )
    # the star at 4x4: a chord cut off at a notch, a third of a spacing; its estimate stays, as one
    star = _measured(6.18, 19.3, (0.0, 47.6))
    j = judge(star, TOL, (4, 4))
    assert j["suggested_tiles"] == [14, 14] and not j.get("local_minimum")
    line = describe_miss("deployed", j, star)
    assert "about 14x14 tiles if the miss falls as 1/tiles per side" in line
    assert "not designed" in line and "would reach" not in line


def test_make_s_designs_at_several_counts_check_the_estimate():
    # the U as make designed it: 6x6, 8x8 at 130 mm, card tape 12x12
    u = tile_trend([[6, 6, 0.1633], [8, 8, 0.1575], [12, 12, 0.2404]], 0.02)
    assert u["rate"] < 0 and u["tiles"] is None
    words = trend_words(u)
    assert "did not fall" in words and "6x6 16.33 %, 8x8 15.75 %, 12x12 24.04 %" in words
    assert "about" not in words
    # a miss that falls slower than 1/tiles: the count at the measured rate, from the largest count
    slow = tile_trend([[4, 4, 0.0573], [8, 8, 0.0343]], 0.02)
    assert 0 < slow["rate"] < 1 and slow["tiles"] == [18, 18]
    assert "slower than" in trend_words(slow) and "about 18x18 tiles at that rate" in trend_words(
        slow
    )
    # faster than 1/tiles: no faster rate is extrapolated than the estimate's
    fast = tile_trend([[4, 4, 0.06], [8, 8, 0.025]], 0.02)
    assert fast["rate"] > 1 and fast["tiles"] == [10, 10]
    # the best design at a count counts; the line takes the trend instead of the one-size estimate
    j = judge(_measured(16.33, 40.0), TOL, (6, 6))
    assert "suggested_tiles" in j
    points = [[6, 6, 0.1633], [8, 8, 0.1575], [8, 8, 0.30], [12, 12, 0.2404]]
    line = describe_miss("deployed", {**j, "trend": points}, _measured(16.33, 40.0))
    assert "did not fall" in line and "if the miss falls" not in line and "8x8 15.75 %" in line


def _limits(name: str, size: float) -> dict:
    fab, _ = design_limits.resolve(
        name, "tape", None, None, None, None, load_target("circle", size)
    )
    assert fab is not None
    return asdict(fab)


@pytest.mark.parametrize("active", [20, 0])
def test_a_count_the_process_rules_out_is_not_suggested(active):
    target = load_target("circle", 30)
    report = {
        "shape": {"deployed": {"status": "missed", "suggested_tiles": [28, 28]}},
        "fabrication": {
            "active": {"fabrication_width": active},
            "limits": _limits("acrylic-3", 30),
        },
    }
    annotate(report, [{"init": "rescaled"}], target)
    j = report["shape"]["deployed"]
    assert "suggested_tiles" not in j and j["estimate_withheld"]["tiles"] == [28, 28]
    why = j["estimate_withheld"]["why"]
    if active:  # the limits bind: more, narrower tiles are no remedy at this size
        assert "20 fabrication rows are active" in why
    else:  # the room check refuses 28x28 tiles 3 mm wide in a 30 mm circle
        assert "refused up front" in why and "--size" in why
    conf = {**_measured(2.02, 3.1), "size_mm": 30.0}
    line = describe_miss("deployed", {**j, "hausdorff_mm": 2.02, "hausdorff_rel": 0.067, "tol_mm": 0.6,
                                      "tol_rel": 0.02, "by_mm": 1.42}, conf)  # fmt: skip
    assert "no tile count is estimated" in line and "about" not in line


def test_a_count_that_fits_stays_suggested():
    target = load_target("circle", 100)
    report = {
        "shape": {"deployed": {"status": "missed", "suggested_tiles": [10, 10]}},
        "fabrication": {"active": {"fabrication_width": 0}, "limits": _limits("acrylic-3", 100)},
    }
    annotate(report, [{"init": "rescaled"}], target)
    assert report["shape"]["deployed"]["suggested_tiles"] == [10, 10]
    assert "estimate_withheld" not in report["shape"]["deployed"]
