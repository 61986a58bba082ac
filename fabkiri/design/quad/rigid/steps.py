"""The reduced problem's two step loops, both on the LM core (``lm.py``): Levenberg-Marquardt on the
merit and the hard-fit projection; and the runs of them a search makes (``reduced._search``)."""

from __future__ import annotations

from typing import TYPE_CHECKING, Self

import numpy as np

from ...core.lm import Damping, Stopping
from ...core.lm import levenberg_marquardt as lm_core
from ..constraints import exact_fits
from .merit import KeptGridBlock

if TYPE_CHECKING:
    from ...core.stencils import Family
    from .merit import _Evaluation
    from .reduced import ReducedSearch, _Merit

MAX_STALL = 3  # a stage stops after this many accepted steps in a row that each gain less than its stall tolerance


class _Member:
    """A member ``p`` of the rigid family as the LM core's point (``lm.LMPoint``): the merit's rows (or,
    with ``hard``, the hard fit's), with what a step needs (``_linear``) formed on the first step from it."""

    hard = False

    def __init__(self, merit: _Merit, p: np.ndarray):
        self.merit, self.x = merit, p
        self.ev: _Evaluation = merit.evaluate(p, hard=self.hard)
        self.gviol = self.ev.gviol
        self._lin: tuple | None = None

    def moved(self, p: np.ndarray) -> Self:
        return type(self)(self.merit, p)

    @property
    def r(self) -> np.ndarray:
        return self.ev.r

    @property
    def linear(self) -> tuple:
        if self._lin is None:
            self._lin = self._linear()
        return self._lin

    def _linear(self) -> tuple:
        """The reduced normal matrix ``JᵀJ`` and gradient ``Jᵀr``."""
        return self.ev.normal()

    def step(self, mu: float) -> np.ndarray:
        """Solves ``(JᵀJ + μ D) dp = −Jᵀr``: D the diagonal of JᵀJ (Marquardt) or its mean (Levenberg)."""
        Hr, g = self.linear
        if self.merit.scaling == "marquardt":
            d = np.maximum(np.diag(Hr), 1e-12 * max(float(np.diag(Hr).max()), 1e-300))
        else:
            d = np.full(len(g), max(float(np.diag(Hr).mean()), 1e-300))
        return np.linalg.solve(Hr + mu * np.diag(d), -g)

    def predicted(self, dp: np.ndarray) -> float:
        Hr, g = self.linear
        return -(float(g @ dp) + 0.5 * float(dp @ (Hr @ dp)))


class _HardMember(_Member):
    """The hard fit's point: the fit rows (plus half-margin inequality rows) and their dense Jacobian."""

    hard = True

    def _linear(self) -> tuple:
        return (self.ev.jacobian(),)

    @property
    def J(self) -> np.ndarray:
        return self.linear[0]

    def step(self, mu: float) -> np.ndarray:
        J = self.J
        return -np.linalg.solve(J.T @ J + mu * np.eye(len(self.x)), J.T @ self.r)

    def predicted(self, dp: np.ndarray) -> float:
        Jdp = self.J @ dp
        return -(float(self.r @ Jdp) + 0.5 * float(Jdp @ Jdp))


def levenberg_marquardt(
    merit: _Merit, p: np.ndarray, max_iter: int, stall_tol: float, log, max_stall: int = MAX_STALL
):
    """Levenberg-Marquardt on the merit; returns ``p, X, iterations``.

    The damping multiplies a scaling matrix (``_Member.step``), so it starts at 1e-3 itself and
    stops the loop above 1e16; otherwise the penalty stages' rules (gain ratio, Nielsen's update).
    """
    start = _Member(merit, p)
    pt, it = lm_core(
        start,
        start.moved,
        Damping(1e-3, 1e16),
        Stopping(max_iter, stall_tol, max_stall),
        log=log,
        label=f"reduced rho={merit.sq**2:g}",
    )
    return pt.x, pt.ev.X, it


