"""Which tiles of a pattern overlap, and how deep (a length): the verifier's measure, which a design's checks
use too (``api/closed_states.overlapping_tiles``), here below both so a design loads none of the verifier."""

from __future__ import annotations

import numpy as np
import shapely

from ..kdtree import KDTree
from . import geometry


def tile_polygons(corners: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Shapely polygons of tiles; invalid (self-intersecting) ones are made valid.

    Returns the polygons and a bool mask of the tiles that had to be repaired.
    """
    polys = shapely.polygons(corners)
    bad = ~shapely.is_valid(polys)
    if bad.any():
        polys = polys.copy()
        polys[bad] = shapely.make_valid(polys[bad])
    return polys, bad


def convex(corners: np.ndarray) -> np.ndarray:
    """Which CCW quads are strictly convex, ``(T,)``."""
    nxt = np.roll(corners, -1, axis=1) - corners
    return np.asarray((geometry.cross2(nxt, np.roll(nxt, -1, axis=1)) > 0).all(axis=1))


def sat_penetration(P: np.ndarray, Q: np.ndarray) -> np.ndarray:
    """Penetration depth (mm) of pairs of convex polygons ``(n, k, 2)``; 0 if they only touch.

    Separating-axis test over every edge normal of both polygons: the depth is
    the smallest projected overlap, negative when separated.
    """
    if len(P) == 0:
        return np.zeros(0)
    edges = np.concatenate([np.roll(P, -1, 1) - P, np.roll(Q, -1, 1) - Q], axis=1)  # (n, 2k, 2)
    norm = np.hypot(edges[..., 0], edges[..., 1])
    nx, ny = -edges[..., 1] / norm, edges[..., 0] / norm  # (n, 2k) unit normals
    k = P.shape[1]
    # projections vertex by vertex: element-wise max/min beat reductions over a tiny axis
    pp = [nx * P[:, i, 0:1] + ny * P[:, i, 1:2] for i in range(k)]
    qq = [nx * Q[:, i, 0:1] + ny * Q[:, i, 1:2] for i in range(k)]
    pmax, pmin, qmax, qmin = pp[0], pp[0], qq[0], qq[0]
    for i in range(1, k):
        pmax, pmin = np.maximum(pmax, pp[i]), np.minimum(pmin, pp[i])
        qmax, qmin = np.maximum(qmax, qq[i]), np.minimum(qmin, qq[i])
    overlap = np.minimum(pmax, qmax) - np.maximum(pmin, qmin)
    return np.maximum(overlap.min(axis=1), 0.0)


def _colmax(a: np.ndarray) -> np.ndarray:
    out = a[:, 0].copy()
    for k in range(1, a.shape[1]):
        np.maximum(out, a[:, k], out=out)
    return out


def _colmin(a: np.ndarray) -> np.ndarray:
    out = a[:, 0].copy()
    for k in range(1, a.shape[1]):
        np.minimum(out, a[:, k], out=out)
    return out


def overlap_depths(
    corners: np.ndarray, is_convex: np.ndarray | None = None
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Candidate tile pairs ``i < j`` and how deep they overlap, as a length (mm).

    Candidates: tile centres closer than the sum of the two circumradii (k-d
    tree). Convex pairs use the separating-axis penetration depth (0 when they
    only touch); other pairs (reflex or self-intersecting tiles) the area of
    their intersection divided by the mean tile edge, an equivalent strip width.
    """
    T = len(corners)
    empty = np.zeros(0, dtype=np.int64)
    if T < 2:
        return empty, empty, np.zeros(0)
    centres = corners.mean(axis=1)
    d = corners - centres[:, None]
    radii = np.sqrt(_colmax(d[..., 0] ** 2 + d[..., 1] ** 2))
    pairs = KDTree(centres).query_pairs(2 * radii.max() * (1 + 1e-9), output_type="ndarray")
    if len(pairs) == 0:
        return empty, empty, np.zeros(0)
    i, j = pairs.T
    near = np.linalg.norm(centres[i] - centres[j], axis=1) <= (radii[i] + radii[j]) * (1 + 1e-9)
    i, j = i[near], j[near]
    if is_convex is None:
        is_convex = convex(corners)
    both = is_convex[i] & is_convex[j]
    depth = np.zeros(len(i))
    # one cheap axis first: the overlap of the projections on the centre line
    # bounds the penetration depth from above; pairs that are apart or just
    # touching there (most of them) need no full separating-axis test
    P, Q = corners[i], corners[j]
    axis = centres[j] - centres[i]
    axis /= np.maximum(np.linalg.norm(axis, axis=1, keepdims=True), 1e-300)
    ax, ay = axis[:, 0:1], axis[:, 1:2]
    pp = P[..., 0] * ax + P[..., 1] * ay
    qq = Q[..., 0] * ax + Q[..., 1] * ay
    bound = np.minimum(_colmax(pp), _colmax(qq)) - np.maximum(_colmin(pp), _colmin(qq))
    eps = 1e-10 * float(radii.mean())
    full = both & (bound > eps)
    depth[both] = np.maximum(bound[both], 0.0)
    depth[full] = np.minimum(sat_penetration(P[full], Q[full]), bound[full])
    if (~both).any():
        L = geometry.mean_edge_length(corners)
        pi, _ = tile_polygons(corners[i[~both]])
        pj, _ = tile_polygons(corners[j[~both]])
        depth[~both] = shapely.area(shapely.intersection(pi, pj)) / L
    return i, j, depth
