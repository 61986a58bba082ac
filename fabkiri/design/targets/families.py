"""Target-matching families: boundary tips on their target arcs and the whole tip outline against a curve."""

from __future__ import annotations

import numpy as np

from ...pattern.geometry import cross2, dot2
from ..core.stencils import Family
from .curve import Target


def shape_match(
    nodes: np.ndarray, sides: np.ndarray, target: Target, nv: int, name: str = "shape"
) -> Family:
    """Signed distance of boundary tips to their arc of the target (normalised units)."""

    project = target.projector(sides)

    def fn(x):
        _, _, d, g = project(x[nodes])
        return d, (nodes[:, None], g[:, None, :])

    return Family(
        name, "fit", fn, 1, meta={"nodes": nodes, "sides": sides, "target": target}, nv=nv
    )


# weights of the outline rows against the tip rows (weight 1): every chord midpoint, and target samples
# (OUTLINE_SAMPLES per tip, each row weighted so all samples together count as much as the tips)
CHORD_WEIGHT = 1.0
OUTLINE_SAMPLES = 4
SAMPLE_WEIGHT = 1.0


def outline_match(
    order: np.ndarray,
    target: Target,
    nv: int,
    name: str = "shape_outline",
    samples: int = OUTLINE_SAMPLES,
) -> Family:
    """The whole tip polygon against the target, not just its vertices (``shape_match``): soft rows.

    * the midpoint of every chord between consecutive tips (``order``: tips in boundary order), signed
      distance to the whole target curve — a chord that cuts a corner or spans an uncovered stretch has its
      midpoint far from the curve;
    * target samples (``samples`` per tip, uniform in arc length, plus every sharp vertex of a polyline target:
      corners and cusps), signed distance to their nearest chord (positive when the target is outside the tip
      polygon) — a star point or heart cusp that no tip reaches pulls the nearest chord's tips towards it.

    Their minimum is not zero (a chord cannot follow a curve), so the exact-fit projection leaves them out
    (``meta["soft"]``).
    """
    order = np.asarray(order, dtype=np.int64)
    E = len(order)
    a_idx, b_idx = order, np.roll(order, -1)
    whole = target.projector(np.full(E, -1))
    pts = _outline_samples(target, samples * E)
    ws = SAMPLE_WEIGHT * np.sqrt(1.0 / samples)

    def fn(x):
        A, B = x[a_idx], x[b_idx]
        _, _, dm, gm = whole(0.5 * (A + B))
        e = B - A
        ee = np.maximum(dot2(e, e), 1e-300)
        j, tj, fj, dj = nearest_chords(pts, A, B)
        # the sign from the tip polygon itself (inside: negative), not from the nearest chord's normal, which
        # flips between the two chords of a tip; the gradient moves the foot (1-t) a + t b towards the sample
        side = np.where(inside_polygon(pts, A, B), -1.0, 1.0)
        off = pts - fj
        ej = e[j]
        nrm = np.stack([ej[:, 1], -ej[:, 0]], -1) / np.sqrt(ee[j])[:, None]
        unit = np.where((dj > 1e-300)[:, None], off / np.maximum(dj, 1e-300)[:, None], nrm)
        g = side[:, None] * unit
        ga = -g * (1.0 - tj)[:, None]
        gb = -g * tj[:, None]
        r = np.concatenate([CHORD_WEIGHT * dm, ws * side * dj])
        nodes = np.concatenate([np.stack([a_idx, b_idx], -1), np.stack([a_idx[j], b_idx[j]], -1)])
        grads = np.concatenate(
            [CHORD_WEIGHT * 0.5 * np.stack([gm, gm], 1), ws * np.stack([ga, gb], 1)]
        )
        return r, (nodes, grads)

    return Family(name, "fit", fn, 1, meta={"nodes": order, "target": target, "soft": True}, nv=nv)


