"""The quad (rotating-squares) tessellation: its fold rules and its registry entry.

The topology module finds hinges, gaps and holes for any tile arity; what is quad about a quad
kirigami is here: the fold rule of the two closed states (spec §2, the primal and dual edge
correspondences) and the standard lattice of :mod:`fabkiri.pattern.lattice`.
"""

from __future__ import annotations

import numpy as np

from ..errors import PatternError
from .lattice import standard_pattern
from .tessellation import Tessellation, register
from .topology import STATES, FoldRule, Topology


def quad_fold_rule(top: Topology, state: int) -> FoldRule:
    """Rotating squares: in state 1 every hinge folds the gap on the ``prev`` side of its even tile,
    in state 2 the other gap; every hole then folds at two opposite corners."""
    tiles = top.tiles
    A, B = top.hinge_tiles.T
    cA, cB = top.hinge_corner.T
    a_even = top.even_tiles()[A]
    fold_gap = np.where(a_even, 0, 1) if state == 1 else np.where(a_even, 1, 0)
    # gap 0: (prev_A, next_B); gap 1: (next_A, prev_B)
    end_cA = np.where(fold_gap == 0, (cA + 3) % 4, (cA + 1) % 4)
    end_cB = np.where(fold_gap == 0, (cB + 1) % 4, (cB + 3) % 4)
    fold_ends = np.stack([tiles[A, end_cA], tiles[B, end_cB]], -1)

    K = top.n_holes
    hole_folds = fold_gap[top.hole_hinges] == top.hole_gap if K else np.zeros((0, 4), bool)
    if K:
        alternating = (hole_folds == np.array([True, False, True, False])).all(1) | (
            hole_folds == np.array([False, True, False, True])
        ).all(1)
        if not alternating.all():
            bad = int(np.flatnonzero(~alternating)[0])
            raise PatternError(
                f"hole {bad} (nodes {top.hole_nodes[bad].tolist()}) does not fold at two opposite "
                f"corners in state {state}: not a rotating-squares quad tessellation"
            )
    # merge corners: the two corners where this hole does not fold
    merge = np.argsort(hole_folds, axis=1, kind="stable")[:, :2] if K else np.zeros((0, 2), int)
    mh = np.take_along_axis(top.hole_hinges, merge, 1) if K else np.zeros((0, 2), int)
    ring_tiles = top.hinge_tiles[mh].reshape(K, 4)
    ring_corners = top.hinge_corner[mh].reshape(K, 4)
    rings = np.stack([ring_tiles, ring_corners], -1)
    return FoldRule(
        state=state,
        fold_gap=fold_gap.astype(np.int64),
        fold_ends=fold_ends,
        fold_corner_ends=np.stack([end_cA, end_cB], -1),
        hole_folds=hole_folds,
        rings=rings,
    )


QUAD = register(
    Tessellation(
        kind="quad",
        arity=4,
        hole_arity=4,
        states=STATES,
        fold_rule=quad_fold_rule,
        standard=standard_pattern,
        boundary_sides=("B", "R", "T", "L"),
        rigid_family=True,
    )
)
