"""Which four points of a target the lattice's corners go to, and how many rows and columns, for an
outline the default split cannot take (an L: the pattern's harmonic map onto it folds tiles).

The default split (rays from the bounding box's centre to its corners) put an L's reflex corner and
the convex corner beside it on one arc: the lattice's side had to run into the pocket and out again, and
every guess ran across it instead (21-33 % Hausdorff). An L is a strip bent once: with the lattice's
corners at the strip's two ends and as many rows as the strip is long in tile widths, the reflex corner
sits alone on the inner arc and the fold-free start (:mod:`.inverse_map`) bends the lattice round it.

The candidates are the default split and every four of the outline's convex sharp vertices, in CCW
order; each is scored by its fold-free start's :func:`distortion`; the least wins: the start the solver has least
to move.
"""

from __future__ import annotations

from itertools import combinations

import numpy as np

from ...pattern import geometry
from ...pattern.kinds.quad.lattice import standard_pattern
from ..core.stencils import Stencils
from ..targets.curve import Target
from .initial import harmonic_map, scale_for
from .inverse_map import TargetMesh, sharp_params, with_corners

MAX_CANDIDATES = 40  # vertex quadruples scored at most (an outline with many sharp corners: a star)
# a re-split keeps at least this share of the tiles it is given
SHAPE_BUDGET = 0.8
# and is taken only when its start's distortion falls below this share of the own split's: an L
# measured 0.43-0.48 against 1.37-1.44, a crescent 0.50-0.55 against 1.20-1.26, stars 0.55-0.68 against
# 0.82-0.97 (kept on their own split)
RESPLIT_GAIN = 0.5
# rows and columns of a re-split lattice: an L's strip 3 tiles across (card-0.3 at 120 mm, 12x3) fitted
# (2.57 %) but overlapped 30 times while deploying; 4 across (16x4) deployed rigidly, collision-free
MIN_ACROSS = 4
NEXT_COUNT = {4: 6, 6: 8, 8: 12}  # make's N x N counts to the next one up (at most its 12x12)


def _stencils(rows: int, cols: int) -> tuple[np.ndarray, Stencils]:
    sp = standard_pattern(rows, cols, tile_size=1.0)
    return sp.nodes - sp.nodes.mean(0), Stencils.from_pattern(sp)


def default_folds(target: Target, rows: int, cols: int) -> bool:
    """Whether the pattern's harmonic map onto ``target`` (its own split) folds tiles."""
    base, st = _stencils(rows, cols)
    L0 = scale_for(base, st, target, "rescaled")
    x = harmonic_map(base, st, target.transformed(1.0 / L0))
    return bool((geometry.signed_areas(x[st.tiles]) <= 0).any())


def distortion(mesh: TargetMesh, corners: np.ndarray, rows: int, cols: int) -> float:
    """How far the fold-free start is from a conformal map (a rotating-squares pattern deploys about
    conformally): the mean log ratio of each tile's diagonals plus the spread (standard deviation) of
    the log tile areas; inf where it folds."""
    base, st = _stencils(rows, cols)
    q = mesh.place(base, st.tip_nodes, st.tip_side, corners)[st.tiles]
    area = geometry.signed_areas(q)
    if (area <= 0).any():
        return float("inf")
    d1 = np.linalg.norm(q[:, 2] - q[:, 0], axis=1)
    d2 = np.linalg.norm(q[:, 3] - q[:, 1], axis=1)
    return float(np.abs(np.log(d1 / d2)).mean() + np.log(area).std())


def candidate_splits(target: Target) -> list[np.ndarray]:
    """The default split and every CCW four of the convex sharp vertices (parameters BL, BR, TR, TL;
    one turn of each: the other turns are the same lattice with rows and columns swapped)."""
    u = sharp_params(target)
    p = target.points
    k = np.searchsorted(target._u[:-1], u)
    a, b = p[k] - p[k - 1], p[(k + 1) % len(p)] - p[k]
    convex = u[(a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0]) > 0]
    quads = [np.asarray(q) for q in combinations(np.sort(convex), 4)][:MAX_CANDIDATES]
    return [target.default_corner_split(), *quads]


def best_split(
    target: Target, shapes: list[tuple[int, int]]
) -> tuple[Target, tuple[int, int], float, float]:
    """The target re-split and the ``(rows, cols)`` of ``shapes`` whose fold-free start is least
    distorted, that distortion, and the default split's at ``shapes[0]``."""
    mesh = TargetMesh(target)
    default = target.default_corner_split()
    best = (target, shapes[0], distortion(mesh, default, *shapes[0]))
    first = best[2]
    for c in candidate_splits(target):
        for rc in shapes:
            d = distortion(mesh, c, *rc)
            if d < best[2]:
                best = (with_corners(target, c), rc, d)
    return (*best, first)


def lattice_shapes(n: int) -> list[tuple[int, int]]:
    """Every R x C (both at least :data:`MIN_ACROSS`) of :data:`SHAPE_BUDGET` to all of ``n`` tiles."""
    out = []
    for c in range(MIN_ACROSS, n // MIN_ACROSS + 1):
        r = n // c
        if r >= MIN_ACROSS and r * c >= SHAPE_BUDGET * n:
            out.append((r, c))
    return out


def bent_strip(
    target: Target, rows: int, cols: int
) -> tuple[Target, tuple[int, int], float, float] | None:
    """The re-split target, its ``(rows, cols)``, distortion and the own split's, when the pattern's
    harmonic map onto ``target``'s own split folds tiles at ``rows`` x ``cols`` and a re-split's start is
    distorted less than :data:`RESPLIT_GAIN` times the own split's: over the shapes of these tiles, else
    of the next standard count's (a strip :data:`MIN_ACROSS` tiles across needs about as many tiles as
    it is long in widths; the design's fabrication rows still hold every tile's width). None: keep it."""
    if not default_folds(target, rows, cols):
        return None
    up = NEXT_COUNT.get(rows) if rows == cols else None
    for n in [rows * cols] + ([up * up] if up else []):
        split, tiles, d, d0 = best_split(target, [(rows, cols), *lattice_shapes(n)])
        if split is not target and d <= RESPLIT_GAIN * d0:
            return split, tiles, d, d0
    return None
