"""Vectorised geometry the verifier needs on top of :mod:`fabkiri.pattern.geometry`."""

from __future__ import annotations

import numpy as np
import shapely
from scipy.spatial import cKDTree

from ..pattern import geometry


def tile_kabsch(source: np.ndarray, target: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Per-tile proper rigid fit of ``source`` (T, n, 2) onto ``target``.

    Returns the rotation angle of every tile ``(T,)`` and the largest corner
    residual after the fit ``(T,)``.
    """
    pc = source.mean(axis=1, keepdims=True)
    qc = target.mean(axis=1, keepdims=True)
    p0, q0 = source - pc, target - qc
    theta = np.arctan2(geometry.cross2(p0, q0).sum(1), geometry.dot2(p0, q0).sum(1))
    moved = geometry.rotate(p0, theta[:, None]) + qc
    return theta, np.linalg.norm(moved - target, axis=-1).max(axis=1)


def point_segment_distance(p: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    ab = b - a
    L2 = geometry.dot2(ab, ab)
    t = np.clip(np.divide(geometry.dot2(p - a, ab), L2, out=np.zeros_like(L2), where=L2 > 0), 0.0, 1.0)
    return np.linalg.norm(a + t[..., None] * ab - p, axis=-1)


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


def overlap_pairs(polys: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Pairs ``i < j`` of touching or overlapping polygons and their intersection areas."""
    tree = shapely.STRtree(polys)
    i, j = tree.query(polys, predicate="intersects")
    keep = i < j
    i, j = i[keep], j[keep]
    areas = shapely.area(shapely.intersection(polys[i], polys[j])) if len(i) else np.zeros(0)
    return i, j, areas


def convex(corners: np.ndarray) -> np.ndarray:
    """Which CCW quads are strictly convex, ``(T,)``."""
    nxt = np.roll(corners, -1, axis=1) - corners
    return (geometry.cross2(nxt, np.roll(nxt, -1, axis=1)) > 0).all(axis=1)


def sat_penetration(P: np.ndarray, Q: np.ndarray) -> np.ndarray:
    """Penetration depth (mm) of pairs of convex polygons ``(n, k, 2)``; 0 if they only touch.

    Separating-axis test over every edge normal of both polygons: the depth is
    the smallest projected overlap, negative when separated.
    """
    if len(P) == 0:
        return np.zeros(0)
    edges = np.concatenate([np.roll(P, -1, 1) - P, np.roll(Q, -1, 1) - Q], axis=1)  # (n, 2k, 2)
    normals = np.stack([-edges[..., 1], edges[..., 0]], -1)
    normals /= np.linalg.norm(normals, axis=-1, keepdims=True)
    pp = np.einsum("nad,nkd->nak", normals, P)
    qq = np.einsum("nad,nkd->nak", normals, Q)
    overlap = np.minimum(pp.max(-1), qq.max(-1)) - np.maximum(pp.min(-1), qq.min(-1))
    return np.maximum(overlap.min(axis=1), 0.0)


def max_overlap_depth(corners: np.ndarray, is_convex: np.ndarray | None = None) -> tuple[float, tuple[int, int] | None]:
    """Largest overlap between any two tiles, as a length (mm), and the pair.

    Candidates come from a k-d tree on tile centres; convex pairs use the
    separating-axis depth, others the intersection area divided by the mean
    tile edge.
    """
    T = len(corners)
    if T < 2:
        return 0.0, None
    centres = corners.mean(axis=1)
    radius = np.linalg.norm(corners - centres[:, None], axis=-1).max()
    pairs = cKDTree(centres).query_pairs(2 * radius * (1 + 1e-9), output_type="ndarray")
    if len(pairs) == 0:
        return 0.0, None
    i, j = pairs.T
    if is_convex is None:
        is_convex = convex(corners)
    both = is_convex[i] & is_convex[j]
    depth = np.zeros(len(i))
    depth[both] = sat_penetration(corners[i[both]], corners[j[both]])
    if (~both).any():
        L = geometry.mean_edge_length(corners)
        pi, _ = tile_polygons(corners[i[~both]])
        pj, _ = tile_polygons(corners[j[~both]])
        depth[~both] = shapely.area(shapely.intersection(pi, pj)) / L
    k = int(np.argmax(depth))
    return float(depth[k]), (int(i[k]), int(j[k]))


def leave_one_out_residual(source: np.ndarray, target: np.ndarray) -> np.ndarray:
    """Per tile, the largest distance of a corner from where the proper rigid fit
    of the *other* corners puts it, ``(T,)``.

    Unlike the all-corner fit residual, which spreads one displaced corner over
    the whole tile (a 0.1 mm move can read as 0.03 mm), this reports a single
    displaced corner at its full displacement.
    """
    n = source.shape[1]
    out = np.zeros(len(source))
    for k in range(n):
        keep = [i for i in range(n) if i != k]
        p, q = source[:, keep], target[:, keep]
        pc, qc = p.mean(axis=1), q.mean(axis=1)
        p0, q0 = p - pc[:, None], q - qc[:, None]
        theta = np.arctan2(geometry.cross2(p0, q0).sum(1), geometry.dot2(p0, q0).sum(1))
        moved = geometry.rotate(source[:, k] - pc, theta) + qc
        out = np.maximum(out, np.linalg.norm(moved - target[:, k], axis=-1))
    return out
