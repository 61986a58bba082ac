"""Fold repair of a coarse-to-fine start in the rigid family (``family.py``).

A coarse rigid design's closed-state-1 grid, resampled to the fine lattice, is not a member of the fine
family: its nearest member (least squares over all grid vertices) can fold a few cells, and a member's
deployed tiles are rigid copies of its grid cells, so those tiles fold too (leaf SVG at 32x32: 3 boundary
cells, the start was thrown away and the solve from the rescaled start ended at 13 % Hausdorff; repaired:
0.43 %). When it
folds, the start is instead the member nearest the resampled grid whose cells are all convex with a margin:
a least-squares
fit to the grid plus a penalty on every corner below the margin, by Gauss-Newton with the penalty raised
until no corner is below half the margin.
"""

from __future__ import annotations

import numpy as np

from ...core.stencils import corner_convexity
from .family import RigidFamily

MARGIN = 0.05  # cross(next - v, prev - v) >= MARGIN l^2 at every corner (the solver's own margin is 0.02)
WEIGHTS = 10.0 ** np.arange(0, 9)  # penalty continuation
STEPS = 15  # Gauss-Newton steps per weight


def convex_member(
    fam: RigidFamily, quads: np.ndarray, grid: np.ndarray, normal: bool = False
) -> tuple[np.ndarray, dict]:
    """Seeds ``S`` of the member nearest ``grid`` ``(G, 2)``; when that member folds a cell of ``quads`` (CCW
    grid vertex indices), of the nearest member whose cells are all convex with margin instead. Also a
    summary: corners below the margin and folded cells before, the largest vertex move (in units of the mean
    cell size) and whether the result folds nothing. ``normal``: ``seeds_for_grid``'s."""
    Z = fam.Z
    G, nf = Z.shape
    conv = corner_convexity("unfold", quads, G)
    c = grid[quads]
    l2 = float(np.mean(0.5 * np.abs(_cross(c[:, 2] - c[:, 0], c[:, 3] - c[:, 1]))))
    eps = MARGIN * l2
    S = fam.seeds_for_grid(grid, normal)
    g0 = conv.residual(Z @ S)
    folded = int(_folded(Z @ S, quads).sum())
    info = {
        "corners_below_margin": int((g0 < eps).sum()),
        "folded_cells": folded,
        "move_rel": 0.0,
        "ok": not folded,
    }
    if not folded:
        # a start without folds is left as it is: thin or reflex corners are the solver's to fix, and
        # repairing them too moved the rigid 32x32 heart into a basin with 7 overlapping pairs in state 2
        return S, info
    ZtZ = Z.T @ Z
    A = np.zeros((2 * nf, 2 * nf))
    A[:nf, :nf] = A[nf:, nf:] = ZtZ / l2

    def merit(S, w):
        d = Z @ S - grid
        v = np.minimum(conv.residual(Z @ S) - eps, 0.0) / l2
        return float((d * d).sum()) / l2 + w * float(v @ v)

    for w in WEIGHTS:
        for _ in range(STEPS):
            c = Z @ S
            g, J = conv(c)
            act = g < eps
            if not act.any():
                break
            J = J[act]
            Jr = np.hstack([(J[:, 0::2] @ Z), (J[:, 1::2] @ Z)]) / l2  # ∂(g / l²)/∂(Sx, Sy)
            r = (g[act] - eps) / l2
            d = (c - grid) / l2
            grad = np.concatenate([Z.T @ d[:, 0], Z.T @ d[:, 1]]) + w * Jr.T @ r
            du = -np.linalg.solve(A + w * Jr.T @ Jr + 1e-12 * np.eye(2 * nf), grad)
            m0, t = merit(S, w), 1.0
            while t > 1e-4:
                Sn = S + t * np.stack([du[:nf], du[nf:]], -1)
                if merit(Sn, w) < m0:
                    break
                t *= 0.5
            else:
                break
            S = Sn
        if conv.residual(Z @ S).min() >= 0.5 * eps:
            info["ok"] = True
            break
    info["move_rel"] = float(np.abs(Z @ S - grid).max() / np.sqrt(l2))
    return S, info


def _folded(grid: np.ndarray, quads: np.ndarray) -> np.ndarray:
    c = grid[quads]
    return 0.5 * _cross(c[:, 2] - c[:, 0], c[:, 3] - c[:, 1]) <= 0.0


def _cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]
