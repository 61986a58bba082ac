"""Shape conformance: how closely an outline follows a target curve, over the whole outline.

Plain arrays in, plain numbers out, so every layer (design report, ``info``, ``verify``) measures the same
way. Both curves are closed polygons in mm: the outline (the deployed boundary tips in boundary order, or a
closed state's outline) and the target (its polyline vertices, or a dense sampling of its spline).

* **Hausdorff distance** (symmetric) between the two curves: the largest distance from any point of
  either curve to the other curve, so a stretch of the target left uncovered counts as much as a tip off
  the curve. Both curves are sampled at a spacing ``h`` of the size / ``SAMPLES_PER_SIZE`` (vertices
  always included) and measured to the exact segments of the other, so the figure is exact to ``h / 2``.
  Curves longer than ``MAX_SAMPLES * h`` together are both sampled at their length / ``MAX_SAMPLES``
  instead (the figures then exact to half that, ``sampling_mm`` in the result): the memory and time stay
  bounded for any outline.
* **Mean distance** both ways (outline → target, target → outline), over arc length.
* **1 − IoU** of the enclosed regions, |A Δ B| / |A ∪ B| in [0, 1], and |A Δ B| / |target| beside it.
* **Tip spacing**: distances between consecutive outline vertices, min and mean.

The *size* of a target is the larger side of its bounding box (the ``--size`` of ``fabkiri design``);
relative figures are fractions of it.
"""

from __future__ import annotations

import functools

import numpy as np
import shapely

from ..kdtree import KDTree
from .geometry import dot2, kabsch

SAMPLES_PER_SIZE = 4000  # sampling spacing h = size / this: Hausdorff exact to 1.25e-4 of the size
# at most this many samples of the two curves together (and of one by densify): curves longer than 25 sizes
# (an outline far off its target, a diverged design's) are sampled at their length over this instead, and
# the miss measured to that spacing; the nearest-sample queries of points far from a curve visit most of
# its samples, so the count bounds the time as well as the memory
MAX_SAMPLES = 25 * SAMPLES_PER_SIZE
SIZE_DEFINITION = "larger side of the target's bounding box"


def size_of(polygon: np.ndarray) -> float:
    """The size of a closed curve (see the module docstring)."""
    p = np.asarray(polygon, float)
    return float((p.max(0) - p.min(0)).max())


def perimeter(polygon: np.ndarray) -> float:
    """The length of the closed polygon."""
    p = np.asarray(polygon, float)
    return float(_lengths(np.roll(p, -1, 0) - p).sum())


def spacing(polygon: np.ndarray, h: float) -> float:
    """The sampling spacing :func:`densify` uses for the closed polygon: ``h``, or its perimeter over
    ``MAX_SAMPLES`` when that is larger."""
    return max(h, perimeter(polygon) / MAX_SAMPLES)


def densify(polygon: np.ndarray, h: float) -> np.ndarray:
    """Points of the closed polygon at spacing at most :func:`spacing` (``h`` unless the polygon is longer
    than ``MAX_SAMPLES`` of it), its vertices included, in order: at most ``MAX_SAMPLES`` + its vertex
    count points."""
    p = np.asarray(polygon, float)
    h = spacing(p, h)
    q = np.roll(p, -1, 0)
    seg = _lengths(q - p)
    k = np.maximum(1, np.ceil(seg / h).astype(np.int64))
    idx = np.repeat(np.arange(len(p)), k)
    start = np.cumsum(k) - k
    f = (np.arange(k.sum()) - np.repeat(start, k)) / np.repeat(k, k)
    return p.take(idx, axis=0) + f[:, None] * (q - p).take(idx, axis=0)


def _lengths(v: np.ndarray) -> np.ndarray:
    """``norm(v, axis=1)`` of ``(n, 2)`` vectors, bit for bit: ``sqrt(x² + y²)`` without numpy's loop per row."""
    return np.sqrt(dot2(v, v))


