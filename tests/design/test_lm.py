"""The one Levenberg-Marquardt core (fabkiri/design/core/lm.py) on small problems with known answers."""

from __future__ import annotations

import numpy as np
import pytest
from fabkiri.design.core.lm import ACCEPT, DAMPING_RULES, Damping, Stopping, levenberg_marquardt


class Dense:
    """A point of ``r(x)`` with an analytic Jacobian; ``g(x) >= 0`` is the inequality (violation max(0, -g))."""

    def __init__(self, fun, x, g=None, singular_until: list | None = None):
        self.fun, self.x, self.g, self.singular_until = fun, np.asarray(x, float), g, singular_until
        self.r, self.J = fun(self.x)
        self.gviol = 0.0 if g is None else max(0.0, -float(g(self.x)))

    def moved(self, x):
        return Dense(self.fun, x, self.g, self.singular_until)

    def step(self, mu):
        if self.singular_until is not None and self.singular_until[0] > 0:
            self.singular_until[0] -= 1
            raise np.linalg.LinAlgError("singular")
        A = self.J.T @ self.J + mu * np.eye(len(self.x))
        return np.linalg.solve(A, -self.J.T @ self.r)

    def predicted(self, dx):
        Jdx = self.J @ dx
        return -(float(self.r @ Jdx) + 0.5 * float(Jdx @ Jdx))


def rosenbrock(x):
    r = np.array([10.0 * (x[1] - x[0] ** 2), 1.0 - x[0]])
    J = np.array([[-20.0 * x[0], 10.0], [-1.0, 0.0]])
    return r, J


def linear(x):  # r = A x - b, minimum at x* = (1, 2), where r = 0
    A = np.array([[2.0, 1.0], [1.0, 3.0], [0.0, 1.0]])
    return A @ x - A @ np.array([1.0, 2.0]), A


def test_rosenbrock_converges_from_the_classic_start():
    start = Dense(rosenbrock, [-1.2, 1.0])
    pt, it = levenberg_marquardt(start, start.moved, Damping(1e-3, 1e20), Stopping(200, 1e-12))
    assert np.allclose(pt.x, [1.0, 1.0], atol=1e-6) and 10 < it < 200


def test_a_step_never_adds_inequality_violation():
    """With x0 <= 0.5 imposed, the iterates stay feasible (each step may add 1e-15 of rounding) and stop on
    the wall, not at (1, 1)."""
    wall = lambda x: 0.5 - x[0]  # noqa: E731
    start = Dense(rosenbrock, [-1.2, 1.0], g=wall)
    seen = []

    def at(x):
        p = start.moved(x)
        seen.append(p)
        return p

    pt, _ = levenberg_marquardt(start, at, Damping(1e-3, 1e20), Stopping(200, 1e-12))
    assert pt.gviol <= 200 * 1e-15 and pt.x[0] <= 0.5 + 1e-12 and abs(pt.x[0] - 1.0) > 0.4
    assert any(p.gviol > 0 for p in seen)  # the limiting had something to refuse


def test_tol_inf_stops_before_a_step_and_does_not_count_it():
    start = Dense(linear, [0.0, 0.0])
    stop = Stopping(50, max_stall=None, tol_inf=1e-10)
    pt, it = levenberg_marquardt(
        start,
        start.moved,
        Damping(1e-12, 1e20, rule="tenfold", raise_by=10.0, raise_growth=1.0),
        stop,
        accept="max_row",
    )
    assert (
        np.abs(pt.r).max() <= 1e-10 and 1 <= it <= 3
    )  # Gauss-Newton on a linear problem: one or two steps
    again, k = levenberg_marquardt(pt, pt.moved, Damping(1e-12, 1e20), stop)
    assert k == 0 and again is pt  # already there: no step taken


def inconsistent(x):  # no zero residual: the least-squares minimum is x = (0, 0), ½‖r‖² = 1
    A = np.array([[1.0, 0.0], [1.0, 0.0], [0.0, 1.0]])
    return A @ x - np.array([1.0, -1.0, 0.0]), A


