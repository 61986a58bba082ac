"""A fold-free start for a non-convex target: the harmonic map of the target onto the lattice's rectangle,
inverted (Tutte's theorem: a map onto a convex boundary does not fold, whatever the target's shape).

The pattern's own harmonic map (``initial.harmonic_map``) pins the tips on a non-convex target and folds
tiles at its reflex corners (an L folded 2 of 64). Here the target is meshed instead, its boundary is
pinned onto the unit square (arc B on the bottom, R on the right, ...), every inner mesh node is the mean
of its neighbours, and each pattern node is placed where the mesh's image holds its place in the square.

Corner-aware: along each arc the target's sharp vertices (an L's reflex corner and the convex corner
beside it) are sent to the nearest boundary tip of that side, so a tip starts on each of them and the
chords do not start across a pocket; between them the arc goes by arc length.
"""

from __future__ import annotations

import numpy as np
import shapely
from scipy import sparse
from scipy.sparse.linalg import splu

from ...kdtree import KDTree
from ...pattern import geometry
from ..targets.curve import Target

SHARP_DEG = 20.0  # a vertex turning by more than this is a corner a tip should start on
MESH_STEPS = 48  # mesh spacing: the target's size over this
# where the map folds a tile, the target meshed this many times finer in turn: a strip's tiles across a
# narrow band (an S, 4 to 8 across 14 mm) are finer than the mesh, and its interpolation folded them
MESH_REFINE = (2, 4)


def sharp_params(target: Target) -> np.ndarray:
    """Parameters of the polyline vertices turning by more than ``SHARP_DEG`` (none for a spline)."""
    if target.kind != "polyline":
        return np.zeros(0)
    p = target.points
    a, b = p - np.roll(p, 1, 0), np.roll(p, -1, 0) - p
    turn = np.arctan2(a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0], (a * b).sum(1))
    return target._u[:-1][np.abs(np.degrees(turn)) > SHARP_DEG]


def _arc_fraction(target: Target, side: int, u: np.ndarray, tip_f: np.ndarray) -> np.ndarray:
    """Fraction along side ``side`` of the square for curve parameters ``u`` on arc ``side``: by arc
    length, bent so each sharp vertex inside the arc lands on the nearest tip fraction ``tip_f``."""
    lo, hi = target.arc_range(side)
    g = (u - lo) / (hi - lo)
    knots_g, knots_f = [0.0], [0.0]
    for s in np.sort((np.mod(sharp_params(target) - lo, 1.0)) / (hi - lo)):
        if not 0.02 < s < 0.98:
            continue  # the arc's own ends (the lattice corners) or outside it
        free = tip_f[(tip_f > knots_f[-1] + 1e-9) & (tip_f < 1.0 - 1e-9)]
        if len(free):
            knots_g.append(float(s))
            knots_f.append(float(free[np.argmin(np.abs(free - s))]))
    knots_g.append(1.0)
    knots_f.append(1.0)
    return np.interp(g, knots_g, knots_f)


def _square_point(side: int, f: np.ndarray) -> np.ndarray:
    return [
        np.column_stack([f, 0 * f]),
        np.column_stack([1 + 0 * f, f]),
        np.column_stack([1 - f, 1 + 0 * f]),
        np.column_stack([0 * f, 1 - f]),
    ][side]


def _mesh(target: Target, steps: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Nodes, triangles and the boundary nodes' curve parameters (the first ``len(u)`` nodes)."""
    h = target.size / steps
    n = max(int(np.ceil(2 * np.pi * target.size / h)), 64)  # generous: the perimeter over h or more
    u = np.linspace(0.0, 1.0, n, endpoint=False)
    u = np.unique(np.concatenate([u, np.mod(target.corners, 1.0), sharp_params(target)]))
    edge = target.point(u)
    poly = shapely.Polygon(edge)
    lo, hi = target.bbox
    gx, gy = np.meshgrid(np.arange(lo[0] + h / 2, hi[0], h), np.arange(lo[1] + h / 2, hi[1], h))
    inner = np.column_stack([gx.ravel(), gy.ravel()])
    keep = shapely.contains_xy(poly, inner[:, 0], inner[:, 1])
    inner = inner[keep]
    keep = shapely.distance(shapely.points(inner), poly.exterior) > 0.4 * h
    nodes = np.vstack([edge, inner[keep]])
    from scipy.spatial import Delaunay  # here: scipy.spatial costs a plain design's start-up

    tri = Delaunay(nodes).simplices
    c = nodes[tri].mean(1)
    return nodes, tri[shapely.contains_xy(poly, c[:, 0], c[:, 1])], u


def with_corners(target: Target, corners: np.ndarray) -> Target:
    """``target`` split at other corners (parameters BL, BR, TR, TL)."""
    return Target(target.name, target.kind, target.points, corners=corners, source=target.source)


def _locate(img: np.ndarray, tri: np.ndarray, q: np.ndarray, k: int = 16):
    """Triangle and barycentric weights of each point ``q`` in the triangulated image ``img``: the
    containing triangle among the ``k`` nearest centroids, else the least outside one."""
    _, near = KDTree(img[tri].mean(1)).query(q, k=min(k, len(tri)))
    a, b, c = (img[tri[near, j]] for j in range(3))
    v0, v1, v2 = b - a, c - a, q[:, None, :] - a
    det = v0[..., 0] * v1[..., 1] - v0[..., 1] * v1[..., 0]
    det = np.where(np.abs(det) < 1e-15, np.nan, det)
    wb = (v2[..., 0] * v1[..., 1] - v2[..., 1] * v1[..., 0]) / det
    wc = (v0[..., 0] * v2[..., 1] - v0[..., 1] * v2[..., 0]) / det
    w = np.stack([1 - wb - wc, wb, wc], -1)
    score = np.nan_to_num(w.min(-1), nan=-np.inf)
    best = np.argmax(score, 1)
    rows = np.arange(len(q))
    wbest = np.clip(w[rows, best], 0.0, None)
    return tri[near[rows, best]], wbest / wbest.sum(1, keepdims=True)


SQUARE_CORNERS = np.array(
    [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]]
)  # where sides 0..3 start