def _chord_feet(pts: np.ndarray, A: np.ndarray, B: np.ndarray):
    """Foot parameter, foot point and distance of each point to each paired chord A -> B (broadcasting)."""
    e = B - A
    ee = np.maximum(dot2(e, e), 1e-300)
    t = np.clip(dot2(pts - A, e) / ee, 0.0, 1.0)
    foot = A + t[..., None] * e
    return t, foot, np.sqrt(dot2(pts - foot, pts - foot))


NEAREST_CANDIDATES = 8  # chords tried per point before the exactness bound is checked


def nearest_chords(pts: np.ndarray, A: np.ndarray, B: np.ndarray):
    """For every point its nearest chord (lowest index on a tie), foot parameter, foot point and distance.

    Exact, in O((K + E) log E) instead of the K x E distance table: the chords with the nearest midpoints are
    measured first, and a point is settled when its best distance is below the next midpoint's distance less
    the longest half chord (no other chord can come closer); the rest (rare) are measured against every chord.
    """
    from ...kdtree import KDTree

    E = len(A)
    k = min(NEAREST_CANDIDATES, E)
    mid = 0.5 * (A + B)
    half = 0.5 * float(np.sqrt(dot2(B - A, B - A)).max(initial=0.0))
    dk, cand = KDTree(mid).query(pts, k=k + 1 if k < E else k)
    # settled only below the bound by more than its rounding: a tie at the bound goes to the full table
    bound = dk[:, k] - half - 1e-12 * (dk[:, k] + half) if k < E else np.full(len(pts), np.inf)
    cand = np.sort(
        cand[:, :k], axis=1
    )  # argmin keeps the first minimum: the lowest index, as a full table
    t, foot, dist = _chord_feet(pts[:, None, :], A[cand], B[cand])
    best = np.argmin(dist, axis=1)
    rows = np.arange(len(pts))
    j, tj, fj, dj = cand[rows, best], t[rows, best], foot[rows, best], dist[rows, best]
    open_ = np.flatnonzero(~(dj < bound))
    if len(open_):
        t, foot, dist = _chord_feet(pts[open_, None, :], A[None], B[None])
        b = np.argmin(dist, axis=1)
        r = np.arange(len(open_))
        j[open_], tj[open_], fj[open_], dj[open_] = b, t[r, b], foot[r, b], dist[r, b]
    return j, tj, fj, dj


def inside_polygon(pts: np.ndarray, A: np.ndarray, B: np.ndarray) -> np.ndarray:
    """Points inside the closed polygon with edges A -> B (even-odd crossings of a ray to +x).

    Only the (point, edge) pairs whose edge straddles the point's height are formed: with the points sorted
    by height each edge's are one contiguous run, so the work is the number of crossings, not K x E.
    """
    order = np.argsort(pts[:, 1], kind="stable")
    ys = pts[order, 1]
    ay, by = A[:, 1], B[:, 1]
    # edge straddles py iff min(ay, by) <= py < max(ay, by), as (ay > py) != (by > py)
    lo = np.searchsorted(ys, np.minimum(ay, by), side="left")
    hi = np.searchsorted(ys, np.maximum(ay, by), side="left")
    n = np.maximum(hi - lo, 0)
    edge = np.repeat(np.arange(len(A)), n)
    start = np.repeat(np.cumsum(n) - n, n)
    p = order[np.repeat(lo, n) + np.arange(int(n.sum())) - start]
    ax, bx = A[edge, 0], B[edge, 0]
    py = pts[p, 1]
    xc = ax + (py - ay[edge]) * (bx - ax) / (by[edge] - ay[edge])
    hits = np.bincount(p[pts[p, 0] < xc], minlength=len(pts))
    return hits % 2 == 1


def _outline_samples(target: Target, n: int) -> np.ndarray:
    """``n`` points uniform in the target's parameter (chord length) and its sharp polyline vertices."""
    pts = target.point(np.linspace(0.0, 1.0, n, endpoint=False))
    if target.kind == "polyline":
        P = target.points
        d0, d1 = P - np.roll(P, 1, 0), np.roll(P, -1, 0) - P
        turn = np.abs(np.arctan2(cross2(d0, d1), dot2(d0, d1)))
        pts = np.vstack([pts, P[turn > np.radians(20.0)]])
    return pts