def test_max_stall_stops_a_loop_that_gains_little():
    """Damping held at 1e4 (JᵀJ ~ 1): every step gains ~1e-4 of the cost, under stall_tol = 1e-2."""
    start = Dense(inconsistent, [3.0, 3.0])
    heavy = Damping(1e4, 1e20, rule="tenfold", mu_min=1e4)
    pt, it = levenberg_marquardt(start, start.moved, heavy, Stopping(100, stall_tol=1e-2))
    assert it == 3 and 0.5 * float(pt.r @ pt.r) < 0.5 * float(start.r @ start.r)
    pt2, it2 = levenberg_marquardt(
        start, start.moved, heavy, Stopping(100, stall_tol=1e-2, max_stall=None)
    )
    assert it2 == 100 and float(pt2.r @ pt2.r) < float(pt.r @ pt.r)
    # the same damping, a stall tolerance under the gain: no stall
    assert (
        levenberg_marquardt(start, start.moved, heavy, Stopping(100, stall_tol=1e-6)).iterations
        == 100
    )


def test_a_singular_solve_raises_the_damping_and_spends_the_iteration():
    flag = [2]
    start = Dense(linear, [0.0, 0.0], singular_until=flag)
    pt, it = levenberg_marquardt(
        start, start.moved, Damping(1e-3, 1e20), Stopping(3, max_stall=None)
    )
    assert flag == [0] and it == 3  # two iterations lost to the singular solves, one step taken
    assert 0.5 * float(pt.r @ pt.r) < 0.5 * float(start.r @ start.r)


def test_mu_max_stops_when_no_step_lowers_the_merit():
    class Flat(Dense):
        def predicted(self, dx):  # a model that always over-promises: every step is refused
            return 1e300

    start = Flat(linear, [0.0, 0.0])
    pt, it = levenberg_marquardt(start, lambda x: Flat(linear, x), Damping(1.0, 1e3), Stopping(100))
    assert (
        pt is start and it == 4
    )  # mu = 1 → 2 → 8 → 64 → 1024 > 1e3: the fourth refusal ends the loop


def test_linear_stop_ends_a_projection_that_stalls():
    """max|r| falling by ~2e-4 a step (damping held at 1e4) is not quadratic: the linear test stops the loop
    once it has not fallen tenfold over 2 accepted steps."""
    start = Dense(inconsistent, [3.0, 3.0])
    heavy = Damping(1e4, 1e20, rule="tenfold", mu_min=1e4)
    pt, it = levenberg_marquardt(
        start, start.moved, heavy, Stopping(50, max_stall=None, linear=(2, 0.1)), accept="max_row"
    )
    assert it == 3 and np.abs(pt.r).max() < np.abs(start.r).max()
    _, k = levenberg_marquardt(
        start, start.moved, heavy, Stopping(50, max_stall=None), accept="max_row"
    )
    assert k == 50
    fast = Damping(
        1e-12, 1e20, rule="tenfold", raise_by=10.0, raise_growth=1.0
    )  # Gauss-Newton: no linear stop
    pt3, _ = levenberg_marquardt(
        start, start.moved, fast, Stopping(50, max_stall=None, linear=(2, 0.1)), accept="max_row"
    )
    assert np.allclose(pt3.x, [0.0, 0.0], atol=1e-9)


def test_the_acceptance_rules_and_damping_rules_differ_as_documented():
    a = Dense(linear, [0.0, 0.0])
    b = a.moved([1.0, 0.0])
    ca, cb = 0.5 * float(a.r @ a.r), 0.5 * float(b.r @ b.r)
    assert cb < ca and np.abs(b.r).max() < np.abs(a.r).max()
    assert ACCEPT["decrease"](a, b, ca, cb, -1.0) and not ACCEPT["gain"](a, b, ca, cb, -1.0)
    assert ACCEPT["max_row"](a, b, ca, cb, -1.0) and not ACCEPT["max_row"](b, a, cb, ca, 1.0)
    d = Damping(1.0, 1e20, mu_min=0.5)
    assert (
        DAMPING_RULES["gain"](d, 1.0, 1.0) == pytest.approx(1 / 3)
        and DAMPING_RULES["gain"](d, 1.0, 0.5) == 1.0
    )
    assert (
        DAMPING_RULES["tenfold"](d, 1.0, 1.0) == 0.5
        and DAMPING_RULES["tenfold"](d, 100.0, 0.0) == 10.0
    )
