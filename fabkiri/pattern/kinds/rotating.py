"""The fold rule shared by rotating-polygon kirigami (rotating squares, kagome triangles).

In a rotating-polygon tessellation the tile graph is bipartite and, as the pattern closes, even
tiles turn one way and odd tiles the other, so every hinge closes the gap on the same side of its
even tile: in state 1 the gap on the ``prev`` side of the even tile, in state 2 the other gap.
Around a hole the tiles alternate colour, so each hole folds at every other corner (two opposite
corners of a quad hole, three alternate corners of a kagome hexagon) and its remaining corners,
the *merge corners*, meet at one point of the closed state.
"""

from __future__ import annotations

import numpy as np

from ...errors import PatternError
from ..topology import FoldRule, Topology


def alternating_fold_rule(top: Topology, state: int, *, what: str, fold_at: str) -> FoldRule:
    """The rotating-polygon fold rule of ``top`` in ``state`` for any tile and hole arity.

    ``what`` names the tessellation and ``fold_at`` the corners a hole folds at, for the error
    raised when a hole does not fold at alternate corners (the tiles are not a rotating-polygon
    tessellation of that kind).
    """
    n = top.arity
    m = top.hole_hinges.shape[1]
    tiles = top.tiles
    A, B = top.hinge_tiles.T
    cA, cB = top.hinge_corner.T
    a_even = top.even_tiles()[A]
    fold_gap = np.where(a_even, 0, 1) if state == 1 else np.where(a_even, 1, 0)
    # gap 0: (prev_A, next_B); gap 1: (next_A, prev_B)
    end_cA = np.where(fold_gap == 0, (cA + n - 1) % n, (cA + 1) % n)
    end_cB = np.where(fold_gap == 0, (cB + 1) % n, (cB + n - 1) % n)
    fold_ends = np.stack([tiles[A, end_cA], tiles[B, end_cB]], -1)

    K = top.n_holes
    hole_folds = fold_gap[top.hole_hinges] == top.hole_gap if K else np.zeros((0, m), bool)
    if K:
        odd = np.arange(m) % 2 == 1
        alternating = (hole_folds == ~odd).all(1) | (hole_folds == odd).all(1)
        if not alternating.all():
            bad = int(np.flatnonzero(~alternating)[0])
            raise PatternError(
                f"hole {bad} (nodes {top.hole_nodes[bad].tolist()}) does not fold at {fold_at} "
                f"in state {state}: not a {what} tessellation"
            )
    # merge corners: the m/2 corners where this hole does not fold
    half = m // 2
    merge = (
        np.argsort(hole_folds, axis=1, kind="stable")[:, :half] if K else np.zeros((0, half), int)
    )
    mh = np.take_along_axis(top.hole_hinges, merge, 1) if K else np.zeros((0, half), int)
    ring_tiles = top.hinge_tiles[mh].reshape(K, m)
    ring_corners = top.hinge_corner[mh].reshape(K, m)
    rings = np.stack([ring_tiles, ring_corners], -1)
    return FoldRule(
        state=state,
        fold_gap=fold_gap.astype(np.int64),
        fold_ends=fold_ends,
        fold_corner_ends=np.stack([end_cA, end_cB], -1),
        hole_folds=hole_folds,
        rings=rings,
    )
