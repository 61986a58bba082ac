"""Periodic cubic interpolating spline (C²), evaluated piece by piece.

The same curve as scipy's ``CubicSpline(x, y, bc_type="periodic")`` with ``PPoly`` evaluation, built
here because ``scipy.interpolate`` (which pulls in ``scipy.optimize`` and ``scipy.special``) was about a
tenth of a second of every design command's start-up. The slopes come from the cyclic tridiagonal
C²-continuity system, solved with SuperLU (``scipy.sparse.linalg``, loaded by the lattice topology anyway).
"""

from __future__ import annotations

import numpy as np
from scipy import sparse
from scipy.sparse.linalg import spsolve


class PeriodicCubic:
    """Piecewise cubic on breakpoints ``x`` (K+1, increasing), coefficients ``c`` (4, K, dim).

    Piece i is ``c[0, i] t³ + c[1, i] t² + c[2, i] t + c[3, i]`` with ``t = u - x[i]``, ``u`` taken
    modulo the period ``x[-1] - x[0]`` (``PPoly``'s layout, so a similar copy scales ``c``).
    """

    def __init__(self, c: np.ndarray, x: np.ndarray):
        self.c = np.asarray(c, dtype=float)
        self.x = np.asarray(x, dtype=float)

    @classmethod
    def interpolate(cls, x: np.ndarray, y: np.ndarray) -> PeriodicCubic:
        """The C² periodic spline through ``y`` (K+1, dim) at ``x``; ``y[0]`` must equal ``y[-1]``."""
        x = np.asarray(x, dtype=float)
        y = np.asarray(y, dtype=float)
        h = np.diff(x)
        delta = np.diff(y, axis=0) / h[:, None]
        K = len(h)
        hp = np.roll(h, 1)  # interval before each knot
        dp = np.roll(delta, 1, axis=0)
        # knot i: h_i s_{i-1} + 2 (h_{i-1} + h_i) s_i + h_{i-1} s_{i+1} = 3 (h_i δ_{i-1} + h_{i-1} δ_i)
        i = np.arange(K)
        A = sparse.csc_matrix(
            (
                np.concatenate([h, 2 * (hp + h), hp]),
                (np.tile(i, 3), np.concatenate([(i - 1) % K, i, (i + 1) % K])),
            ),
            shape=(K, K),
        )
        rhs = 3 * (h[:, None] * dp + hp[:, None] * delta)
        s = np.asarray(spsolve(A, rhs)).reshape(K, -1)
        s1 = np.roll(s, -1, axis=0)
        hh = h[:, None]
        c = np.stack([(s + s1 - 2 * delta) / hh**2, (3 * delta - 2 * s - s1) / hh, s, y[:-1]])
        return cls(c, x)

    def __call__(self, u, nu: int = 0) -> np.ndarray:
        """Value (``nu`` = 0) or ``nu``-th derivative (1, 2) at ``u``."""
        x, c = self.x, self.c
        u = np.asarray(u, dtype=float)
        flat = x[0] + np.mod(u.ravel() - x[0], x[-1] - x[0])
        i = np.clip(np.searchsorted(x, flat, side="right") - 1, 0, len(x) - 2)
        t = (flat - x[i])[:, None]
        # the pieces' coefficients: ``take`` makes indexing's copies without its general indexing
        a, b, d, e = c.take(i, axis=1)
        if nu == 0:
            out = ((a * t + b) * t + d) * t + e
        elif nu == 1:
            out = (3 * a * t + 2 * b) * t + d
        elif nu == 2:
            out = 6 * a * t + 2 * b
        else:
            raise ValueError(f"derivative order {nu} not supported")
        return out.reshape(*u.shape, c.shape[2])

    def value_and_derivatives(self, u: np.ndarray):
        """Value, first and second derivative at ``u`` (one interval lookup for the three)."""
        x, c = self.x, self.c
        u = np.asarray(u, dtype=float)
        flat = x[0] + np.mod(u.ravel() - x[0], x[-1] - x[0])
        i = np.clip(np.searchsorted(x, flat, side="right") - 1, 0, len(x) - 2)
        t = (flat - x[i])[:, None]
        a, b, d, e = c.take(i, axis=1)
        a3t = 3 * a * t
        shape = (*u.shape, c.shape[2])
        return (
            (((a * t + b) * t + d) * t + e).reshape(shape),
            ((a3t + 2 * b) * t + d).reshape(shape),
            (2 * a3t + 2 * b).reshape(shape),
        )
