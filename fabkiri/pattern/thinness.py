"""How thin a pattern's tiles are: the one definition ``design``, ``info``, ``cut`` and ``print`` share.

**Thinnest width** of a convex tile: its minimum width, the smallest distance
between two parallel lines enclosing it. For a convex polygon one of those lines
carries an edge, so it is the smallest altitude

    w(T) = min over edges e of  max over corners j of  dist(j, line e).

A tile *shrunk* by ``d`` (every edge moved inward by ``d``, mitre corners: the
ligament sheet's gap/2, the printer's gap/2) has the same edge directions; its
corner ``j`` moves by ``d · m_j`` with the mitre vector ``m_j = (n_a + n_b) / (1 + n_a·n_b)``
(``n`` the inward unit normals of the two edges at ``j``). At scale ``s`` its
distances are ``s · h_je - d (1 - n_e·m_j)``, linear in ``s``, so the smallest
scale at which every shrunk tile is at least ``w`` wide (and keeps four edges)
has a closed form (:func:`min_scale`). Pure numpy, millimetres or any unit.
"""

from __future__ import annotations

from functools import cached_property, lru_cache

import numpy as np
from scipy import sparse
from scipy.sparse import csgraph

from .geometry import cross2, dot2

EDGE_EPS_MM = 1e-6  # a shrunk edge shorter than this is gone
WEB_SLACK_MM = (
    1e-5  # web checks forgive this much: cut files snap every coordinate to a 1e-6 mm grid
)


def _frame(corners: np.ndarray):
    """Per tile and edge ``e`` (corner e to e+1): unit direction ``u``, inward normal ``n``, length."""
    E = np.roll(corners, -1, axis=-2) - corners
    L = np.linalg.norm(E, axis=-1)
    u = E / np.where(L > 0, L, 1.0)[..., None]
    n = np.stack([-u[..., 1], u[..., 0]], -1)  # inward for counter-clockwise tiles
    return u, n, L


def _mitres(n: np.ndarray) -> np.ndarray:
    """Mitre vector of every corner: corner j moves by ``d · m_j`` when the tile shrinks by ``d``."""
    na = np.roll(n, 1, axis=-2)  # edge j-1 -> j
    nb = n  # edge j -> j+1
    return (na + nb) / (1.0 + dot2(na, nb))[..., None]


def _distances(corners: np.ndarray, n: np.ndarray):
    """``h[t, e, j]``: distance of corner j from the line of edge e (positive inside)."""
    rel = (
        corners[..., None, :, :] - corners[..., :, None, :]
    )  # (T, e, j, 2): corner j minus corner e
    return dot2(rel, n[..., :, None, :])


def widths(corners: np.ndarray, shrink: float = 0.0) -> np.ndarray:
    """Thinnest width of every tile ``(T, n, 2)`` (CCW), after shrinking by ``shrink``.

    A tile that loses an edge when shrunk (or is not counter-clockwise) gets width 0. A non-convex tile
    is measured the same way, over all its edges' lines: the linear measure :func:`min_scale` inverts.
    """
    corners = np.asarray(corners, dtype=float)
    u, n, L = _frame(corners)
    h = _distances(corners, n)
    if shrink:
        m = _mitres(n)
        h = h - shrink * (1.0 - dot2(n[..., :, None, :], m[..., None, :, :]))
    w = h.max(-1).min(-1)
    ccw = cross2(corners, np.roll(corners, -1, axis=-2)).sum(-1) > 0
    ok = (shrunk_edges(corners, shrink) > EDGE_EPS_MM * (shrink > 0)).all(-1) & ccw
    return np.where(ok, np.maximum(w, 0.0), 0.0)


def shrunk_edges(corners: np.ndarray, shrink: float) -> np.ndarray:
    """Signed length of every edge once the tile is shrunk by ``shrink`` ``(T, n)``."""
    u, n, L = _frame(corners)
    if not shrink:
        return L
    m = _mitres(n)
    return L + shrink * dot2(u, np.roll(m, -1, axis=-2) - m)


def shrunk_quads(corners: np.ndarray, shrink: float) -> np.ndarray:
    """Corners of every tile shrunk by ``shrink`` (mitre), in corner order (valid while its edges last)."""
    corners = np.asarray(corners, dtype=float)
    if not shrink:
        return corners.copy()
    return corners + shrink * _mitres(_frame(corners)[1])


