"""Constraint residuals of a deployed pattern, evaluated (docs/algorithm.md#constraints).

These are the quantities the inverse design drives to zero, measured here for
reporting: edge pairs and angle rings per closed state, hinge sums for rigid
deployability. Angle residuals are wrapped into (-π, π]; tiles for which
wrapping changed a residual are reported, since that only happens for
self-intersecting or reflex tiles.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from . import geometry
from .model import Pattern

RIGID_TOL_RAD = 1e-9  # hinge sums below this: rigid-deployable


@dataclass(frozen=True, eq=False)
class StateResiduals:
    state: int
    edge_pairs: np.ndarray  # (H,) |l(h,a) - l(h,b)| in mm
    rings: np.ndarray  # (K,) wrapped sum of the merge-corner angles minus 2π
    wrapped_tiles: np.ndarray  # tiles whose angles needed wrapping in some ring


def state_residuals(
    pattern: Pattern, state: int, nodes: np.ndarray | None = None
) -> StateResiduals:
    top = pattern.topology
    x = pattern.nodes if nodes is None else nodes
    fold = top.fold(state)
    h = x[top.hinge_node]
    la = np.linalg.norm(x[fold.fold_ends[:, 0]] - h, axis=1)
    lb = np.linalg.norm(x[fold.fold_ends[:, 1]] - h, axis=1)
    angles = geometry.corner_angles(x[top.tiles])
    if top.n_holes:
        ring_angles = angles[fold.rings[..., 0], fold.rings[..., 1]]
        raw = ring_angles.sum(axis=1) - geometry.TWO_PI
        rings = geometry.wrap_angle(raw)
        needed = np.abs(raw - rings) > np.pi
        suspects = np.unique(fold.rings[needed][..., 0])
        # blame only tiles that are not simple polygons (angle sum != (n-2)π); a
        # ring that is merely far from closing needs no excuse
        simple_sum = (top.arity - 2) * np.pi
        off = np.abs(angles[suspects].sum(axis=1) - simple_sum) > 1e-6
        wrapped = suspects[off]
    else:
        rings, wrapped = np.zeros(0), np.zeros(0, dtype=np.int64)
    return StateResiduals(
        state=state, edge_pairs=np.abs(la - lb), rings=rings, wrapped_tiles=wrapped
    )


def hinge_sums(pattern: Pattern, nodes: np.ndarray | None = None) -> np.ndarray:
    """θ_A(h) + θ_B(h) - π at every hinge, wrapped (zero for rigid deployability)."""
    top = pattern.topology
    x = pattern.nodes if nodes is None else nodes
    angles = geometry.corner_angles(x[top.tiles])
    A, B = top.hinge_tiles.T
    cA, cB = top.hinge_corner.T
    return geometry.wrap_angle(angles[A, cA] + angles[B, cB] - np.pi)