def _to_curve(points: np.ndarray, curve_dense: np.ndarray, tree):
    """Distance of each point to the closed polyline through ``curve_dense`` and its foot point.

    The nearest dense vertex is found by the tree and the exact distance taken to the two segments beside
    it; with the curve sampled at spacing h this is exact up to h / 2 and in practice to round-off.
    """
    n = len(curve_dense)
    _, j = tree.query(points)
    best_d = np.full(len(points), np.inf)
    best_f = np.zeros_like(points)
    # x and y apart: numpy's sums over a row of two are a loop per row; ``a x + b y`` and ``sqrt(x² + y²)`` are
    # the same operations in the same order as ``.sum(1)`` and ``norm(axis=1)``, so the same bits (and rows
    # gathered by ``take``, the same copies as indexing by an array, without its general indexing)
    px, py = points[:, 0], points[:, 1]
    for a, b in ((j - 1) % n, j), (j, (j + 1) % n):
        A, B = curve_dense.take(a, axis=0), curve_dense.take(b, axis=0)
        ax, ay = A[:, 0], A[:, 1]
        abx, aby = B[:, 0] - ax, B[:, 1] - ay
        t = (px - ax) * abx + (py - ay) * aby
        t = np.clip(t / np.maximum(abx * abx + aby * aby, 1e-300), 0.0, 1.0)
        fx, fy = ax + t * abx, ay + t * aby
        dx, dy = px - fx, py - fy
        d = np.sqrt(dx * dx + dy * dy)
        better = d < best_d
        best_d = np.where(better, d, best_d)
        best_f = np.where(better[:, None], np.stack([fx, fy], -1), best_f)
    return best_d, best_f


def _polygon(points: np.ndarray):
    poly = shapely.Polygon(points)
    return poly if poly.is_valid else shapely.make_valid(poly)


def measure(outline: np.ndarray, target: np.ndarray, size: float | None = None) -> dict:
    """Conformance of the closed ``outline`` polygon to the closed ``target`` polygon (both ``(n, 2)`` mm).

    ``size`` defaults to :func:`size_of` the target. Returns a dict of plain floats (JSON-ready):
    ``hausdorff_mm``, ``hausdorff_rel`` (fraction of the size), ``mean_outline_to_target_mm``,
    ``mean_target_to_outline_mm``, ``one_minus_iou``, ``symdiff_over_target``, ``spacing_min_mm``,
    ``spacing_mean_mm``, ``size_mm`` and ``worst`` (the point where the Hausdorff distance is attained and
    its nearest point on the other curve, ``on`` naming the curve it lies on).
    """
    A = np.asarray(outline, float).reshape(-1, 2)
    B = np.asarray(target, float).reshape(-1, 2)
    size = float(size_of(B) if size is None else size)
    h = size / SAMPLES_PER_SIZE
    h = max(h, (perimeter(A) + perimeter(B)) / MAX_SAMPLES)
    Ad = densify(A, h)
    Bd, tree = _target_samples(B, h)
    dA, fA = _to_curve(Ad, Bd, tree)
    dB, fB = _to_curve(Bd, Ad, KDTree(Ad))
    wA = _arc_weights(Ad)
    wB = _arc_weights(Bd)
    if dA.max() >= dB.max():
        k = int(np.argmax(dA))
        worst = {"on": "outline", "at": Ad[k].tolist(), "nearest": fA[k].tolist()}
    else:
        k = int(np.argmax(dB))
        worst = {"on": "target", "at": Bd[k].tolist(), "nearest": fB[k].tolist()}
    haus = float(max(dA.max(), dB.max()))
    pa, pb = _polygon(A), _polygon(B)
    sym = float(shapely.symmetric_difference(pa, pb).area)
    union = float(shapely.union(pa, pb).area)
    gaps = _lengths(np.roll(A, -1, 0) - A)
    out = {
        "hausdorff_mm": haus,
        "hausdorff_rel": haus / size,
        "mean_outline_to_target_mm": float(wA @ dA),
        "mean_target_to_outline_mm": float(wB @ dB),
        "one_minus_iou": sym / union if union > 0 else 1.0,
        "symdiff_over_target": sym / max(float(pb.area), 1e-300),
        "spacing_min_mm": float(gaps.min()),
        "spacing_mean_mm": float(gaps.mean()),
        "points": int(len(A)),
        "size_mm": size,
        "size_definition": SIZE_DEFINITION,
        "worst": worst,
    }
    if h > size / SAMPLES_PER_SIZE:  # curves too long for the usual spacing: the one used instead
        out["sampling_mm"] = h
    return out


