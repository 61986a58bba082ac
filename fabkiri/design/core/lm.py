"""The one Levenberg-Marquardt core of the design solvers: damping schedule, acceptance, stopping.

Every design solver minimises ½‖r‖² of some residual rows with the same loop; what differs between
them is the linear algebra and the policy, so the core takes the first as a callable and the
second as parameters:

- the full solver (``penalty.py``) steps over all node coordinates with the sparse normal
  equations (``normal.NormalEquations``, SuperLU + CG);
- the rigid-family solver (``quad/rigid/steps.py``) steps over the family's closed-form coordinates
  with the dense reduced normal matrix;
- the closed-state outline solvers (``outline.py``, ``offset_outline.py``) step over the square
  rows' solution space, dense as well.

A solver describes one iterate as a *point* (``LMPoint``): its unknowns ``x``, residual ``r``,
largest inequality violation ``gviol`` (a step may never raise it: it is halved up to six times,
then refused), the damped step ``step(mu)`` and the decrease of ½‖r‖² its linear model predicts
for a step, ``predicted(dx)``. ``step`` may raise ``numpy.linalg.LinAlgError``; the damping then
rises tenfold and the iteration is spent (the reduced solver's dense solve on a singular matrix).

Where the solvers' loops differed they still do, as parameters (``Damping``, ``Stopping`` and the
acceptance rule's name); each solver's choice is explained where it builds them.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Generic, NamedTuple, Protocol, TypeVar

import numpy as np

HALVINGS = (
    6  # a step that raises the inequality violation is halved at most this often, then refused
)
FEASIBLE_SLACK = 1e-15  # the violation a step may add (rounding)
MIN_GAIN = 1e-4  # the "gain" rule accepts a step that achieves this share of its predicted decrease


class LMPoint(Protocol):
    """One iterate as the core sees it (see the module docstring)."""

    x: np.ndarray
    gviol: float

    @property
    def r(self) -> np.ndarray: ...

    def step(self, mu: float) -> np.ndarray: ...

    def predicted(self, dx: np.ndarray) -> float: ...


@dataclass(frozen=True)
class Damping:
    """How the damping ``mu`` moves.

    ``rule`` names the update after an accepted step (``DAMPING_RULES``): "gain" is Nielsen's
    ``mu·max(1/3, 1 − (2ρ − 1)³)`` for the gain ratio ρ (the penalty stages: the step is only as
    good as the model, so the damping follows the ratio); "tenfold" divides by ten, not below
    ``mu_min`` (the projections: near the manifold Gauss-Newton converges quadratically, so the
    damping is driven down fast). A refused step multiplies ``mu`` by ``raise_by``, which then grows
    by ``raise_growth`` per refusal in a row and is reset by an accepted step. ``mu`` above ``mu_max``
    stops the loop: no step, however short, lowers the merit.
    """

    mu0: float
    mu_max: float
    rule: str = "gain"
    mu_min: float = 0.0
    raise_by: float = 2.0
    raise_growth: float = 2.0

    def accepted(self, mu: float, ratio: float) -> float:
        return DAMPING_RULES[self.rule](self, mu, ratio)

    @classmethod
    def tenfold(cls, mu0: float, mu_max: float, mu_min: float) -> Damping:
        """The projections' damping: down tenfold per accepted step to ``mu_min``, up tenfold per
        refusal."""
        return cls(mu0, mu_max, rule="tenfold", mu_min=mu_min, raise_by=10.0, raise_growth=1.0)


def _nielsen(d: Damping, mu: float, ratio: float) -> float:
    return mu * max(1 / 3, 1 - (2 * ratio - 1) ** 3)


def _tenfold(d: Damping, mu: float, ratio: float) -> float:
    return max(mu / 10, d.mu_min)


DAMPING_RULES: dict[str, Callable[[Damping, float, float], float]] = {
    "gain": _nielsen,
    "tenfold": _tenfold,
}


@dataclass(frozen=True)
class Stopping:
    """When the loop ends (besides ``Damping.mu_max``).

    - ``max_iter`` iterations (a refused step counts);
    - ``max_stall`` accepted steps in a row that each lower ½‖r‖² by at most ``stall_tol`` of it,
      or (with ``xtol``) move no unknown by more than ``xtol·(1 + max|x|)`` (None: never);
    - ``tol_inf``: before a step, ``max|r| ≤ tol_inf`` (a projection that has arrived);
    - ``linear``: ``(k, gain)``, after an accepted step, when ``max|r|`` has not fallen below
      ``gain`` times its value ``k`` accepted steps earlier: a projection converging linearly,
      not quadratically, has rows that conflict.
    """

    max_iter: int
    stall_tol: float = 1e-6
    max_stall: int | None = 3
    xtol: float | None = None
    tol_inf: float | None = None
    linear: tuple[int, float] | None = None


def _gain(pt: LMPoint, trial: LMPoint, cost: float, cn: float, ratio: float) -> bool:
    return ratio > MIN_GAIN


def _max_row(pt: LMPoint, trial: LMPoint, cost: float, cn: float, ratio: float) -> bool:
    return np.abs(trial.r).max(initial=0.0) < np.abs(pt.r).max(initial=0.0)


def _decrease(pt: LMPoint, trial: LMPoint, cost: float, cn: float, ratio: float) -> bool:
    return cn < cost


# what an accepted step must do besides staying finite and adding no inequality violation:
# "gain": achieve MIN_GAIN of its predicted decrease (the merit minimisations);
# "max_row": lower the largest |row| (the full solver's projection, judged in the norm of its tolerance);
# "decrease": lower ½‖r‖² at all (the rigid family's hard fit, a damped Gauss-Newton)
ACCEPT: dict[str, Callable[[LMPoint, LMPoint, float, float, float], bool]] = {
    "gain": _gain,
    "max_row": _max_row,
    "decrease": _decrease,
}


P = TypeVar("P", bound=LMPoint)


class LMResult(NamedTuple, Generic[P]):
    """The last accepted point and the iterations spent (not counting a final arrival check)."""

    point: P
    iterations: int


def _limited(pt: P, dx: np.ndarray, point_at: Callable[[np.ndarray], P]) -> tuple[P, np.ndarray]:
    """Step limiting: halve ``dx`` until the trial point adds no inequality violation.

    Returns the last trial and the step after the last halving (which, when every trial failed,
    is half the last trial's step: the step is then refused anyway)."""
    for _ in range(HALVINGS):
        trial = point_at(pt.x + dx)
        if trial.gviol <= pt.gviol + FEASIBLE_SLACK:
            break
        dx = 0.5 * dx
    return trial, dx


def levenberg_marquardt(
    start: P,
    point_at: Callable[[np.ndarray], P],
    damping: Damping,
    stopping: Stopping,
    accept: str = "gain",
    log: Callable[[str], None] | None = None,
    label: str = "",
) -> LMResult[P]:
    """Minimise ½‖r‖² from ``start``; ``point_at(x)`` makes the point at ``x``.

    Every tenth accepted iteration is logged as ``label``, cost, damping, gain ratio and violation.
    """
    pt, cost = start, 0.5 * float(start.r @ start.r)
    mu, nu = damping.mu0, damping.raise_by
    rule, stall, it = ACCEPT[accept], 0, 0
    worst: list[float] = []
    for it in range(1, stopping.max_iter + 1):
        if stopping.tol_inf is not None and np.abs(pt.r).max(initial=0.0) <= stopping.tol_inf:
            return LMResult(pt, it - 1)
        try:
            dx = pt.step(mu)
        except np.linalg.LinAlgError:
            mu *= 10.0
            continue
        trial, dx = _limited(pt, dx, point_at)
        ok = trial.gviol <= pt.gviol + FEASIBLE_SLACK
        if ok:  # a refused violation needs no residual
            cn = 0.5 * float(trial.r @ trial.r)
            pred = pt.predicted(dx)
            ratio = (cost - cn) / pred if pred > 0 else -1.0
            ok = bool(np.isfinite(cn)) and rule(pt, trial, cost, cn, ratio)
        if not ok:
            mu, nu = mu * nu, nu * damping.raise_growth
            if mu > damping.mu_max:
                break
            continue
        small = _small(stopping, cost, cn, dx, pt.x)
        pt, cost = trial, cn
        mu, nu = damping.accepted(mu, ratio), damping.raise_by
        stall = stall + 1 if small else 0
        if stopping.linear is not None and _linear(stopping.linear, worst, pt):
            break
        if log is not None and it % 10 == 0:
            log(
                f"  {label} it {it}: cost {cost:.3e} mu {mu:.1e} ratio {ratio:.2f} gviol {pt.gviol:.1e}"
            )
        if stopping.max_stall is not None and stall >= stopping.max_stall:
            break
    return LMResult(pt, it)


def _small(stopping: Stopping, cost: float, cn: float, dx: np.ndarray, x: np.ndarray) -> bool:
    """Whether an accepted step gained little (``Stopping``)."""
    if cost - cn <= stopping.stall_tol * max(cost, 1e-300):
        return True
    return stopping.xtol is not None and np.abs(dx).max() <= stopping.xtol * (1 + np.abs(x).max())


def _linear(linear: tuple[int, float], worst: list[float], pt: LMPoint) -> bool:
    """Record ``max|r|`` of an accepted point; whether it fell by less than ``gain`` over ``k`` steps."""
    k, gain = linear
    worst.append(float(np.abs(pt.r).max(initial=0.0)))
    return len(worst) > k and worst[-1] > gain * worst[-1 - k]


def halving_gauss_newton(
    x: np.ndarray,
    state: tuple,
    step: Callable[[np.ndarray, tuple], np.ndarray],
    at: Callable[[np.ndarray], tuple],
    tol: float,
    max_iter: int,
    halvings: int,
):
    """Undamped Gauss-Newton steps onto ``r = 0``, each halved until the residual norm drops.

    ``at(x)`` gives the state at ``x`` (its residual first, then whatever ``step`` reuses); ``step(x, state)``
    the full step (the tube solvers': the minimum-norm least-squares solution of ``J dx = −r``). Stops at
    ``max|r| ≤ tol``, after ``max_iter`` steps, or where ``halvings`` halvings do not lower ``‖r‖``
    (the caller reports the residual it stopped at). Returns ``(x, state, steps)``.
    """
    steps = 0
    while np.abs(state[0]).max() > tol and steps < max_iter:
        dx = step(x, state)
        for _ in range(halvings):
            new = at(x + dx)
            if np.linalg.norm(new[0]) < np.linalg.norm(state[0]):
                break
            dx = 0.5 * dx
        else:
            break
        x, state = x + dx, new
        steps += 1
    return x, state, steps
