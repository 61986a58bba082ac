"""The coarse level of a coarse-to-fine start (``DesignProblem._coarse_level``): fitted with the tips on their
arcs only, and again with the outline rows where that outline misses the shape tolerance (issue #37: the
drop's tips-only levels sat at 40 % of its size, and its 64x64 design ended in a 22 % local minimum)."""

from __future__ import annotations

from dataclasses import replace

import pytest
from fabkiri.design.core.conformance import deployed
from fabkiri.design.core.request import DesignRequest
from fabkiri.design.quad.problem import DesignProblem
from fabkiri.design.quad.solve import design, design_problem
from fabkiri.design.targets.lookup import load_target
from fabkiri.pattern.model import Pattern

from ..conftest import REPO


def _start_miss(prob: DesignProblem, target) -> float:
    pat = Pattern(nodes=prob.X0[: prob.n] * prob.L0, tiles=prob.std.tiles)
    return deployed(pat.nodes, pat.topology, target)["hausdorff_rel"]


@pytest.mark.slow
def test_a_coarse_level_that_misses_the_outline_is_refitted_with_the_outline_rows():
    drop = load_target(str(REPO / "bench" / "data" / "drop.csv"), size=100.0)
    prob = design_problem(DesignRequest(16, 16, drop, rigid=True, init="coarse", coarse_refit=True))
    level = prob.coarse
    assert level is not None and level["used"]
    assert (
        level["tips_only_hausdorff_rel"] > 0.2
    )  # the tips-only 8x8 level: bunched tips (main: the start)
    assert level["fit"] == "outline" and level["hausdorff_rel"] <= 0.02
    # the fine start resampled from it (main: 40 % of the size)
    assert _start_miss(prob, drop) < 0.1


def test_a_coarse_level_within_the_tolerance_keeps_the_tips_only_fit():
    circle = load_target("circle", size=100.0)
    prob = design_problem(DesignRequest(16, 16, circle, rigid=True, init="coarse"))
    level = prob.coarse
    assert level is not None and level["used"] and level["fit"] == "tips"
    assert level["hausdorff_rel"] <= 0.02 and "tips_only_hausdorff_rel" not in level


@pytest.mark.slow
def test_a_coarse_level_is_refitted_past_a_threshold_of_the_callers():
    """``coarse_refit_above`` (the minimax finish's own threshold) replaces the shape tolerance as the miss that
    asks for the refit: the circle's 8x8 level, within the 2 % tolerance, is refitted past a smaller one."""
    circle = load_target("circle", size=100.0)
    ask = DesignRequest(16, 16, circle, rigid=True, init="coarse", coarse_refit=True)
    assert "tips_only_hausdorff_rel" not in (design_problem(ask).coarse or {})
    level = design_problem(replace(ask, coarse_refit_above=1e-6)).coarse
    assert level is not None and level["tips_only_hausdorff_rel"] > 1e-6
    assert level["hausdorff_rel"] <= level["tips_only_hausdorff_rel"] or level["fit"] == "tips"


@pytest.mark.slow
def test_a_coarse_to_fine_design_that_misses_is_redone_from_refitted_levels_and_the_closer_kept():
    drop = load_target(str(REPO / "bench" / "data" / "drop.csv"), size=100.0)
    # at a 0.5 % tolerance the 16x16 design from the tips-only 8x8 level (0.92 %) misses
    req = DesignRequest(
        16, 16, drop, rigid=True, init="coarse", solver="reduced", second_opinion_above=0.005
    )
    res = design(req)
    refit = res.report["coarse_refit"]
    h = deployed(res.pattern.nodes, res.pattern.topology, drop)["hausdorff_rel"]
    assert refit["tips_only_hausdorff_rel"] > 0.005
    assert h == min(refit["tips_only_hausdorff_rel"], refit["refit_hausdorff_rel"])
    assert refit["kept"] == ("refit" if h < refit["tips_only_hausdorff_rel"] else "tips_only")
    # the kept design's own coarse level says how it was fitted
    level = res.report["coarse"]
    assert res.converged and level["used"]
    assert level["fit"] == ("outline" if refit["kept"] == "refit" else "tips")


def test_a_design_within_the_tolerance_is_not_redone():
    circle = load_target("circle", size=100.0)
    res = design(DesignRequest(16, 16, circle, rigid=True, init="coarse", solver="reduced"))
    assert res.converged and "coarse_refit" not in res.report


@pytest.mark.slow
def test_the_drop_at_32x32_meets_one_percent_from_refitted_coarse_levels():
    """From the tips-only 16x16 level the rigid 32x32 drop ends at 1.78 % (main, whatever the tolerance); at a
    1 % tolerance that miss redoes it from refitted levels (0.51 %, 9 CPU s with the reduced solver)."""
    drop = load_target(str(REPO / "bench" / "data" / "drop.csv"), size=100.0)
    req = DesignRequest(
        32, 32, drop, rigid=True, init="coarse", solver="reduced", second_opinion_above=0.01
    )
    res = design(req)
    h = deployed(res.pattern.nodes, res.pattern.topology, drop)["hausdorff_rel"]
    assert res.converged and h <= 0.01
    assert res.report["coarse_refit"]["tips_only_hausdorff_rel"] > 0.01
