"""The reduced problem's two step loops: Levenberg-Marquardt on the merit and the hard-fit projection."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from .reduced import _Merit

MAX_STALL = 3  # a stage stops after this many accepted steps in a row that each gain less than its stall tolerance


def levenberg_marquardt(merit: _Merit, p: np.ndarray, max_iter: int, stall_tol: float, log):
    """Levenberg-Marquardt on the merit; returns ``p, X, iterations``."""
    ev = merit.evaluate(p)
    Hr, g = ev.normal()
    cost = 0.5 * float(ev.r @ ev.r)
    gviol = ev.gviol
    mu = 1e-3
    nu = 2.0
    stall = 0
    it = 0
    for it in range(1, max_iter + 1):
        if merit.scaling == "marquardt":
            d = np.maximum(np.diag(Hr), 1e-12 * max(float(np.diag(Hr).max()), 1e-300))
        else:
            d = np.full(len(g), max(float(np.diag(Hr).mean()), 1e-300))
        try:
            dp = np.linalg.solve(Hr + mu * np.diag(d), -g)
        except np.linalg.LinAlgError:
            mu *= 10.0
            continue
        for _ in range(6):  # step limiting: no new inequality violation
            evn = merit.evaluate(p + dp)
            if evn.gviol <= gviol + 1e-15:
                break
            dp = 0.5 * dp
        cn = 0.5 * float(evn.r @ evn.r)
        pred = -(float(g @ dp) + 0.5 * float(dp @ (Hr @ dp)))
        ratio = (cost - cn) / pred if pred > 0 else -1.0
        if np.isfinite(cn) and evn.gviol <= gviol + 1e-15 and ratio > 1e-4:
            small = (cost - cn) <= stall_tol * max(cost, 1e-300)
            p, ev, cost, gviol = p + dp, evn, cn, evn.gviol
            Hr, g = ev.normal()
            mu *= max(1 / 3, 1 - (2 * ratio - 1) ** 3)
            nu = 2.0
            stall = stall + 1 if small else 0
            if it % 10 == 0:
                log(f"  reduced rho={merit.sq ** 2:g} it {it}: cost {cost:.3e} mu {mu:.1e} ratio {ratio:.2f}")
            if stall >= MAX_STALL:
                break
        else:
            mu *= nu
            nu *= 2.0
            if mu > 1e16:
                break
    return p, ev.X, it


def hard_fit(merit: _Merit, p: np.ndarray, fit_tol: float, max_iter: int = 40):
    """Damped Gauss-Newton on the fit rows (plus half-margin inequality rows): ``X, iterations``.

    The fit rows are fewer than the unknowns, so with little damping a step is close to the
    minimum-norm one; the damping falls tenfold after every step that lowers the sum of squares
    (without a new inequality violation) and rises tenfold otherwise.
    ``X`` is None when the rows could not be brought under ``fit_tol``.
    """
    ev = merit.evaluate(p, hard=True)
    Jr = ev.jacobian()
    scale = max(float((Jr * Jr).sum(0).mean()), 1e-300)
    mu = 1e-12 * scale
    for it in range(1, max_iter + 1):
        r = ev.r
        if np.abs(r).max(initial=0.0) <= fit_tol:
            return ev.X, it - 1
        dp = -np.linalg.solve(Jr.T @ Jr + mu * np.eye(len(p)), Jr.T @ r)
        for _ in range(6):
            evn = merit.evaluate(p + dp, hard=True)
            if evn.gviol <= ev.gviol + 1e-15:
                break
            dp = 0.5 * dp
        if evn.gviol <= ev.gviol + 1e-15 and float(evn.r @ evn.r) < float(r @ r):
            p, ev = p + dp, evn
            Jr = ev.jacobian()
            mu = max(mu / 10.0, 1e-14 * scale)
        else:
            mu *= 10.0
            if mu > 1e4 * scale:
                break
    return (ev.X if np.abs(ev.r).max(initial=0.0) <= fit_tol else None), it
