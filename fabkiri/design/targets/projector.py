"""Projection of points onto a target curve's arcs or the whole curve (:meth:`Target.project`): the nearest
seed from a KD-tree, the foot from it (Newton on a spline, the nearest of neighbouring segments on a
polyline), the signed distance and its gradient, and the rule for a point as far from two stretches."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from ...pattern.geometry import dot2

if TYPE_CHECKING:
    from .curve import Target

ARC_PAD = 0.1  # fraction of an arc's parameter range its feet may pass its ends by
# a point on the whole curve as far from two of its stretches as this (of the size, well above round-off)
# takes the foot further along (``Projector._tie_broken``); the nearest seeds tried for a second stretch
TIE_TOL = 1e-9
TIE_SEEDS = 6
_OFFSETS = np.array([-1, 0, 1])  # a polyline foot's neighbouring segments and periods


class Projector:
    """Projection of points on fixed arcs onto a target (see :meth:`Target.project`)."""

    def __init__(self, target: Target, side: np.ndarray):
        self.target = target
        self.side = side
        self.whole = side < 0
        lo, hi = np.full(len(side), -np.inf), np.full(len(side), np.inf)
        on = ~self.whole
        s = side[on]
        a = target.corners[s]
        b = target.corners[(s + 1) % 4] + (s == 3)
        # the foot may slide a little past the arc's ends: a tip at a split point is then measured
        # to the curve itself, which is smooth there, not to a clamped end point (a cone in the
        # distance, which turned Gauss-Newton's quadratic convergence into linear at corner tips)
        pad = ARC_PAD * (b - a)
        lo[on], hi[on] = a - pad, b + pad
        self.lo, self.hi = lo, hi
        self.any_whole, self.all_whole = bool(self.whole.any()), bool(self.whole.all())
        # the trees for these corners, fetched once (not on every call of a constraint family)
        self.index = target._arc_index()
        self._gap: float | None = None

    def __call__(self, p: np.ndarray):
        """``(u, foot, d, n)`` as :meth:`Target.project` returns them."""
        tgt = self.target
        tree, us, lift, whole, whole_u, a, b = self.index
        q = (p - b) / a
        if self.all_whole:
            u = whole_u[whole.query(q)[1]]
        elif self.any_whole:
            u = np.empty(len(p))
            u[self.whole] = whole_u[whole.query(q[self.whole])[1]]
            on = ~self.whole
            u[on] = us[tree.query(np.column_stack([q[on], self.side[on] * lift]))[1]]
        else:
            u = us[tree.query(np.column_stack([q, self.side * lift]))[1]]
        u, foot, n = _feet(tgt, p, u, self.lo, self.hi)
        d, grad = _distance(p, foot, n, tgt.size)
        if self.all_whole and len(p):
            return self._tie_broken(p, q, u, foot, d, grad)
        return u, foot, d, grad

    def _seed_gap(self) -> float:
        """``TIE_SEEDS`` of the whole curve's largest seed spacings (in the parameter): the nearest seeds of
        one stretch lie within it of their foot, so a seed farther away lies on another stretch."""
        if self._gap is None:
            us = np.sort(np.mod(self.index[4], 1.0))
            self._gap = TIE_SEEDS * float(np.diff(np.r_[us, us[0] + 1.0]).max())
        return self._gap

    def _tie_broken(self, p, q, u, foot, d, grad):
        """``(u, foot, d, grad)`` with one rule where a point is as far (within ``TIE_TOL`` of the size) from two
        stretches of the curve: the foot further along the curve (counter-clockwise, the shorter way round).

        On the curve's medial axis the distance has two feet, and the nearest seed picked one by round-off: a
        chord midpoint on the axis of the symmetric heart, above its cusp, went to the left or the right lobe
        as the BLAS kernels rounded, and the 16x16 heart's fit to one of two minima (1.42 % or 4.65 % off).
        The rule is a convention (the mean of both gradients, the symmetric subgradient, kept the symmetric
        start symmetric and ended 14.5 % off; the foot of lower or higher parameter 4.64 % and 2.50 %)."""
        tgt = self.target
        whole, whole_u = self.index[3], self.index[4]
        k = min(TIE_SEEDS, len(whole_u))
        # the nearest seeds, from either stretch
        seeds = whole_u[whole.query(q, k=k)[1]].reshape(len(p), k)
        # only seeds on another stretch than the foot found (``_seed_gap`` away), ahead of it
        ahead = np.mod(seeds - u[:, None], 1.0)
        at, col = np.nonzero((ahead < 0.5) & (ahead > self._seed_gap()))
        if not len(at):
            return u, foot, d, grad
        uk, fk, nk = _feet(tgt, p[at], seeds[at, col], self.lo[at], self.hi[at])
        dk, gk = _distance(p[at], fk, nk, tgt.size)
        tol = TIE_TOL * max(tgt.size, 1e-300)
        apart = np.sqrt(dot2(fk - foot[at], fk - foot[at]))
        ok = (np.abs(np.abs(dk) - np.abs(d[at])) <= tol) & (apart > 1e3 * tol)
        ok &= np.mod(uk - u[at], 1.0) < 0.5  # its foot ahead too
        if not ok.any():
            return u, foot, d, grad
        u, foot, d, grad = u.copy(), foot.copy(), d.copy(), grad.copy()
        # one foot per point: the farthest such where several are
        sel = np.flatnonzero(ok)
        sel = sel[np.lexsort((-apart[sel], at[sel]))]
        sel = sel[np.r_[True, at[sel][1:] != at[sel][:-1]]]
        rows = at[sel]
        u[rows], foot[rows], d[rows], grad[rows] = uk[sel], fk[sel], dk[sel], gk[sel]
        return u, foot, d, grad


def _feet(tgt: Target, p: np.ndarray, u: np.ndarray, lo: np.ndarray, hi: np.ndarray):
    """``(u, foot, outward unit normal)`` of the points ``p`` from the seeds ``u``, each within ``[lo, hi]``."""
    if tgt.kind == "spline":
        u, foot, d1 = tgt._newton_foot(p, u, lo, hi)
        n = np.stack([d1[:, 1], -d1[:, 0]], -1)
        return u, foot, n / np.sqrt(dot2(n, n))[:, None]
    u, foot = tgt._polyline_foot(p, u, lo, hi)
    return u, foot, tgt._normal(u, foot)


def _clip(x, lo, hi):
    """``np.clip`` for finite ``x`` without its per-call overhead (most of a small projection's time)."""
    return np.minimum(np.maximum(x, lo), hi)


def _length(d: np.ndarray) -> np.ndarray:
    """Length of each 2-vector of ``d`` (``np.linalg.norm`` over the last axis, without its overhead)."""
    return np.sqrt(dot2(d, d))


def _distance(p, foot, n, size: float):
    """Signed distance of ``p`` from its ``foot`` (outward normal ``n``: positive outside) and its gradient."""
    diff = p - foot
    dist = np.sqrt(dot2(diff, diff))
    sgn = np.where(dot2(diff, n) >= 0, 1.0, -1.0)
    safe = dist > 1e-13 * max(size, 1e-300)
    grad = np.where(safe[:, None], (sgn / np.where(safe, dist, 1.0))[:, None] * diff, n)
    return sgn * dist, grad
