"""Small vectorised planar-geometry helpers shared by every layer.

All functions take numpy arrays and work on whole batches of tiles at once:
``corners`` is always an array of shape ``(T, 4, 2)`` (tile, corner, xy) with
corners in counter-clockwise order.
"""

from __future__ import annotations

import numpy as np

TWO_PI = 2.0 * np.pi


def cross2(u: np.ndarray, v: np.ndarray) -> np.ndarray:
    """z-component of the cross product of 2D vectors (broadcasting)."""
    return u[..., 0] * v[..., 1] - u[..., 1] * v[..., 0]


def dot2(u: np.ndarray, v: np.ndarray) -> np.ndarray:
    return u[..., 0] * v[..., 0] + u[..., 1] * v[..., 1]


def signed_angle(u: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Signed angle in (-pi, pi] that turns direction ``u`` onto ``v``."""
    return np.arctan2(cross2(u, v), dot2(u, v))


def wrap_angle(a: np.ndarray) -> np.ndarray:
    """Map angles into (-pi, pi]."""
    w = np.mod(np.asarray(a, dtype=float) + np.pi, TWO_PI) - np.pi
    return np.where(w == -np.pi, np.pi, w)


def rotation(theta: np.ndarray) -> np.ndarray:
    """Rotation matrices ``(..., 2, 2)`` for angles ``theta``."""
    c, s = np.cos(theta), np.sin(theta)
    return np.stack([np.stack([c, -s], -1), np.stack([s, c], -1)], -2)


def rotate(points: np.ndarray, theta: np.ndarray | float) -> np.ndarray:
    """Rotate points ``(..., 2)`` by ``theta`` (broadcast over leading axes)."""
    c, s = np.cos(theta), np.sin(theta)
    x, y = points[..., 0], points[..., 1]
    return np.stack([c * x - s * y, s * x + c * y], -1)


def corner_angles(corners: np.ndarray) -> np.ndarray:
    """Interior angle at every corner of CCW quads, in [0, 2*pi).

    The angle at corner k turns the edge to corner k+1 onto the edge to
    corner k-1 counter-clockwise, so a convex CCW tile has angles in (0, pi).
    """
    nxt = np.roll(corners, -1, axis=-2) - corners
    prv = np.roll(corners, 1, axis=-2) - corners
    return np.mod(signed_angle(nxt, prv), TWO_PI)


def edge_lengths(corners: np.ndarray) -> np.ndarray:
    """Length of edge k (corner k to k+1) of every tile, shape ``(T, 4)``."""
    return np.linalg.norm(np.roll(corners, -1, axis=-2) - corners, axis=-1)


def signed_areas(corners: np.ndarray) -> np.ndarray:
    """Shoelace signed area of every polygon; positive when CCW."""
    nxt = np.roll(corners, -1, axis=-2)
    return 0.5 * cross2(corners, nxt).sum(axis=-1)


def mean_edge_length(corners: np.ndarray) -> float:
    """The mean tile edge, the length scale every relative tolerance uses."""
    return float(edge_lengths(corners).mean()) if corners.size else 1.0


def kabsch_angles(source: np.ndarray, target: np.ndarray) -> np.ndarray:
    """Rotation angle of the best proper fit of each polygon onto its target.

    ``source`` and ``target`` are ``(..., n, 2)``; the fit is over the last two
    axes (one rotation per polygon, e.g. per tile), returned as ``(...)``.
    """
    p = source - source.mean(axis=-2, keepdims=True)
    q = target - target.mean(axis=-2, keepdims=True)
    return np.arctan2(cross2(p, q).sum(-1), dot2(p, q).sum(-1))


def kabsch(source: np.ndarray, target: np.ndarray) -> tuple[float, np.ndarray]:
    """Proper rigid motion (no reflection) that best maps ``source`` onto ``target``.

    Returns ``(theta, t)`` with ``target ≈ rotate(source, theta) + t`` in the
    least-squares sense. In 2D the optimal rotation has a closed form.
    """
    p = source.reshape(-1, 2)
    q = target.reshape(-1, 2)
    theta = float(kabsch_angles(p, q))
    t = q.mean(axis=0) - rotate(p.mean(axis=0), theta)
    return theta, t


def aligned_distance(source: np.ndarray, target: np.ndarray) -> float:
    """Largest point distance after the best proper rigid alignment."""
    theta, t = kabsch(source, target)
    moved = rotate(source.reshape(-1, 2), theta) + t
    return float(np.linalg.norm(moved - target.reshape(-1, 2), axis=1).max(initial=0.0))


def self_intersecting_tiles(corners: np.ndarray) -> np.ndarray:
    """Indices of tiles whose outline crosses itself (e.g. bow-tie quads).

    Uses GEOS through shapely: a polygon ring that touches or crosses itself
    is not valid.
    """
    import shapely

    if len(corners) == 0:
        return np.zeros(0, dtype=int)
    polys = shapely.polygons(corners)
    return np.flatnonzero(~shapely.is_valid(polys))


def strictly_convex(polys: np.ndarray) -> np.ndarray:
    """Whether each polygon ``(n, k, 2)`` is strictly convex (every corner turns the same way, none flat):
    a simple polygon with a non-zero area."""
    a = np.roll(polys, -1, 1) - polys
    turn = cross2(a, np.roll(a, -1, 1))
    return np.asarray((turn > 0).all(1) | (turn < 0).all(1))


def clipped_areas(subject: np.ndarray, clip: np.ndarray) -> np.ndarray:
    """Area of ``subject[i] ∩ clip[i]`` (``(n, k, 2)`` each; ``clip`` strictly convex, ``subject`` simple):
    Sutherland-Hodgman, the subject clipped by each edge of the clip polygon in turn, for every pair at once.

    Each polygon is kept as a fixed number of corners, repeated at the end where it has fewer (a repeated
    corner is an edge of length 0: it adds nothing to the clipping or to the area). An edge with every
    corner of a polygon on its inner side leaves that polygon as it is: only the others are clipped by it."""
    orient = np.sign(signed_areas(clip))[:, None]
    P = np.asarray(subject, float)
    if not len(P):
        return np.zeros(0)
    live = np.ones(len(P), dtype=bool)
    k = clip.shape[1]
    for j in range(k):
        c, d = clip[:, j], clip[:, (j + 1) % k]
        f = orient * cross2(
            (d - c)[:, None], P - c[:, None]
        )  # >= 0: on the inner side of edge c -> d
        cut = np.flatnonzero(~(f >= 0).all(1))
        if not len(cut):
            continue
        if len(cut) == len(P):
            P, count = _clip_by_edge(P, f, 1)
            live &= count > 0
            continue
        Pc, count = _clip_by_edge(P[cut], f[cut], P.shape[1])
        live[cut] &= count > 0
        out = np.empty((len(P), Pc.shape[1], 2))
        out[:, : P.shape[1]] = P
        out[:, P.shape[1] :] = P[:, -1:]  # a polygon left as it is, its last corner repeated
        out[cut] = Pc
        P = out
    area = 0.5 * np.abs(cross2(P, np.roll(P, -1, 1)).sum(1))
    return np.where(live, area, 0.0)


def _clip_by_edge(P: np.ndarray, f: np.ndarray, least: int) -> tuple[np.ndarray, np.ndarray]:
    """Polygons ``P`` ``(n, k, 2)`` clipped by the edge whose inner side is ``f >= 0`` (``f`` the corners'
    signed distances): each corner kept where inside, then the point where its edge crosses, if it does.
    The kept points in order, the last repeated up to the most kept or ``least`` (the first point where
    none is kept), and how many each kept."""
    Q = np.roll(P, -1, 1)
    fq = np.roll(f, -1, 1)
    inside, crosses = f >= 0, (f >= 0) != (fq >= 0)
    den = np.where(crosses, f - fq, 1.0)
    cut = P + (Q - P) * (f / den)[..., None]
    pts = np.stack([P, cut], 2).reshape(len(P), -1, 2)  # each corner, then where its edge crosses
    keep = np.stack([inside, crosses], 2).reshape(len(P), -1)
    rank = np.cumsum(keep, 1)
    count = rank[:, -1]
    m = max(int(count.max(initial=0)), least)
    r, col = np.nonzero(keep)
    order = np.zeros((len(P), m), dtype=np.intp)
    order[r, rank[r, col] - 1] = col  # the i-th kept point of each polygon
    last = np.maximum(count - 1, 0)[:, None]
    order = np.take_along_axis(order, np.minimum(np.arange(m), last), 1)
    return np.take_along_axis(pts, order[..., None], 1), count
