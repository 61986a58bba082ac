"""The full solver's loops: penalty Levenberg-Marquardt stages, then Gauss-Newton projection.

See ``solve.py``'s docstring for the method; ``_solve_full`` runs it on a
``problem.DesignProblem`` and returns ``(X, mode)``.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
from scipy import sparse

from ..core.lm import Damping, Stopping, levenberg_marquardt
from . import constraints as C
from .constraints import exact_fits
from .measures import _ineq_values, _mean_edge, family_residuals
from .problem import DesignProblem

STALL = (
    1e-6  # a penalty stage ends after 3 accepted steps that each lower the merit by less than this
)
EARLY_STALL = 1e-3  # ... looser in the first stage: the next one refines from there
# (penalty weight, stall tolerance, iteration cap) per stage; the projection then enforces c = 0 exactly,
# moving x by O(|c|), so the last stage need not converge the penalty problem to high accuracy
PENALTIES = ((1e2, EARLY_STALL, 200), (1e4, STALL, 40))
STIFF_PENALTIES = (
    (1e4, 1e-4, 300),
    (1e6, STALL, 60),
)  # fallback when the first schedule gets stuck
COARSE_PENALTIES = (
    (1e4, STALL, 40),
)  # from a coarse-to-fine start: repair the constraints stiffly, then project
RESTART_ABOVE = 1e-3  # max equality row after the first schedule that triggers the fallback
# inexact LM: penalty-stage steps solve the normal equations to 1e-5 (the gain ratio judges the step that
# was actually taken); the projection keeps 1e-13 so its Gauss-Newton steps stay quadratically convergent.
# 1e-3 and 1e-4 were faster on the rigid circle but landed in worse local minima on must-show targets
# (heart 16x16 fit 12.8 mm instead of 0.09 mm, blob 8x8 rigid 0.92 mm instead of 0.16 mm); 1e-5 did not.
LM_CG_RTOL = 1e-5
# a projection whose max row has not fallen tenfold over its last 5 accepted steps has stopped converging
# quadratically: the rows conflict (the 16x16 heart's half-margin rows: 50 steps from 1e-6 to 3e-8, then the
# equalities-only pass converged in 6); it hands over to the next pass
HARD_STALL_STEPS = 5
HARD_STALL_GAIN = 0.1
PROJECT_KEPT = (
    5  # Gauss-Newton steps at most on a design kept instead of the stiff restart (``_projected``)
)


def _stacked(prob: DesignProblem, X: np.ndarray, rho: float, hard: list[C.Family] | None = None):
    """Residual vector and Jacobian of the phase-1 merit (or of ``hard`` rows only)."""
    rs, Js = [], []
    if hard is not None:
        for f in hard:
            if f.kind == "ineq":  # projection keeps inequalities with half their margin
                v, J = _ineq_rows(f, X, 0.5 * prob.margin[f.name])
                act = v < 0
                r = np.where(act, v, 0.0)
                J = sparse.diags(act.astype(float)) @ J
            else:
                r, J = f(X)
            rs.append(r)
            Js.append(J)
        return np.concatenate(rs), sparse.vstack(Js).tocsr()
    sq = np.sqrt(rho)
    w = np.sqrt(prob.req.reg_weight)
    for f in prob.families:
        if f.kind == "ineq":
            v, J = _ineq_rows(f, X, prob.margin[f.name])
            act = v < 0
            rs.append(sq * np.where(act, v, 0.0))
            Js.append(sparse.diags(sq * act.astype(float)) @ J)
            continue
        r, J = f(X)
        if f.kind == "eq":
            rs.append(sq * r)
            Js.append(sq * J)
        elif f.kind == "fit":
            rs.append(r)
            Js.append(J)
        else:
            rs.append(w * r)
            Js.append(w * J)
    return np.concatenate(rs), sparse.vstack(Js).tocsr()


def _ineq_rows(f: C.Family, X: np.ndarray, margin: float):
    """``(g - margin, J)`` of inequality family ``f``: ``J`` holds the rows below the margin at least (the
    others are masked off by the caller), so a family that can (``Family.active``) computes only those."""
    if f.active is None:
        r, J = f(X)
        return r - margin, J
    v = f.residual(X) - margin
    return v, f.jacobian_where(X, v < 0)


class _Point:
    """An iterate of the full solver for the LM core (``lm.LMPoint``).

    Its residual and sparse Jacobian (of the merit, or of the hard rows) are stacked on first use:
    a step refused for a new inequality violation needs neither.
    """

    def __init__(
        self, prob: DesignProblem, x: np.ndarray, shape: tuple, rho: float, hard, rtol: float
    ):
        self.prob, self.x, self.shape, self.rho, self.hard, self.rtol = (
            prob,
            x,
            shape,
            rho,
            hard,
            rtol,
        )
        self.gviol = max(0.0, -_ineq_values(prob, x.reshape(shape)).min(initial=0.0))
        self._rows: tuple | None = None

    def moved(self, x: np.ndarray) -> _Point:
        return _Point(self.prob, x, self.shape, self.rho, self.hard, self.rtol)

    @property
    def r(self) -> np.ndarray:
        return self.rows[0]

    @property
    def rows(self) -> tuple:
        if self._rows is None:
            self._rows = _stacked(self.prob, self.x.reshape(self.shape), self.rho, self.hard)
        return self._rows

    def step(self, mu: float) -> np.ndarray:
        r, J = self.rows
        return self.prob.normal.solve(J, r, mu, rtol=self.rtol)

    def predicted(self, dx: np.ndarray) -> float:
        r, J = self.rows
        Jdx = J @ dx
        return -(float(r @ Jdx) + 0.5 * float(Jdx @ Jdx))


def _lm(
    prob: DesignProblem,
    X: np.ndarray,
    rho: float,
    max_iter: int,
    log,
    hard=None,
    tol_inf=0.0,
    stall_tol=STALL,
):
    """Levenberg-Marquardt on the merit (or on the hard rows) with the core ``lm``; returns X, iterations.

    The penalty stages (``hard`` None) damp by the gain ratio from 1e-3 of the mean diagonal of JᵀJ and
    solve inexactly (``LM_CG_RTOL``). The projection (``hard`` rows) starts almost undamped (1e-12),
    damps tenfold down and up, solves to 1e-13, accepts a step that lowers the largest row (its
    tolerance is a max norm), stops when that row is under ``tol_inf`` or converges only linearly.
    Both stop after 3 steps that gain less than ``stall_tol`` or move x by less than 1e-13.
    """
    start = _Point(
        prob, X.reshape(-1).copy(), X.shape, rho, hard, LM_CG_RTOL if hard is None else 1e-13
    )
    J = start.rows[1]
    diag_mean = float((J.multiply(J)).sum() / max(len(start.x), 1))
    scale = max(diag_mean, 1e-30)
    stopping = Stopping(max_iter, stall_tol=stall_tol, xtol=1e-13)
    if hard is None:
        damping = Damping(1e-3 * scale, 1e20 * scale)
    else:
        damping = Damping.tenfold(1e-12 * scale, 1e20 * scale, 1e-14 * diag_mean)
        stopping = replace(stopping, tol_inf=tol_inf, linear=(HARD_STALL_STEPS, HARD_STALL_GAIN))
    pt, it = levenberg_marquardt(
        start,
        start.moved,
        damping,
        stopping,
        accept="gain" if hard is None else "max_row",
        log=log,
        label=f"rho={rho:g}",
    )
    return pt.x.reshape(X.shape), it


def _solve_full(prob: DesignProblem, log, iters: dict, stalled=None):
    """Penalty LM stages then projection (module docstring); returns ``(X, mode)``. ``stalled(X)``, if given,
    is asked before the stiff restart with the first schedule's end ``X``: an ``(X, mode)`` it returns is the
    answer instead (the restart is most of the time, ``routes._second_opinion``)."""
    req = prob.req

    def eq_max(Y):
        return max((float(np.abs(f.residual(Y)).max()) for f in prob.of("eq")), default=0.0)

    eqs = prob.of("eq")
    fits = exact_fits(prob.of("fit"))

    first = COARSE_PENALTIES if prob.coarse is not None and prob.coarse["used"] else PENALTIES
    best = None
    for attempt, schedule in enumerate((first, STIFF_PENALTIES)):
        tag = "_restart" if attempt else ""
        X = prob.X0.copy()
        for rho, stall_tol, cap in schedule:
            X, k = _lm(prob, X, rho, min(cap, req.max_iter), log, stall_tol=stall_tol)
            iters[f"lm_rho_{rho:g}{tag}"] = k
            log(f"rho={rho:g}: {k} iterations, max equality row {eq_max(X):.2e}")
        if attempt == 0 and eq_max(X) > RESTART_ABOVE:
            # the fit dragged the pattern off the constraint manifold into a wall of inequalities:
            # start again keeping the constraints stiff from the first step
            log(f"max equality row {eq_max(X):.2e} > {RESTART_ABOVE:g}: the first schedule stopped")
            if (kept := _instead_of_restart(stalled, X, log)) is not None:
                return _projected(prob, kept, log, iters)
            continue
        Xp, mode, kp = _project(prob, X, log, eqs, fits)
        iters[f"projection{tag}"] = kp
        res = family_residuals(prob, Xp, _mean_edge(prob, Xp))
        worst = max((res[f.name] for f in eqs), default=0.0)
        if best is None or worst < best[0]:
            best = (worst, Xp, mode)
        if worst <= req.tol:
            break
        log(f"projection stopped at {worst:.2e} > tol" + ("" if not attempt else ": giving up"))
        if not attempt and (kept := _instead_of_restart(stalled, X, log)) is not None:
            return _projected(prob, kept, log, iters)
    assert best is not None, "the stiff attempt always projects"
    _, X, mode = best
    return X, mode


def _project(prob: DesignProblem, X: np.ndarray, log, eqs: list, fits: list):
    """Projection onto c = 0 (and s = 0 when the fit is nearly exact); returns X, mode, iterations."""
    req = prob.req
    L = _mean_edge(prob, X)
    tol_abs = lambda fams: min(req.tol * L**f.dim for f in fams)  # noqa: E731
    fit_rel = max((float(np.abs(f.residual(X)).max()) / L for f in fits), default=0.0)
    if fits and fit_rel < 1e-2:
        # the least-squares fit is (nearly) exact: try to make it exact
        Xh, kh = _lm(
            prob,
            X,
            0.0,
            50,
            log,
            hard=eqs + fits + prob.of("ineq"),
            tol_inf=0.1 * tol_abs(eqs + fits),
        )
        if all(v <= req.tol for v in family_residuals(prob, Xh, _mean_edge(prob, Xh)).values()):
            return Xh, "hard", kh
    Xp, kp = _lm(prob, X, 0.0, 50, log, hard=eqs + prob.of("ineq"), tol_inf=0.1 * tol_abs(eqs))
    if max((float(np.abs(f.residual(Xp)).max()) for f in eqs), default=0.0) > 0.1 * tol_abs(eqs):
        # the half margins may block the last steps: project on the equalities alone (steps that
        # would violate g >= 0 are still halved or refused)
        Xq, kq = _lm(prob, Xp, 0.0, 50, log, hard=eqs, tol_inf=0.1 * tol_abs(eqs))
        return Xq, "least-squares", kp + kq
    return Xp, "least-squares", kp


def _projected(prob: DesignProblem, kept: tuple, log, iters: dict) -> tuple:
    """``kept`` (``(X, mode)``, a valid rigid-family member, equalities at about 1e-13) after a few Gauss-Newton
    steps on the equalities alone, where they lower its worst row and leave it valid (the schedules' own
    projections end near 1e-14)."""
    Xp, kp = _lm(prob, kept[0], 0.0, PROJECT_KEPT, log, hard=prob.of("eq"), tol_inf=0.0)
    iters["projection_kept"] = kp

    def worst(Y):
        res = family_residuals(prob, Y, _mean_edge(prob, Y))
        return max((res[f.name] for f in prob.of("eq")), default=0.0)

    if worst(Xp) < worst(kept[0]) and _ineq_values(prob, Xp).min(initial=0.0) >= 0.0:
        return Xp, kept[1]
    return kept


def _instead_of_restart(stalled, X: np.ndarray, log):
    """``stalled(X)`` of the first schedule's end ``X`` where the caller gave one, else None: the restart."""
    kept = None if stalled is None else stalled(X)
    if kept is None:
        log("restarting with stiff penalties")
    return kept
