"""Inverse design inside the closed-form rigid-deployable family (``rigid.py``).

For ``--rigid`` with rhombus holes every equality family (edge pairs of both
closed states, hinge sums) holds identically on the family ``x(S, ψ)``, so the
problem left is small and unconstrained but for the inequalities:

    min_p  |s(x)|² + w E_reg(x) + ρ |min(0, g(x) - m)|²,   x = x(p), p = (S, ψ),

with 2(M+N+2)+1 unknowns instead of 2V. It is solved by Levenberg-Marquardt
with dense normal matrices ``Dᵀ (JᵀJ) D`` (``D = ∂x/∂p``; ``JᵀJ`` stays sparse
in node space, so the large regulariser block is never formed densely), with
the same step limiting on the inequalities as the full solver. When the fit
comes out nearly exact, minimum-norm Gauss-Newton steps on the fit rows make
it exact ("hard" shape matching). The caller (``solve.py``) checks every family
on the result and falls back to the full solver when a check fails.
"""

from __future__ import annotations

import numpy as np
from scipy import sparse

from .constraints import Family
from .rigid import RigidFamily

# (penalty weight, stall tolerance, iteration cap) per stage, softest first as in the full solver: a stiff
# inequality wall from the start leaves LM crawling along it (16x16 rigid circle: 300 iterations to a
# 1.3 mm fit at 1e4 alone, 74 to an exact fit from 1e2). Near an exact fit the tiny regulariser is
# minimised along the curved fit manifold, where LM crawls too: a stage stops after 3 steps in a row that
# each gain less than its stall tolerance, and the hard-fit projection finishes.
STAGES = ((1e2, 1e-3, 200), (1e4, 1e-6, 40))
# The first stage can run from two starts that differ only in LM's damping: Marquardt (diag JᵀJ) and
# Levenberg (identity) scaling reach different local minima, and neither is always better (rigid 16x16:
# heart 13.3 mm vs 0.43 mm, circle exact vs 0.04 mm). The second runs only when the first misses the
# target by more than ``miss_tol`` of its size; the better merit is kept.
SCALINGS = ("marquardt", "levenberg")
# A result that violates an inequality (g < 0: a coarse-to-fine start can leave a reflex corner that the fit
# holds against any penalty; 32x32 rigid ellipse from a coarse start) ranks below every feasible one, and
# the other scaling is tried as well.
MAX_STALL = 3


class _Merit:
    """Stacked residuals of the reduced problem and their node-space Jacobians."""

    def __init__(self, fam: RigidFamily, families: list[Family], margin: dict, reg_weight: float,
                 rho: float = STAGES[0][0], scaling: str = "marquardt"):
        self.fam = fam
        self.nf = fam.n_seeds
        self.fits = [f for f in families if f.kind == "fit"]
        self.regs = [f for f in families if f.kind == "reg"]
        self.ineqs = [f for f in families if f.kind == "ineq"]
        self.margin = margin
        self.w = float(np.sqrt(reg_weight))
        self.sq = float(np.sqrt(rho))
        self.scaling = scaling

    def unpack(self, p: np.ndarray):
        nf = self.nf
        return np.stack([p[:nf], p[nf:2 * nf]], -1), float(p[-1])

    def nodes(self, p: np.ndarray) -> np.ndarray:
        S, psi = self.unpack(p)
        return self.fam.nodes(S, psi)

    def ineq_violation(self, X: np.ndarray) -> float:
        return max(0.0, -min((float(f.residual(X).min(initial=np.inf)) for f in self.ineqs), default=0.0))

    def rows(self, X: np.ndarray, hard: bool = False):
        """Residual vector and node-space Jacobian (CSR) of the merit, or of the hard-fit rows."""
        rs, Js = [], []
        for f in self.fits:
            r, J = f(X)
            rs.append(r)
            Js.append(J)
        if not hard:
            for f in self.regs:
                r, J = f(X)
                rs.append(self.w * r)
                Js.append(self.w * J)
        for f in self.ineqs:
            r, J = f(X)
            m = self.margin[f.name] * (0.5 if hard else 1.0)
            v = r - m
            act = np.flatnonzero(v < 0)
            if len(act):
                s = 1.0 if hard else self.sq
                rs.append(s * v[act])
                Js.append(s * J[act])
        return np.concatenate(rs), sparse.vstack(Js, format="csr")


def fit_miss(fits: list[Family], X: np.ndarray) -> float:
    """Largest |fit row| relative to its target's size (both in normalised units)."""
    return max((float(np.abs(f.residual(X)).max()) / f.meta["target"].size for f in fits), default=0.0)


# below this many entries in the reduced Jacobian J D it is formed densely (measured, 1 thread: 8x8 0.14 ms
# vs 0.55 ms through the sparse JᵀJ, 32x32 15 vs 24 ms; 64x64, 1.7e7 entries, 181 vs 150 ms)
DENSE_JD = 4e6


def _normal(J: sparse.csr_matrix, r: np.ndarray, D: np.ndarray):
    """Reduced Gauss-Newton matrix ``Dᵀ JᵀJ D`` and gradient ``Dᵀ Jᵀ r``."""
    if J.shape[0] * D.shape[1] <= DENSE_JD:
        JD = J @ D
        return JD.T @ JD, JD.T @ r
    H = (J.T @ J).tocsr()
    return D.T @ (H @ D), D.T @ (J.T @ r)


