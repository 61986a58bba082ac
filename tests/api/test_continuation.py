"""The continuation in the fabrication limits (``api/continuation.py``): what its steps say about a miss."""

from __future__ import annotations

import pytest
from fabkiri.api.continuation import limits_note, shape_held_to
from fabkiri.api.design_report import DesignAttempt

TOL = 0.02


@pytest.mark.parametrize(
    ("trace", "held"),
    [
        (
            [[0.25, 0.007], [0.5, 0.005], [0.75, 0.067], [1.0, 0.19]],
            0.5,
        ),  # the limits cost the shape
        (
            [[0.25, 0.007], [0.5, None], [0.75, 0.011], [1.0, 0.19]],
            0.75,
        ),  # unconverged steps say nothing
        (
            [[0.25, 0.007], [0.5, 0.005], [0.75, 0.011], [1.0, 0.015]],
            None,
        ),  # the full limits met it
        (
            [[0.25, 0.03], [0.5, 0.05], [1.0, 0.19]],
            None,
        ),  # no step met it: the start may be at fault
        ([[0.25, 0.01], [1.0, None]], 0.25),  # the full limits did not converge
        ([], None),  # no steps (the jump converged)
    ],
)
def test_shape_held_to_is_the_largest_fraction_that_met_the_tolerance(trace, held):
    assert shape_held_to(trace, TOL) == held


def test_the_miss_note_names_the_fraction_and_the_full_limits_miss():
    trace = [[0.25, 0.007], [0.5, 0.005], [0.75, 0.067], [1.0, 0.19]]
    cont = {
        "steps_hausdorff_rel": trace,
        "shape_held_to": shape_held_to([[0.0, 0.0017], *trace], TOL),
        "free_hausdorff_rel": 0.0017,
    }
    report = {"continuation": cont}
    note = limits_note(_judged(report))
    assert "without them (0.2%) and up to 50% of them" in note and "19.0%" in note
    cont["steps_hausdorff_rel"][-1][1] = None
    assert "unconverged" in limits_note(_judged(report))
    cont["shape_held_to"] = shape_held_to([[0.0, 0.014], [0.25, 0.029], [1.0, 0.23]], TOL)
    assert cont["shape_held_to"] == 0.0  # only the design without the rows met it
    assert "without them (0.2%), at all" in limits_note(_judged(report))
    assert limits_note(_judged({"continuation": {"shape_held_to": None}})) == ""
    assert limits_note(_judged({})) == ""


def _outcome(h: float, valid: bool = True):
    """A judged attempt as ``_check`` returns it: (pattern, report, problems, valid, states)."""
    report = {
        "conformance": {"deployed": {"hausdorff_rel": h}},
        "shape": {"deployed": {"status": "met" if h <= TOL else "missed"}},
    }
    return DesignAttempt(None, report, [], valid, {})


def _judged(report: dict) -> DesignAttempt:
    """A valid attempt with ``report`` (what ``limits_note`` reads)."""
    return DesignAttempt(None, report, [], True, {})


@pytest.mark.parametrize(
    ("jump", "steps_h", "runs_steps", "kept", "tiles"),
    [
        ((True, 0.01), 0.05, False, 0.01, 16),  # the jump met the shape: no steps
        ((False, 0.04), 0.03, True, 0.03, 16),  # the jump stalled: the steps, as before
        ((False, 0.04), 0.03, True, 0.03, 8),
        ((True, 0.19), 0.17, True, 0.17, 16),  # converged but missed: the steps, the better kept
        ((True, 0.19), 0.21, True, 0.19, 16),  # ... the jump when it is better
        ((True, 0.19), 0.17, False, 0.19, 8),  # ... from 16x16 only
        ((True, 0.03), 0.031, False, 0.03, 16),  # ... and a near miss is the refinement's
    ],
)
def test_the_steps_follow_a_jump_that_stalls_or_misses(
    monkeypatch, jump, steps_h, runs_steps, kept, tiles
):
    from types import SimpleNamespace

    import fabkiri.api.continuation as C
    import numpy as np

    calls = []

    def fake_raise(req, X, init, steps, spent, trace=None):
        calls.append(steps)
        converged, h = jump if steps is C.JUMP else (True, steps_h)
        if trace is not None:
            trace.append([1.0, h])
        return steps, SimpleNamespace(converged=converged, h=h), X, spent + 1.0

    monkeypatch.setattr(C, "_raise_limits", fake_raise)
    req = SimpleNamespace(rigid=False, rows=tiles, cols=tiles, second_opinion_above=TOL)
    trace: list = []
    steps, step, _, outcome, spent = C._jump_or_steps(
        req, np.zeros((4, 2)), "rigid", lambda r: _outcome(r.h, r.converged), 0.0, trace
    )
    assert (C.CONTINUATION in calls) == runs_steps and calls[0] is C.JUMP
    assert steps == ((1.0, *C.CONTINUATION) if runs_steps else (1.0,))
    assert outcome[1]["conformance"]["deployed"]["hausdorff_rel"] == kept
    assert spent == (2.0 if runs_steps else 1.0) and len(trace) == int(runs_steps)


@pytest.mark.parametrize(
    ("tiles", "held", "miss", "worth"),
    [
        (16, 0.5, 0.19, False),  # the limits cost the shape and the miss is far: no refinement
        (16, 0.5, 0.03, True),  # within REFINE_WITHIN x the tolerance: refined
        (16, None, 0.19, True),  # the steps do not say the limits cost it
        (8, 0.5, 0.19, True),  # below 16x16, as before
    ],
)
def test_the_refinement_is_skipped_only_far_past_a_limit(tiles, held, miss, worth):
    from types import SimpleNamespace

    from fabkiri.api.continuation import REFINE_WITHIN, _refine_worth

    req = SimpleNamespace(rows=tiles, cols=tiles, second_opinion_above=TOL)
    assert REFINE_WITHIN * TOL < 0.19
    assert _refine_worth(req, held, miss) is worth