def shrunk_tiles(corners: np.ndarray, shrink: float) -> tuple[np.ndarray, np.ndarray]:
    """:func:`shrunk_quads` and :func:`shrunk_edges` of the same tiles, their frames computed once."""
    corners = np.asarray(corners, dtype=float)
    u, n, L = _frame(corners)
    if not shrink:
        return corners.copy(), L
    m = _mitres(n)
    return corners + shrink * m, L + shrink * dot2(u, np.roll(m, -1, axis=-2) - m)


def min_scale(
    corners: np.ndarray, width: float, shrink: float = 0.0, min_edge: float = 0.0
) -> tuple[float, int, str]:
    """Smallest scale ``s`` at which every tile of ``s · corners``, shrunk by ``shrink`` (not scaled),
    is at least ``width`` wide and keeps four edges at least ``min_edge`` long (and > ``EDGE_EPS_MM``);
    ``(s, tile, reason)`` with the tile that sets it.

    Exact: distances and shrunk edge lengths are linear in ``s`` (module docstring), so each tile's
    threshold is ``max_e min_j (width + b_je) / a_je`` (and the edges' own), no search.
    """
    return TileScales(corners)(width, shrink, min_edge)


class TileScales:
    """:func:`min_scale` of one placed state for many widths and shrinks: the tiles' frames, distances
    and mitre terms, which do not depend on them, computed once, and each answer kept (the fabricability
    summary asks for every material's web and every printer's gap, some alike)."""

    def __init__(self, corners: np.ndarray) -> None:
        corners = np.asarray(corners, dtype=float)
        self.n_tiles = len(corners)
        self.answers: dict[tuple, tuple[float, int, str]] = {}
        if not self.n_tiles:
            return
        self.u, self.n, self.L = _frame(corners)
        self.a = _distances(corners, self.n)  # (T, e, j)

    @cached_property
    def losses(self) -> tuple[np.ndarray, np.ndarray]:
        """Per unit shrink, what each corner-to-edge distance and each edge's length lose (a shrink's)."""
        u, n = self.u, self.n
        m = _mitres(n)
        return 1.0 - dot2(n[..., :, None, :], m[..., None, :, :]), dot2(
            u, np.roll(m, -1, axis=-2) - m
        )

    def __call__(
        self, width: float, shrink: float = 0.0, min_edge: float = 0.0
    ) -> tuple[float, int, str]:
        key = (width, shrink, min_edge)
        if key not in self.answers:
            self.answers[key] = self._answer(width, shrink, min_edge)
        return self.answers[key]

    def _answer(self, width: float, shrink: float, min_edge: float) -> tuple[float, int, str]:
        T = self.n_tiles
        if T == 0:
            return 0.0, -1, ""
        a, L = self.a, self.L
        b = shrink * self.losses[0] if shrink else np.zeros_like(a)
        with np.errstate(divide="ignore", invalid="ignore"):
            need = np.where(a > 0, (width + b) / a, np.inf)
        s_width = need.min(-1).max(-1)  # (T,)
        s_edges = np.zeros(T)
        if shrink:
            loss = -shrink * self.losses[1]  # shrunk edge = s L - loss
            with np.errstate(divide="ignore", invalid="ignore"):
                s_edges = np.where(L > 0, (loss + max(min_edge, EDGE_EPS_MM)) / L, np.inf).max(-1)
        s = np.maximum(s_width, s_edges)
        t = int(np.argmax(s))
        reason = "width" if s_width[t] >= s_edges[t] else "edge"
        return float(s[t]), t, reason


def polygon_width(points: np.ndarray) -> float:
    """Thinnest width of the convex hull of ``points`` ``(n, 2)``, any number of corners (the same
    definition as :func:`widths`: min over hull edges of the largest distance from that edge's line)."""
    from ..kdtree import ConvexHull

    pts = np.unique(np.asarray(points, dtype=float), axis=0)
    if len(pts) < 3:
        return 0.0
    try:
        hull = pts[ConvexHull(pts).vertices]
    except Exception:  # collinear points: no area, no width
        return 0.0
    E = np.roll(hull, -1, axis=0) - hull
    n = np.stack([-E[:, 1], E[:, 0]], -1) / np.linalg.norm(E, axis=1, keepdims=True)
    rel = hull[None, :, :] - hull[:, None, :]  # [e, j]: corner j minus corner e
    return float(np.abs(np.einsum("ejd,ed->ej", rel, n)).max(1).min())