def _target_samples(target: np.ndarray, h: float):
    """The target's samples at spacing ``h`` and their KD-tree. The last target's are kept: a design
    measures several outlines against one target (its coarse level, each start, the report), and the
    tree of the same samples is the same tree (the same nearest samples, the same figures)."""
    return _samples_of(target.tobytes(), target.shape, h)


@functools.lru_cache(maxsize=1)
def _samples_of(data: bytes, shape: tuple, h: float):
    dense = densify(np.frombuffer(data).reshape(shape), h)
    dense.flags.writeable = False  # shared by every measure against this target
    return dense, KDTree(dense)


def _arc_weights(dense: np.ndarray) -> np.ndarray:
    """Arc-length weights (summing to 1) of the points of a closed dense polyline."""
    seg = _lengths(np.roll(dense, -1, 0) - dense)
    w = 0.5 * (seg + np.roll(seg, 1))
    return w / max(float(w.sum()), 1e-300)


# ------------------------------------------------------------------ outlines of a pattern


def boundary_tip_order(
    tiles: np.ndarray, hole_nodes: np.ndarray, hole_tiles: np.ndarray, free_nodes: np.ndarray
) -> np.ndarray:
    """The free corners (boundary tips) in counter-clockwise boundary order.

    The outer boundary of a deployed pattern is every tile edge that is not a hole edge; with CCW tiles
    it is one cycle traversed in the tiles' own edge direction, so following it from a tip visits every
    tip in order. The last few answers are kept: a design asks for the same topology's order in its
    solve, its report and its preview (a Python walk, slow at 128x128 tiles).
    """
    arrays = [np.asarray(x) for x in (tiles, hole_nodes, hole_tiles, free_nodes)]
    key = tuple((x.shape, x.dtype.str, x.tobytes()) for x in arrays)
    if key not in _TIP_ORDERS:
        if len(_TIP_ORDERS) >= 4:
            _TIP_ORDERS.pop(next(iter(_TIP_ORDERS)))
        _TIP_ORDERS[key] = _walk_tips(*arrays)
    return _TIP_ORDERS[key].copy()


_TIP_ORDERS: dict = {}


def _walk_tips(
    tiles: np.ndarray, hole_nodes: np.ndarray, hole_tiles: np.ndarray, free_nodes: np.ndarray
) -> np.ndarray:
    T, n = tiles.shape
    a = tiles.reshape(-1)
    b = np.roll(tiles, -1, axis=1).reshape(-1)
    t = np.repeat(np.arange(T), n)
    # the boundary half-edges: every tile edge (tile, lower node, upper node) that is no hole edge
    bd = np.ones(len(a), dtype=bool)
    if len(hole_nodes):
        h0, h1 = hole_nodes.ravel(), np.roll(hole_nodes, -1, axis=1).ravel()
        k = min(hole_tiles.size, h0.size)
        base = 1 + max(T, *(int(v.max(initial=0)) for v in (a, h0, hole_tiles)))
        hole = _edge_codes(hole_tiles.ravel()[:k], h0[:k], h1[:k], base)
        bd = ~np.isin(_edge_codes(t, a, b, base), hole)
    # keyed by (tile, start node): a hinge bordering no hole (a kagome row's end tile) starts two boundary
    # edges, one per tile, so the node alone does not name the edge
    nxt = dict(zip(zip(t[bd].tolist(), a[bd].tolist()), b[bd].tolist()))
    free = set(free_nodes.tolist())
    if not free:
        return np.zeros(0, dtype=np.int64)
    start = int(free_nodes[0])
    # the tiles at each node the walk can reach, in the tiles' order
    near = np.isin(a, np.append(b[bd], start))
    users: dict[int, list[int]] = {}
    for tt, x in zip(t[near].tolist(), a[near].tolist()):
        users.setdefault(x, []).append(tt)
    order: list[int] = []
    key: tuple[int, int] | None = (users[start][0], start)
    for _ in range(len(nxt) + 1):
        if key is None:
            break
        if key[1] in free:
            order.append(key[1])
        y = nxt.get(key)
        if y is None or y == start:
            break
        # arriving at y along tile key[0]: at a hinge the boundary goes on along the other tile
        key = (next((u for u in users[y] if u != key[0]), key[0]), y)
    if len(order) != len(free):  # not one simple boundary cycle
        return np.asarray(free_nodes)
    return np.asarray(order, dtype=np.int64)