def hard_fit(merit: _Merit, p: np.ndarray, fit_tol: float, max_iter: int = 40):
    """Damped Gauss-Newton on the fit rows (plus half-margin inequality rows): ``X, p, iterations``.

    The fit rows are fewer than the unknowns, so with little damping a step is close to the
    minimum-norm one; the damping falls tenfold after every step that lowers the sum of squares
    (without a new inequality violation) and rises tenfold otherwise (the core's "tenfold" rule
    and "decrease" acceptance, with no stall test: the loop ends at ``fit_tol``).
    ``X`` is None when the rows could not be brought under ``fit_tol`` (``p``: the last member either way).
    """
    start = _HardMember(merit, p)
    scale = max(float((start.J * start.J).sum(0).mean()), 1e-300)
    damping = Damping.tenfold(1e-12 * scale, 1e4 * scale, 1e-14 * scale)
    pt, it = lm_core(
        start,
        start.moved,
        damping,
        Stopping(max_iter, max_stall=None, tol_inf=fit_tol),
        accept="decrease",
    )
    return (pt.ev.X if np.abs(pt.r).max(initial=0.0) <= fit_tol else None), pt.x, it


def fit_miss(fits: list[Family], X: np.ndarray) -> float:
    """Largest |fit row| relative to its target's size (both in normalised units)."""
    return max(
        (float(np.abs(f.residual(X)).max()) / f.meta["target"].size for f in fits), default=0.0
    )


def stage(judge, rho: float, scaling: str, how: ReducedSearch, tag: str):
    """The merit of one stage of a search (``reduced._search``): ``judge`` at ``rho`` and ``scaling``, with the
    regulariser's grid block kept through the stage (``merit.KeptGridBlock``) where ``how.keep_block`` asks and
    the search is not a contact rerun (``tag``); not on the dense path (``TileShapeRows``)."""
    merit = judge.staged(rho, scaling)
    if not how.keep_block or tag or merit._tiles is not None:
        return merit
    merit._kept = KeptGridBlock(merit, len(merit.grid_regs))
    return merit


def exact_fit(merit, p, X, key: str, iters: dict, how: ReducedSearch):
    """``(p, X, "hard")`` where the fit is within 1 % of a tile and the hard-fit projection makes it exact."""
    fit_max = max(
        (float(np.abs(f.residual(X)).max()) for f in exact_fits(merit.fits)),
        default=0.0,
    )
    if merit.fits and fit_max < 1e-2 * how.mean_edge(X):
        Xh, ph, kh = hard_fit(merit, p, how.fit_tol)
        iters[f"reduced_{key}_hard"] = kh
        if Xh is not None:
            return ph, Xh, "hard"
    return None


def stiffer_alone(judge, p0, scaling: str, iters: dict, how: ReducedSearch):
    """The stiffer stage alone from a coarse design's member ``p0`` (``how.member``): ``(p, X, merit)`` where it
    stalls before its cap, feasible, with its fit within ``how.miss_tol``; else None, and the stages run from
    ``p0`` as before. Where the fine level must move far (star, ellipse, heart at 48-64 tiles) this stage crawls
    along its wall to the cap, or stalls with the fit still off, and would end further off. The stage keeps its
    regulariser block where ``how.keep_block`` asks (``stage``)."""
    assert how.member is not None
    rho, stall_tol, cap, max_stall = how.member
    merit = stage(judge, rho, scaling, how, "")
    p, X, k = levenberg_marquardt(merit, p0, min(cap, how.max_iter), stall_tol, how.log, max_stall)
    iters[f"reduced_{scaling}_member_rho_{rho:g}"] = k
    miss = fit_miss(exact_fits(merit.fits), X)
    if k < cap and judge.ineq_violation(judge.state(p)) == 0.0 and miss <= how.miss_tol:
        return p, X, merit
    how.log(
        f"the stiffer stage alone ({k} iterations, misses by {miss:.3%}): the stages from the start"
    )
    return None