def _lm(merit: _Merit, p: np.ndarray, max_iter: int, stall_tol: float, log):
    """Levenberg-Marquardt on the merit; returns ``p, X, iterations``."""
    fam = merit.fam
    X = merit.nodes(p)
    r, J = merit.rows(X)
    D = fam.jacobian(*merit.unpack(p))
    Hr, g = _normal(J, r, D)
    cost = 0.5 * float(r @ r)
    gviol = merit.ineq_violation(X)
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
            Xn = merit.nodes(p + dp)
            gviol_n = merit.ineq_violation(Xn)
            if gviol_n <= gviol + 1e-15:
                break
            dp = 0.5 * dp
        rn, Jn = merit.rows(Xn)
        cn = 0.5 * float(rn @ rn)
        pred = -(float(g @ dp) + 0.5 * float(dp @ (Hr @ dp)))
        ratio = (cost - cn) / pred if pred > 0 else -1.0
        if np.isfinite(cn) and gviol_n <= gviol + 1e-15 and ratio > 1e-4:
            small = (cost - cn) <= stall_tol * max(cost, 1e-300)
            p, X, r, J, cost, gviol = p + dp, Xn, rn, Jn, cn, gviol_n
            D = fam.jacobian(*merit.unpack(p))
            Hr, g = _normal(J, r, D)
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
    return p, X, it


def solve_reduced(fam: RigidFamily, X0: np.ndarray, psi0: float, families: list[Family], margin: dict,
                  reg_weight: float, fit_tol: float, mean_edge, log, max_iter: int = 200,
                  miss_tol: float = 0.0):
    """Fit within the rigid family from the member nearest ``X0`` at ``psi0``.

    ``mean_edge(X)`` gives the length unit of the 1 % "nearly exact" threshold.
    Returns ``(X, mode, iterations)`` with ``mode`` "hard" when the fit rows were
    driven to ``fit_tol`` (absolute, normalised units), else "least-squares".
    """
    S0, _ = fam.fit(X0, psi0)
    p0 = np.concatenate([S0[:, 0], S0[:, 1], [psi0]])
    iters: dict = {}
    best = None
    judge = _Merit(fam, families, margin, reg_weight, STAGES[-1][0])
    for scaling in SCALINGS:
        p = p0
        for n, (rho, stall_tol, cap) in enumerate(STAGES):
            merit = _Merit(fam, families, margin, reg_weight, rho, scaling if n == 0 else "marquardt")
            p, X, k = _lm(merit, p, min(cap, max_iter), stall_tol, log)
            iters[f"reduced_{scaling}_rho_{rho:g}"] = k
            fit_max = max((float(np.abs(f.residual(X)).max()) for f in merit.fits), default=0.0)
            if merit.fits and fit_max < 1e-2 * mean_edge(X):
                Xh, kh = _hard_fit(merit, p, fit_tol)
                iters[f"reduced_{scaling}_hard"] = kh
                if Xh is not None:  # an exact fit: nothing left to compare
                    return Xh, "hard", iters
        r, _ = judge.rows(X)
        cost = float(r @ r)
        miss = fit_miss(merit.fits, X)
        viol = judge.ineq_violation(X)
        log(f"reduced ({scaling} start): merit {cost:.4e}, fit misses by {miss:.3%} of the target size"
            + (f", an inequality violated by {viol:.2e}" if viol > 0 else ""))
        if best is None or (viol > 0, cost) < best[0]:
            best = ((viol > 0, cost), X)
        if miss <= miss_tol and not viol > 0:
            break
    return best[1], "least-squares", iters


def _hard_fit(merit: _Merit, p: np.ndarray, fit_tol: float, max_iter: int = 40):
    """Damped Gauss-Newton on the fit rows (plus half-margin inequality rows): ``X, iterations``.

    The fit rows are fewer than the unknowns, so with little damping a step is close to the
    minimum-norm one; the damping falls tenfold after every step that lowers the sum of squares
    (without a new inequality violation) and rises tenfold otherwise.
    ``X`` is None when the rows could not be brought under ``fit_tol``.
    """
    fam = merit.fam
    X = merit.nodes(p)
    gviol = merit.ineq_violation(X)
    r, J = merit.rows(X, hard=True)
    Jr = J @ fam.jacobian(*merit.unpack(p))
    scale = max(float((Jr * Jr).sum(0).mean()), 1e-300)
    mu = 1e-12 * scale
    for it in range(1, max_iter + 1):
        if np.abs(r).max(initial=0.0) <= fit_tol:
            return X, it - 1
        dp = -np.linalg.solve(Jr.T @ Jr + mu * np.eye(len(p)), Jr.T @ r)
        for _ in range(6):
            Xn = merit.nodes(p + dp)
            gviol_n = merit.ineq_violation(Xn)
            if gviol_n <= gviol + 1e-15:
                break
            dp = 0.5 * dp
        rn, Jn = merit.rows(Xn, hard=True)
        if gviol_n <= gviol + 1e-15 and float(rn @ rn) < float(r @ r):
            p, X, r, gviol = p + dp, Xn, rn, gviol_n
            Jr = Jn @ fam.jacobian(*merit.unpack(p))
            mu = max(mu / 10.0, 1e-14 * scale)
        else:
            mu *= 10.0
            if mu > 1e4 * scale:
                break
    return (X if np.abs(r).max(initial=0.0) <= fit_tol else None), it
