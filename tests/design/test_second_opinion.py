"""The full solver's second opinion: a first schedule that stops short is handed to the caller before the
stiff restart (``penalty._solve_full(stalled=...)``, ``routes._polish``)."""

from __future__ import annotations

import numpy as np
import pytest
from fabkiri.design.core.request import DesignRequest
from fabkiri.design.quad import penalty as P
from fabkiri.design.quad import routes as R
from fabkiri.design.quad.measures import _acceptable, _objective
from fabkiri.design.quad.problem import DesignProblem
from fabkiri.design.targets import lookup as T


def _problem() -> DesignProblem:
    return DesignProblem(DesignRequest(6, 6, T.load_target("heart", 100.0), rigid=True))


@pytest.mark.slow
def test_a_first_schedule_that_stops_short_is_offered_before_the_restart(monkeypatch):
    """One penalty iteration leaves the equalities far off: the end is offered to ``stalled``, whose valid
    answer is kept (after the equalities' Gauss-Newton steps) and no stiff restart runs; a None answer
    restarts as before."""
    monkeypatch.setattr(P, "PENALTIES", ((1e2, P.EARLY_STALL, 1),))
    prob = _problem()
    ends: list = []

    def offer(X):
        ends.append(X.copy())
        return R._reduced_from(prob, X, np.pi / 4, None, lambda m: None, {}, "t_", R.SCALINGS[:1])

    iters: dict = {}
    X, _ = P._solve_full(prob, lambda m: None, iters, offer)
    assert len(ends) == 1 and not np.allclose(ends[0], prob.X0)
    assert not any(k.endswith("_restart") for k in iters) and "projection_kept" in iters
    assert _acceptable(prob, X)

    iters = {}
    X, _ = P._solve_full(prob, lambda m: None, iters, lambda X: None)
    assert any(k.endswith("_restart") for k in iters)


def test_the_rigid_member_replaces_the_restart_only_when_valid_and_no_worse_than_the_end(
    monkeypatch,
):
    prob = _problem()
    X = prob.X0.copy()  # the guess: its rigid member fits it better
    polished: list = []
    out = R._polish(prob, X, lambda m: None, {}, polished)
    assert out is not None and polished == [True]
    assert _acceptable(prob, out[0]) and _objective(prob, out[0]) <= _objective(prob, X)
    # an end that fits better than the member (objective 0 here): the restart runs instead
    monkeypatch.setattr(R, "_objective", lambda prob, Y: 0.0 if Y is X else 1.0)
    polished = []
    assert R._polish(prob, X, lambda m: None, {}, polished) is None and not polished