def hinge_corner_distances(corners: np.ndarray, hinge_tiles: np.ndarray, hinge_corner: np.ndarray):
    """Closest pair of hinges on one tile: ``(distance, tile)``, ``(inf, -1)`` if no tile has two."""
    T, n = corners.shape[:2]
    has = np.zeros((T, n), dtype=bool)
    has[hinge_tiles.ravel(), hinge_corner.ravel()] = True
    d = np.linalg.norm(corners[:, :, None, :] - corners[:, None, :, :], axis=-1)
    pair = has[:, :, None] & has[:, None, :] & ~np.eye(n, dtype=bool)[None]
    d = np.where(pair, d, np.inf).min((1, 2))
    t = int(np.argmin(d)) if T else -1
    return (float(d[t]), t) if T and np.isfinite(d[t]) else (float("inf"), -1)


def measures(corners: np.ndarray, hinge_tiles: np.ndarray, hinge_corner: np.ndarray) -> dict:
    """Thinnest tile, shortest edge and closest hinge pair of one placed state (its units)."""
    w = widths(corners)
    L = np.linalg.norm(np.roll(corners, -1, axis=-2) - corners, axis=-1)
    hd, ht = hinge_corner_distances(corners, hinge_tiles, hinge_corner)
    t, e = divmod(int(np.argmin(L)), corners.shape[1])
    return {
        "thinnest_tile_mm": float(w.min()),
        "thinnest_tile": int(np.argmin(w)),
        "shortest_edge_mm": float(L.min()),
        "shortest_edge_tile": t,
        "closest_hinge_pair_mm": hd if np.isfinite(hd) else None,
        "closest_hinge_pair_tile": ht,
    }


def pal_bound(n_tiles: int, width: float) -> float:
    """Least total area of ``n_tiles`` convex tiles each at least ``width`` wide (Pál: a convex set of
    minimum width w has area at least w²/√3, the equilateral triangle's)."""
    return n_tiles * width * width / np.sqrt(3.0)


def cross_signs_ok(corners: np.ndarray) -> bool:
    """Every tile convex and counter-clockwise (the widths above assume it)."""
    E = np.roll(corners, -1, axis=-2) - corners
    return bool((cross2(E, np.roll(E, -1, axis=-2)) > 0).all())


# ------------------------------------------------------------------ printed strips (closed form)
# A printed strip of hinge h (``fabkiri.fabricate.print.geometry.strip_outlines``) crosses its closed seam: along
# the seam it spans ``[t0, t0 + w]`` from the hinge point (t0 where the seam enters the pair of tiles shrunk
# by d), across it reaches ``reach + d`` into each tile. Strips on one face must keep the radial clearance.
# Inside a tile the strip lies in that box (clipped further by the tile), so the separation of two boxes is
# a lower bound on the strips' distance; along any axis it is linear in the scale (the box has a fixed size
# in mm, its anchor moves with the pattern), which gives the smallest scale in closed form.


def hinge_of_corner(
    hinge_tiles: np.ndarray, hinge_corner: np.ndarray, n_tiles: int, arity: int = 4
) -> np.ndarray:
    """``(T, arity)`` hinge at each tile corner, -1 where there is none."""
    out = np.full((n_tiles, arity), -1, dtype=np.int64)
    H = len(hinge_tiles)
    out[hinge_tiles[:, 0], hinge_corner[:, 0]] = np.arange(H)
    out[hinge_tiles[:, 1], hinge_corner[:, 1]] = np.arange(H)
    return out


def coincident_hinges(
    hinge_tiles: np.ndarray, hinge_corner: np.ndarray, fold_ends: np.ndarray, n_tiles: int
) -> np.ndarray:
    """Hinge pairs that meet in a closed state by its fold rule (the far ends of a folded seam are one
    node, and each may carry a hinge): ``(P, 2)``, each pair once, lower index first."""
    hc = hinge_of_corner(hinge_tiles, hinge_corner, n_tiles)
    a = hc[hinge_tiles[:, 0], fold_ends[:, 0]]
    b = hc[hinge_tiles[:, 1], fold_ends[:, 1]]
    ok = (a >= 0) & (b >= 0) & (a != b)
    pairs = np.sort(np.stack([a[ok], b[ok]], 1), axis=1)
    return unique_pairs(pairs, len(hinge_tiles))


