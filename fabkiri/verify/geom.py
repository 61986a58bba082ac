"""Vectorised geometry the verifier needs on top of :mod:`fabkiri.pattern.geometry`."""

from __future__ import annotations

import numpy as np
import shapely

from ..kdtree import KDTree
from ..pattern import geometry
from ..pattern.overlap import (  # noqa: F401  (re-exported: the verifier's callers import these from here)
    convex,
    overlap_depths,
    sat_penetration,
    tile_polygons,
)


def tile_kabsch(source: np.ndarray, target: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Per-tile proper rigid fit of ``source`` (T, n, 2) onto ``target``.

    Returns the rotation angle of every tile ``(T,)`` and the largest corner
    residual after the fit ``(T,)``.
    """
    theta = geometry.kabsch_angles(source, target)
    moved = geometry.rotate(
        source - source.mean(axis=1, keepdims=True), theta[:, None]
    ) + target.mean(axis=1, keepdims=True)
    return theta, np.linalg.norm(moved - target, axis=-1).max(axis=1)


def point_segment_distance(p: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    ab = b - a
    L2 = geometry.dot2(ab, ab)
    t = np.clip(
        np.divide(geometry.dot2(p - a, ab), L2, out=np.zeros_like(L2), where=L2 > 0), 0.0, 1.0
    )
    return np.linalg.norm(a + t[..., None] * ab - p, axis=-1)


def max_overlap_depth(
    corners: np.ndarray, is_convex: np.ndarray | None = None
) -> tuple[float, tuple[int, int] | None]:
    """Largest overlap between any two tiles (see :func:`overlap_depths`) and the pair."""
    i, j, depth = overlap_depths(corners, is_convex)
    if len(depth) == 0:
        return 0.0, None
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
        theta = geometry.kabsch_angles(p, q)
        moved = geometry.rotate(source[:, k] - pc, theta) + qc
        out = np.maximum(out, np.linalg.norm(moved - target[:, k], axis=-1))
    return out


def snap_corners(corners: np.ndarray, eps: float) -> np.ndarray:
    """Corners closer than ``eps`` (transitively) moved onto one representative."""
    from scipy import sparse
    from scipy.sparse import csgraph

    pts = corners.reshape(-1, 2)
    pairs = KDTree(pts).query_pairs(eps, output_type="ndarray")
    if len(pairs) == 0:
        return corners.copy()
    n = len(pts)
    g = sparse.coo_matrix((np.ones(len(pairs)), (pairs[:, 0], pairs[:, 1])), shape=(n, n))
    _, label = csgraph.connected_components(g, directed=False)
    first = np.full(label.max() + 1, -1)
    first[label[::-1]] = np.arange(n)[::-1]
    return pts[first[label]].reshape(corners.shape)


def _edge_matched(snapped: np.ndarray) -> bool:
    """True if, after snapping, every tile edge is either unshared or shared by
    exactly one other tile in the opposite direction (a conforming coverage)."""
    pts = snapped.reshape(-1, 2)
    _, vid = np.unique(pts, axis=0, return_inverse=True)
    vid = vid.reshape(snapped.shape[:2])
    a, b = vid.ravel(), np.roll(vid, -1, axis=1).ravel()
    if (a == b).any():
        return False
    directed = a.astype(np.int64) * (vid.max() + 1) + b
    if len(np.unique(directed)) != len(directed):
        return False  # the same directed edge twice: two tiles on one side
    return True


def tiles_union(corners: np.ndarray, eps: float, coverage: bool = True) -> shapely.Geometry:
    """Union of tiles robust to rounding: corners within ``eps`` are snapped first.

    A conforming coverage (no overlaps — the caller says so with ``coverage`` —
    and full shared edges, the rhombus case) uses GEOS coverage union, which is
    exact and fast; anything else (T-junctions,
    self-intersecting tiles) the general overlay.
    """
    S = snap_corners(corners, eps)
    polys = shapely.polygons(S)
    valid = shapely.is_valid(polys)
    if coverage and valid.all() and _edge_matched(S):
        try:
            u = shapely.coverage_union_all(polys)
        except shapely.errors.GEOSException:  # not noded as a coverage (T-junctions)
            u = None
        # trust it only when it is what a gap-free, overlap-free coverage gives
        if (
            u is not None
            and u.is_valid
            and u.geom_type == "Polygon"
            and not len(u.interiors)
            and abs(u.area - shapely.area(polys).sum()) <= 1e-9 * u.area
        ):
            return u
    if not valid.all():
        polys = polys.copy()
        polys[~valid] = shapely.make_valid(polys[~valid])
    return shapely.union_all(polys)