def _edge_codes(t: np.ndarray, x: np.ndarray, y: np.ndarray, base: int) -> np.ndarray:
    """One integer per edge ``(tile, min node, max node)`` (``base`` above every tile and node)."""
    t, x, y = (np.asarray(v, dtype=np.int64) for v in (t, x, y))
    return (t * base + np.minimum(x, y)) * base + np.maximum(x, y)


def closed_outline(corners: np.ndarray, eps: float | None = None) -> np.ndarray:
    """Exterior ring (CCW, not repeated) of the union of closed-state tiles ``(T, 4, 2)``.

    Hairline cracks between tiles (round-off) are closed by a buffer of ``eps`` out and back in
    (default 1e-7 of the tiles' extent); of several pieces the largest is taken.
    """
    c = np.asarray(corners, float)
    ext = float((c.reshape(-1, 2).max(0) - c.reshape(-1, 2).min(0)).max())
    eps = 1e-7 * ext if eps is None else eps
    u = (
        shapely.union_all(shapely.polygons(c))
        .buffer(eps, join_style="mitre")
        .buffer(-eps, join_style="mitre")
    )
    if hasattr(u, "geoms"):
        u = max(u.geoms, key=lambda g: g.area)
    ring = shapely.Polygon(u.exterior).simplify(eps)
    pts = np.asarray(ring.exterior.coords)[:-1]
    if shapely.LinearRing(pts).is_ccw is False:
        pts = pts[::-1]
    return pts


def align_rigid(outline: np.ndarray, target: np.ndarray, iterations: int = 40, starts: int = 24):
    """Proper rigid motion placing ``outline`` on ``target`` (closed-state outlines are size-matched but
    sit anywhere): the centroids matched, the best of ``starts`` rotations, then iterative closest points.
    Returns ``(R, t)``: the outline placed is ``outline @ R.T + t``."""
    A = np.asarray(outline, float)
    B = np.asarray(target, float)
    h = size_of(B) / 1000
    Bd = densify(B, h)
    tree = KDTree(Bd)
    Ad0 = densify(A, h)
    ca = _polygon(A).centroid
    cb = _polygon(B).centroid
    A0 = Ad0 - [ca.x, ca.y]
    best = None
    for th in np.linspace(0, 2 * np.pi, starts, endpoint=False):
        c, s = np.cos(th), np.sin(th)
        R = np.array([[c, -s], [s, c]])
        P = A0 @ R.T + [cb.x, cb.y]
        for _ in range(3 if starts > 1 else iterations):
            P, R, t = _icp_step(Ad0, P, Bd, tree)
        err = float(np.mean(tree.query(P)[0] ** 2))
        if best is None or err < best[0]:
            best = (err, P)
    assert best is not None  # starts >= 1
    P = best[1]
    for _ in range(iterations):
        Pn, R, t = _icp_step(Ad0, P, Bd, tree)
        if np.abs(Pn - P).max() <= 1e-12 * size_of(B):
            P = Pn
            break
        P = Pn
    return _fit(Ad0, P)


def _fit(src: np.ndarray, dst: np.ndarray):
    """``(R, t)`` of :func:`geometry.kabsch` (``dst ≈ src @ R.T + t``)."""
    th, t = kabsch(src, dst)
    c, s = np.cos(th), np.sin(th)
    return np.array([[c, -s], [s, c]]), t


def _icp_step(src: np.ndarray, P: np.ndarray, Bd: np.ndarray, tree):
    """One iterative-closest-point step onto the exact foot points on the target's segments."""
    _, foot = _to_curve(P, Bd, tree)
    R, t = _fit(src, foot)
    return src @ R.T + t, R, t