def unique_pairs(pairs: np.ndarray, n: int) -> np.ndarray:
    """``np.unique(pairs, axis=0)`` of index pairs ``(P, 2)`` in ``range(n)`` (int64): one integer per pair
    sorted, as the rows sort, without the row-wise sort of ``axis=0``."""
    pairs = np.asarray(pairs, dtype=np.int64).reshape(-1, 2)
    key = np.unique(pairs[:, 0] * np.int64(n) + pairs[:, 1])
    return np.stack([key // n, key % n], 1)


def hinge_faces(top_, state: int, contracted) -> tuple[np.ndarray, bool]:
    """``strip_faces`` of the hinges that meet in closed state ``state`` and in each closed state of
    ``contracted`` (a topology's, a pattern's), and whether two hinges that meet got the same face."""
    folds = [top_.fold(s).fold_corner_ends for s in (1, 2) if s == state or s in contracted]
    pairs = np.concatenate(
        [coincident_hinges(top_.hinge_tiles, top_.hinge_corner, f, top_.n_tiles) for f in folds]
    )
    face = strip_faces(unique_pairs(pairs, top_.n_hinges), top_.n_hinges)
    return face, bool(len(pairs) and (face[pairs[:, 0]] == face[pairs[:, 1]]).any())


def strip_faces(pairs: np.ndarray, n_hinges: int) -> np.ndarray:
    """Face per hinge (0 top, 1 bottom): hinges that meet go on opposite faces, the lowest of each group on
    top (the two-colouring ``fabkiri.fabricate.cut.hinges.assign_faces`` makes from the placed states).

    The last few answers are kept: a design's fabricability summary asks the same for every printer preset."""
    pairs = np.ascontiguousarray(pairs, dtype=np.int64).reshape(-1, 2)
    return _strip_faces(pairs.tobytes(), int(n_hinges)).copy()


@lru_cache(maxsize=8)
def _strip_faces(pairs_bytes: bytes, n_hinges: int) -> np.ndarray:
    """A breadth-first search from the lowest hinge of each group gives every hinge the face opposite to
    the one it is reached from, so the parity of its depth, whatever the order of the search (an odd
    cycle included): the depths of one search from an extra node joined to each group's lowest hinge."""
    pairs = np.frombuffer(pairs_bytes, dtype=np.int64).reshape(-1, 2)
    H = n_hinges
    if not len(pairs):
        return np.zeros(H, dtype=np.int64)
    g = sparse.coo_matrix((np.ones(len(pairs)), (pairs[:, 0], pairs[:, 1])), shape=(H, H))
    _, group = csgraph.connected_components(g, directed=False)
    lowest = np.full(group.max() + 1, H)
    np.minimum.at(lowest, group, np.arange(H))
    rows = np.concatenate([pairs[:, 0], np.full(len(lowest), H)])
    cols = np.concatenate([pairs[:, 1], lowest])
    joined = sparse.coo_matrix((np.ones(len(rows)), (rows, cols)), shape=(H + 1, H + 1))
    depth = csgraph.shortest_path(joined.tocsr(), directed=False, unweighted=True, indices=H)[:H]
    return (depth.astype(np.int64) - 1) % 2


def same_face_pairs(hinge_tiles: np.ndarray, face: np.ndarray, n_tiles: int):
    """Every two hinges on one tile and one face: ``(tile, h, side_h, k, side_k)`` arrays (side 0: the tile
    is the hinge's tile A, 1: its tile B)."""
    H = len(hinge_tiles)
    t = hinge_tiles.ravel()
    h = np.repeat(np.arange(H), 2)
    side = np.tile([0, 1], H)
    order = np.lexsort((h, t))
    t, h, side = t[order], h[order], side[order]
    # every two entries of one tile (i < j in the sorted order), by tile, then i, then j
    most = int(np.bincount(t, minlength=1).max(initial=0)) if len(t) else 0
    i = np.concatenate([np.arange(len(t) - d) for d in range(1, most)] or [np.zeros(0, np.int64)])
    j = np.concatenate([np.arange(d, len(t)) for d in range(1, most)] or [np.zeros(0, np.int64)])
    keep = (t[i] == t[j]) & (face[h[i]] == face[h[j]])
    i, j = i[keep], j[keep]
    order = np.lexsort((j, i))
    i, j = i[order], j[order]
    arr = np.stack([t[i], h[i], side[i], h[j], side[j]], 1).astype(np.int64).reshape(-1, 5)
    return tuple(arr.T)


def strip_frames(
    corners: np.ndarray,
    hinge_tiles: np.ndarray,
    hinge_corner: np.ndarray,
    fold_ends: np.ndarray,
    shrink: float,
):
    """Per hinge of a placed closed state: hinge point ``p`` (H, 2), seam direction ``e`` (H, 2), the
    normal into tile A and into tile B ``n`` (H, 2, 2), and ``t0`` (H,) where the seam enters the pair of
    tiles shrunk by ``shrink`` (mitre: ``shrink / sin`` of the sharper of the two corners at the hinge)."""
    A, B = hinge_tiles.T
    p = 0.5 * (corners[A, hinge_corner[:, 0]] + corners[B, hinge_corner[:, 1]])
    far = 0.5 * (corners[A, fold_ends[:, 0]] + corners[B, fold_ends[:, 1]])
    e = far - p
    e = e / np.linalg.norm(e, axis=1, keepdims=True)
    perp = np.stack([-e[:, 1], e[:, 0]], -1)
    n = np.empty((len(p), 2, 2))
    sines = []
    for side, (X, c) in enumerate(((A, hinge_corner[:, 0]), (B, hinge_corner[:, 1]))):
        centre = corners[X].mean(1)
        sgn = np.sign(dot2(centre - p, perp))
        n[:, side] = perp * np.where(sgn == 0, 1.0, sgn)[:, None]
        here = corners[X, c]
        k = corners.shape[1]
        u = corners[X, (c + 1) % k] - here
        v = corners[X, (c - 1) % k] - here
        sines.append(np.abs(cross2(u, v)) / (np.linalg.norm(u, axis=1) * np.linalg.norm(v, axis=1)))
    t0 = shrink / np.maximum(np.minimum(*sines), 1e-12)
    return p, e, n, t0


def _box_extent(
    axis: np.ndarray, e: np.ndarray, n: np.ndarray, a0: np.ndarray, a1: float, b1: float
):
    """min and max over the box ``{a e + b n: a in [a0, a0 + a1], b in [0, b1]}`` of its dot with ``axis``."""
    ea, nb = dot2(e, axis), dot2(n, axis)
    lo = a0 * ea + a1 * np.minimum(ea, 0.0) + b1 * np.minimum(nb, 0.0)
    hi = a0 * ea + a1 * np.maximum(ea, 0.0) + b1 * np.maximum(nb, 0.0)
    return lo, hi


def strip_clearance_scales(
    corners: np.ndarray,
    hinge_tiles: np.ndarray,
    hinge_corner: np.ndarray,
    fold_ends: np.ndarray,
    pairs: tuple,
    shrink: float,
    width: float,
    reach: float,
    clearance: float,
) -> np.ndarray:
    """Per same-face pair (:func:`same_face_pairs`) the smallest scale from which their boxes on the shared
    tile are at least ``clearance`` apart along one of the four box axes (separating-axis gap, a lower
    bound on the distance): linear in the scale per axis, so exact for the boxes; 0 where no scale brings
    them closer."""
    tile, h, sh, k, sk = pairs
    if not len(tile):
        return np.zeros(0)
    p, e, n, t0 = strip_frames(corners, hinge_tiles, hinge_corner, fold_ends, shrink)
    R = reach + shrink
    nh, nk = n[h, sh], n[k, sk]
    upper = np.full(
        len(tile), np.inf
    )  # the boxes are closer than the clearance along every axis for s in
    lower = np.full(len(tile), -np.inf)  # (lower, upper): each axis' gap is linear in s
    for axis in (e[h], nh, e[k], nk):
        lo_h, hi_h = _box_extent(axis, e[h], nh, t0[h], width, R)
        lo_k, hi_k = _box_extent(axis, e[k], nk, t0[k], width, R)
        dp = dot2(p[k] - p[h], axis)
        for slope, off in (
            (dp, lo_k - hi_h),
            (-dp, lo_h - hi_k),
        ):  # k beyond h along the axis, or before
            with np.errstate(divide="ignore", invalid="ignore"):
                root = (clearance - off) / slope
            upper = np.where(slope > 0, np.minimum(upper, root), upper)
            lower = np.where(slope < 0, np.maximum(lower, root), lower)
            lower = np.where(
                (slope == 0) & (off >= clearance), np.inf, lower
            )  # this axis always separates
    return np.where(lower < upper, np.maximum(upper, 0.0), 0.0)
