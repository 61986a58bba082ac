"""The top level of a rigid route (the lattice asked for, not a coarse level of a larger one) of
``routes.MEMBER_STAGE_TILES`` started from its coarse design tries the stiffer penalty stage alone first
(``reduced.MEMBER_STAGE``): there its start, the coarse design's member, is close to the fine design and the soft
stage's detour cost iterations and fit (issue #36's 64x64 circle); where that stage alone does not stall close to
the target, the two stages run from the start as before. Neither larger lattices (96x96 and 128x128 ended further
off with it) nor a coarse level of one (it would change the start of the level above) try it, but for a lattice
above ``routes.KEEP_BLOCK_TILES`` that keeps its regulariser block (``MEMBER_STAGE_KEPT``)."""

from __future__ import annotations

import numpy as np
import pytest
from fabkiri.design.core.conformance import deployed
from fabkiri.design.core.request import DesignRequest
from fabkiri.design.quad import routes
from fabkiri.design.quad.rigid import reduced as R
from fabkiri.design.quad.rigid import steps
from fabkiri.design.quad.solve import design
from fabkiri.design.targets.lookup import load_target

SOFT, STIFF = "reduced_marquardt_rho_100", "reduced_marquardt_rho_10000"
ALONE = "reduced_marquardt_member_rho_10000"


def _circle(n: int, init: str = "coarse"):
    return design(DesignRequest(n, n, load_target("circle", size=100.0), rigid=True, init=init))


def test_the_top_level_from_its_coarse_design_takes_the_stiffer_stage_only(monkeypatch):
    assert set(_circle(16).report["iterations"]) == {SOFT, STIFF}  # outside the bounds: both
    monkeypatch.setattr(routes, "MEMBER_STAGE_TILES", (16 * 16, 16 * 16))
    res = _circle(16)
    assert res.converged and res.report["coarse"]["used"]
    assert set(res.report["iterations"]) == {ALONE}  # stalled, feasible, close: kept
    # a start that is not a coarse design's member keeps both stages
    assert set(_circle(16, init="rescaled").report["iterations"]) == {SOFT, STIFF}


def test_a_coarse_level_in_the_bounds_is_untouched(monkeypatch):
    asked: list = []
    search = routes.ReducedSearch

    def spy(*args, **kw):
        asked.append(kw["member"])
        return search(*args, **kw)

    monkeypatch.setattr(routes, "ReducedSearch", spy)
    before = _circle(32)
    assert before.report["coarse"]["used"] and not any(asked)
    # the 16x16 level of the 32x32 design (itself started from its coarse design) is in the bounds: not tried
    monkeypatch.setattr(routes, "MEMBER_STAGE_TILES", (16 * 16, 16 * 16))
    asked.clear()
    after = _circle(32)
    assert len(asked) >= 2 and not any(asked)
    assert np.array_equal(after.pattern.nodes, before.pattern.nodes)
    # ... while the top level in the bounds is
    monkeypatch.setattr(routes, "MEMBER_STAGE_TILES", (16 * 16, 32 * 32))
    asked.clear()
    _circle(32)
    assert asked[-1] is not None and not any(asked[:-1])


@pytest.mark.slow
def test_the_stiffer_stage_alone_fits_a_48x48_circle_closer_in_fewer_iterations(monkeypatch):
    circle = load_target("circle", size=100.0)

    def run():
        res = _circle(48)
        assert res.converged
        h = deployed(res.pattern.nodes, res.pattern.topology, circle)["hausdorff_rel"]
        return h, res.report["iterations_total"], res.report["max_equality_residual"]

    h, its, residual = run()
    monkeypatch.setattr(routes, "MEMBER_STAGE_TILES", (10**9, 10**9))  # both stages, as before
    h_both, its_both, residual_both = run()
    assert its < its_both and h <= h_both
    assert residual <= max(residual_both, 1e-11)


def test_a_lattice_that_keeps_its_block_takes_the_stiffer_stage_alone_keeping_it(monkeypatch):
    """Above ``routes.KEEP_BLOCK_TILES`` (forced low here, on the block path) the top level started from a close
    tips-fitted coarse design tries ``MEMBER_STAGE_KEPT``, with the stage's regulariser block kept."""
    monkeypatch.setattr(routes, "KEEP_BLOCK_TILES", 8 * 8)
    monkeypatch.setattr(routes, "FINISH_FLOOR", 1.0)
    monkeypatch.setattr(R, "DENSE_JD", 0)
    asked: list = []
    search, lm = routes.ReducedSearch, steps.levenberg_marquardt

    def spy(*args, **kw):
        asked.append((kw["member"], kw["keep_block"]))
        return search(*args, **kw)

    runs: list = []

    def lm_spy(merit, p, max_iter, stall_tol, log, max_stall=steps.MAX_STALL):
        runs.append((merit._kept is not None, max_stall))
        return lm(merit, p, max_iter, stall_tol, log, max_stall)

    monkeypatch.setattr(routes, "ReducedSearch", spy)
    monkeypatch.setattr(steps, "levenberg_marquardt", lm_spy)
    res = _circle(10)
    assert res.converged and res.report["coarse"]["fit"] == "tips"
    # the 5x5 level (a coarse level, from rescaled) neither; the 10x10 level both
    assert asked == [(None, False), (R.MEMBER_STAGE_KEPT, True)]
    assert R.MEMBER_STAGE_KEPT[-1] == 2 < steps.MAX_STALL
    assert runs[-1] == (True, 2) and ALONE in res.report["iterations"]
