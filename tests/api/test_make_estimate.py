"""``make`` words a missed design's tile count from every count it designed: no estimate where the misses
do not fall with tiles (the asymmetric U for card-0.3: 6x6, 8x8 at 130 mm, card tape 12x12), the measured
rate where they do (docs/design-solver.md, adv54). The designs are stand-ins: each misses by a rule of its
tile count, so the run is cheap and every other part of make (retries, sizes, options) is real."""

from __future__ import annotations

from types import SimpleNamespace

import fabkiri
import pytest
from fabkiri.api import maker_design
from fabkiri.design.core import conformance as conf


def _designed_missing(monkeypatch, miss_at) -> list[tuple[int, int]]:
    """make's designs replaced by ones that miss ``miss_at(tiles per side)`` of the size, tips spaced
    three times the miss apart (a chord cut off: each gets the one-size estimate); the counts designed."""
    counts: list[tuple[int, int]] = []

    def design(result, plan, say):
        rows, cols = plan.tiles.tiles
        counts.append((rows, cols))
        h = miss_at((rows * cols) ** 0.5)
        c = {
            "hausdorff_mm": 100.0 * h,
            "hausdorff_rel": h,
            "size_mm": 100.0,
            "spacing_mean_mm": 300.0 * h,
            "worst": {"at": [0.0, 0.0]},
        }
        j = conf.judge(c, (0.02, "rel"), (rows, cols))
        report = {"shape": {"deployed": j}, "conformance": {"deployed": c}}
        result.pattern = SimpleNamespace(design={"report": report})
        result.figures = {"hausdorff_rel": h, "shape_tol_rel": 0.02, "rows_active": 3}
        line = "fabkiri: design failed: " + conf.describe_miss("deployed", j, c)
        return maker_design.StepRun(False, 1, f"missed {100 * h:.2f} %", {}, [line])

    monkeypatch.setattr(maker_design, "_design", design)
    return counts


def _miss_line(result) -> str:
    step = result.step("design")
    assert step is not None and not step.ok
    lines = [d for d in step.details if d.startswith("fabkiri: design failed: shape missed")]
    assert len(lines) == 1
    return lines[0]


def test_misses_that_do_not_fall_with_tiles_name_no_count(monkeypatch):
    counts = _designed_missing(monkeypatch, lambda n: 0.16 * (n / 6) ** 0.3)  # rising with tiles
    result = fabkiri.make("circle", size=100, material="card-0.3")
    assert not result.ok and len(set(counts)) >= 2
    line = _miss_line(result)
    assert "the misses did not fall with tiles" in line and "no tile count is estimated" in line
    assert "if the miss falls as 1/tiles" not in line  # the one-size estimate is replaced
    trend = result.figures["tile_trend"]
    assert trend["rate"] < 0 and trend["tiles"] is None
    assert {(r, c) for r, c, _ in trend["designed"]} == set(counts)


def test_misses_that_fall_give_the_count_of_their_measured_rate(monkeypatch):
    counts = _designed_missing(monkeypatch, lambda n: 0.3 / n)  # as 1/tiles per side: 15 tiles
    result = fabkiri.make("circle", size=100, material="card-0.3")
    assert not result.ok and len(set(counts)) >= 2
    line = _miss_line(result)
    assert "the misses fell at least as fast as 1/tiles per side" in line
    assert "about 16x16 tiles at 1/tiles per side" in line
    assert result.figures["tile_trend"]["rate"] == pytest.approx(1.0)