def square_boundary(
    tgt: Target, u: np.ndarray, tip_q: np.ndarray, tip_side: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """The unit square's points of the boundary nodes at curve parameters ``u`` (each on the arc of its side,
    the tips' fractions ``tip_q`` bending it) and the tips' curve parameters."""
    fixed = np.full((len(u), 2), np.nan)
    tip_u = np.empty(len(tip_side))
    for s in range(4):
        a, b = tgt.arc_range(s)
        uu = np.mod(u - a, 1.0) + a
        on = (uu >= a) & (uu < b)
        tq = tip_q[tip_side == s]
        f_tip = [tq[:, 0], tq[:, 1], 1 - tq[:, 0], 1 - tq[:, 1]][s]
        f = _arc_fraction(tgt, s, uu[on], np.sort(f_tip))
        fixed[on] = _square_point(s, f)
        order = np.argsort(uu[on])  # the tips go on the curve itself, by the same fractions
        tip_u[tip_side == s] = np.interp(
            f_tip, np.append(f[order], 1.0), np.append(uu[on][order], b)
        )
    # a node on a corner where the curve's parameter wraps can fall off both arcs by round-off (the mod
    # above): it is that corner of the square (left unset, the KD-tree of the map refused its NaN)
    off = np.flatnonzero(np.isnan(fixed[:, 0]))
    if len(off):
        starts = np.array([tgt.arc_range(s)[0] for s in range(4)])
        gap = np.abs(np.mod(u[off, None] - starts + 0.5, 1.0) - 0.5)
        fixed[off] = SQUARE_CORNERS[gap.argmin(1)]
    return fixed, tip_u


class TargetMesh:
    """A target meshed once, its inner nodes' Laplacian factorised: the map for any four corners
    (the target's own or others') and any lattice is then two triangular solves and a point search."""

    def __init__(self, target: Target, steps: int = MESH_STEPS):
        self.target = target
        self.nodes, self.tri, self.u = _mesh(target, steps)
        e = np.vstack([self.tri[:, [0, 1]], self.tri[:, [1, 2]], self.tri[:, [2, 0]]])
        e = np.unique(np.sort(e, 1), axis=0)
        n, nb = len(self.nodes), len(self.u)
        # each edge once per direction (the edges are unique): no duplicates to sum
        W = sparse.csr_matrix((np.ones(2 * len(e)), (e.ravel(), e[:, ::-1].ravel())), (n, n))
        L = (sparse.diags(np.asarray(W.sum(1)).ravel()) - W).tocsr()
        # nodes outside every kept triangle (Delaunay's across a pocket) are pinned where they are
        used = np.zeros(n, bool)
        used[self.tri.ravel()] = True
        self.free = np.flatnonzero(used & (np.arange(n) >= nb))
        self.Lfb = L[self.free][:, :nb]
        self.lu = splu(L[self.free][:, self.free].tocsc())

    def place(
        self, base: np.ndarray, tip_nodes: np.ndarray, tip_side: np.ndarray, corners: np.ndarray
    ) -> np.ndarray:
        """Pattern ``base`` (its bounding box read as the square) on the target split at ``corners``."""
        tgt = with_corners(self.target, corners)
        lo, hi = base.min(0), base.max(0)
        q = (base - lo) / (hi - lo)
        fixed, tip_u = square_boundary(tgt, self.u, q[tip_nodes], tip_side)
        img = np.full((len(self.nodes), 2), np.nan)
        img[: len(self.u)] = fixed
        rhs = -(self.Lfb @ fixed)
        img[self.free] = np.column_stack([self.lu.solve(rhs[:, 0]), self.lu.solve(rhs[:, 1])])
        t, w = _locate(img, self.tri, q)
        out = np.einsum("nk,nkd->nd", w, self.nodes[t])
        out[tip_nodes] = tgt.point(tip_u)
        return out


def inverse_harmonic_map(
    base: np.ndarray,
    tip_nodes: np.ndarray,
    tip_side: np.ndarray,
    target: Target,
    tiles: np.ndarray | None = None,
) -> np.ndarray:
    """Pattern ``base`` (its bounding box read as the square) placed on ``target``, fold-free; where
    ``tiles`` (node indices, four a tile) are given and the placement folds one, the target meshed finer
    (:data:`MESH_REFINE`) until it does not, the last placement returned if every one folds."""
    x = TargetMesh(target).place(base, tip_nodes, tip_side, target.corners)
    for k in MESH_REFINE if tiles is not None else ():
        if (geometry.signed_areas(x[tiles]) > 0).all():
            break
        x = TargetMesh(target, k * MESH_STEPS).place(base, tip_nodes, tip_side, target.corners)
    return x
