"""Tile cores to quads: cut edges, ligament openings, fitted offsets and the four corners of a tile."""

from __future__ import annotations

from typing import Any

import numpy as np
import shapely

from ..errors import VerifyError
from ..exchange.linework import JOIN_MM, SNAP_MM, Linework
from ..pattern import geometry
from .geom import point_segment_distance
from .manifest import Allowances
from .matching import match_by_shape, match_in_place

EDGE_ON_MM = (
    0.02  # a cut edge bounds an opened tile core when its midpoint is this close to the core
)


def _on_cut_edges(parts: np.ndarray, material: shapely.Geometry, arity: int = 4) -> np.ndarray:
    """Opened tile cores as ``arity``-gons whose sides lie on the material's own cut edges.

    An opening leaves each tile's sides exact away from the ligament roots, but a root leaves a
    bump (or, at a mitre, a spike) that can pull a corner off. Each core's coarse quad is kept only
    to say which side is which: every side is put on the longest cut edge of the material that runs
    along it (parallel within 10°) with its midpoint on the core, and the corners are where those
    lines meet. Cores with no such edge on some side are left as they are. Vectorised over all
    (core, edge) pairs; ties between equally long edges go to the first the STRtree query lists.
    """
    if not len(parts):
        return parts
    xy, ring = shapely.get_coordinates(
        shapely.get_rings(shapely.get_parts(material)), return_index=True
    )
    same = ring[1:] == ring[:-1]
    segs = np.stack([xy[:-1][same], xy[1:][same]], 1)
    segs = segs[np.linalg.norm(segs[:, 1] - segs[:, 0], axis=1) > 0]
    mids = shapely.points(segs.mean(axis=1))
    out = np.array(parts, dtype=object)
    rings = shapely.get_exterior_ring(out)
    pi, si = shapely.STRtree(mids).query(rings, predicate="dwithin", distance=EDGE_ON_MM)
    # one pass over every (part, cut edge) pair: the coarse quad of each part that has pairs
    K = len(out)
    Q = np.full((K, arity, 2), np.nan)
    has_q = np.zeros(K, bool)
    for k in np.unique(pi):
        if out[k].geom_type == "Polygon":
            q = quad_corners(out[k], n=arity)
            if q is not None:
                Q[k], has_q[k] = q, True
    keep = has_q[pi]
    pi, si = pi[keep], si[keep]
    q = Q[pi]  # (P, arity, 2) the polygon of each pair's part
    e = segs[si, 1] - segs[si, 0]
    elen = np.linalg.norm(e, axis=1)
    side = np.roll(q, -1, 1) - q
    slen = np.linalg.norm(side, axis=-1)
    m = segs[si].mean(axis=1)
    dist = np.stack(
        [point_segment_distance(m, q[:, i], q[:, (i + 1) % arity]) for i in range(arity)], 1
    )
    along = np.abs(geometry.cross2(e[:, None, :], side)) <= 0.17 * elen[:, None] * slen
    dist = np.where(along & (dist <= 0.1 * slen), dist, np.inf)
    which = np.where(np.isfinite(dist).any(axis=1), dist.argmin(axis=1), -1)
    # per (part, side) the longest edge, the first of equals in query order (as argmax picks)
    ok = which >= 0
    order = np.lexsort((np.arange(len(pi))[ok], -elen[ok], which[ok], pi[ok]))
    idx = np.flatnonzero(ok)[order]
    key = pi[idx] * arity + which[idx]
    first = np.ones(len(key), bool)  # no pair at all leaves every part as it is
    first[1:] = key[1:] != key[:-1]
    best = np.full((K, arity), -1)
    best.reshape(-1)[key[first]] = idx[first]
    full = (best >= 0).all(axis=1)
    ks = np.flatnonzero(full)
    b = best[ks]  # (n, arity) pair index of each side's line
    P0, D = segs[si[b], 0], e[b]  # (n, arity, 2)
    p1, d1 = np.roll(P0, 1, axis=1), np.roll(D, 1, axis=1)  # side i-1 meets side i at corner i
    den = geometry.cross2(d1, D)
    par = np.abs(den) < 1e-9 * np.linalg.norm(d1, axis=-1) * np.linalg.norm(D, axis=-1)
    with np.errstate(divide="ignore", invalid="ignore"):
        C = p1 + (geometry.cross2(P0 - p1, D) / den)[..., None] * d1
    qk = Q[ks]
    size = np.linalg.norm(qk - qk.mean(1, keepdims=True), axis=-1).max(axis=1)
    good = ~par.any(axis=1) & (np.linalg.norm(C - qk, axis=-1).max(axis=1) <= 0.5 * size)
    for k, c in zip(ks[good], C[good]):
        out[k] = shapely.Polygon(c)
    return out


def _hairline_free(g: shapely.Geometry) -> np.ndarray:
    """The parts of ``g`` after an opening at the join tolerance (drops 1 µm hairlines, keeps convex parts)."""
    g = g.buffer(-JOIN_MM, join_style="mitre", mitre_limit=UNDO_MITRE).buffer(
        JOIN_MM, join_style="mitre", mitre_limit=UNDO_MITRE
    )
    return shapely.get_parts(g)


def _declared_strips_moved(
    parts: np.ndarray,
    strips: shapely.Geometry | None,
    frame_tiles: np.ndarray | None,
    al: Allowances,
    material: shapely.Geometry | None = None,
) -> shapely.Geometry | None:
    """The declared ligaments moved with the sheet: the rigid motion that takes the manifest's tile
    placement onto the tiles an opening found, applied to the strips. None if it cannot be found.

    A symmetric lattice's tiles fit several motions equally well (a quarter turn off); a ligament is
    material, so of those the motion that puts the most of the strips on the ``material`` is taken, and
    none where that leaves a tenth of the strips off it."""
    if strips is None or frame_tiles is None or not len(parts):
        return None
    grown = (
        shapely.buffer(parts, al.tile_shrink, join_style="mitre", mitre_limit=10.0)
        if al.tile_shrink
        else parts
    )
    quads, _ = quads_of(grown, frame_tiles.shape[1])
    alts: list = []
    first = match_in_place(frame_tiles, quads, alternatives=alts)[:3]
    best, cover = None, -1.0
    for a, res, sh in [first, *alts]:
        motion = _motion(frame_tiles, quads, a, res, sh)
        if motion is None:
            continue
        moved = _moved(strips, *motion)
        c = 1.0 if material is None else shapely.area(moved & material) / max(moved.area, 1e-300)
        if c > cover:
            best, cover = moved, c
    return best if cover >= 0.9 else None


def _moved(g: shapely.Geometry, theta: float, t: np.ndarray) -> shapely.Geometry:
    from shapely import affinity

    return affinity.translate(
        affinity.rotate(g, theta, origin=(0, 0), use_radians=True), t[0], t[1]
    )


def _motion(
    frame_tiles: np.ndarray, quads: np.ndarray, a: np.ndarray, res: np.ndarray, sh: np.ndarray
) -> tuple[float, np.ndarray] | None:
    """The rigid motion of a matching (``a``: recovered quad -> frame tile, ``res``, corner shift ``sh``),
    fitted on the tiles the opening gave back whole: a tile narrower than a ligament comes back cut
    short, and its corners would pull the motion off. None with too few tiles matched."""
    ok = a >= 0
    if ok.sum() < max(3, len(frame_tiles) // 2):
        return None
    good = np.flatnonzero(ok & (res <= max(2.0 * float(np.median(res[ok])), 1e-3)))
    good = good if len(good) >= 3 else np.flatnonzero(ok)
    k = quads.shape[1]
    dst = quads[good[:, None], (np.arange(k)[None, :] + sh[good][:, None]) % k]
    theta, t = geometry.kabsch(frame_tiles[a[good]], dst)
    return float(theta), np.asarray(t)


def _nested(lw: Linework) -> bool:
    """Whether a closed outline holds another (the outline of one sheet piece and its holes)."""
    polys = np.array([shapely.Polygon(p) for p in lw.polylines], dtype=object)
    if len(polys) < 2:
        return False
    a, b = shapely.STRtree(polys).query(polys, predicate="contains_properly")
    return bool((a != b).any())


def _open_ligaments(material: shapely.Geometry, width: float | None) -> np.ndarray:
    """The tile cores of a ligament sheet: an opening (mitre: convex tiles come back exactly) of
    radius above half the ligament width drops the strips: the smallest radius (x1.25 steps, from
    0.6 times the declared width, else from 10 µm) after which the piece count no longer grows."""

    def opened(r: float) -> np.ndarray:
        g = material.buffer(-r, join_style="mitre", mitre_limit=10.0).buffer(
            r, join_style="mitre", mitre_limit=10.0
        )
        parts = shapely.get_parts(g)
        return parts[shapely.area(parts) > 4 * r * r]

    r = 0.6 * width if width else 0.01  # a declared width is where the search starts
    best, first = opened(r), r
    while r < 5.0:
        r *= 1.25
        nxt = opened(r)
        if len(nxt) < len(best) and len(best) > 1:
            break
        if len(nxt) > len(best):
            best, first = nxt, r
    margin = opened(1.5 * first)  # clear of the strips' roots, when that keeps every tile
    return margin if len(margin) == len(best) else best


UNDO_MITRE = 1000.0  # undoing an offset must keep sharp corners sharp
MAX_FITTED_OFFSET_MM = 0.25  # a kerf up to 0.5 mm: any more is not a laser's kerf


MAX_FITTED_SHRINK_MM = 2.5  # a ligament sheet's tiles shrunk by up to half a 5 mm gap


def _fit_offset(R: np.ndarray, D: np.ndarray, L: float, tol: float, lo: float = 0.0) -> float:
    """The outward (mitre) offset of separate outlines from their design tiles, 0 if none is needed.

    Per matched tile the offset that explains its area, (A_cut - A) / perimeter; their median, if
    it lies within [0, MAX_FITTED_OFFSET_MM]. Each tile's congruence is still checked after it is undone.
    """
    a, _, _ = match_by_shape(D, R, L)
    ok = a >= 0
    if not ok.any():
        return 0.0
    A = np.abs(geometry.signed_areas(D[a[ok]]))
    P = geometry.edge_lengths(D[a[ok]]).sum(axis=1)
    # a mitre offset k of a convex quad has area A + P k + k^2 sum cot(alpha/2): the root near the
    # first-order k (that alone is 0.02 mm off for a 0.7 mm shrink of 20 mm tiles)
    c2 = (1.0 / np.tan(0.5 * geometry.corner_angles(D[a[ok]]))).sum(axis=1)
    dA = np.abs(geometry.signed_areas(R[ok])) - A
    disc = np.maximum(P * P + 4 * c2 * dA, 0.0)
    k_each = np.where(np.abs(c2) > 1e-12, 2 * dA / (P + np.sqrt(disc)), dA / P)
    k = float(np.median(k_each))
    return k if 0.1 * tol < abs(k) and lo <= k <= MAX_FITTED_OFFSET_MM else 0.0


def _set_reference_aside(
    quads: np.ndarray,
    D: np.ndarray,
    L: float,
    tol: float,
    n_tiles: int | None = None,
) -> tuple[np.ndarray, float | None]:
    """Take out the reference square (a square that is no design tile), by geometry.

    fabkiri cuts an uncompensated square beside the parts so the kerf can be measured; a file
    moved, turned or without its manifest still has it. ``n_tiles``: the design tiles on the sheet
    (default all). A square
    congruent to a design tile is taken only when the sheet has more regions than tiles. Of several
    candidates the odd one out is taken: the fewest squares of its side (kerf-offset tiles are all alike,
    the uncompensated square is not), then the farthest from the other regions (tiles in place touch or
    sit a gap apart, the square sits beside them), then the largest. Returns the other quads and its side.
    """
    if not len(quads):
        return quads, None
    e = geometry.edge_lengths(quads)
    diag = (
        np.linalg.norm(quads[:, 2] - quads[:, 0], axis=1),
        np.linalg.norm(quads[:, 3] - quads[:, 1], axis=1),
    )
    sides = e.mean(axis=1)
    square = (e.max(axis=1) - e.min(axis=1) <= tol) & (np.abs(diag[0] - diag[1]) <= tol)
    cand = np.flatnonzero(square)
    if D.shape[1] == 4 and len(cand):  # a square may be a design tile; other tiles never are
        surplus = len(quads) > (len(D) if n_tiles is None else n_tiles)
        if not surplus:
            cand = cand[~_tile_like(D, quads[cand], L, tol)]
    if not len(cand):
        return quads, None
    alike = (np.abs(sides[cand][:, None] - sides[square][None, :]) <= tol).sum(axis=1)
    cand = cand[alike == alike.min()]
    if len(cand) > 1:
        polys = shapely.polygons(quads)
        (src, _), dist = shapely.STRtree(polys).query_nearest(
            polys[cand], exclusive=True, return_distance=True, all_matches=False
        )
        clear = np.zeros(len(cand))
        clear[src] = np.round(dist / tol)
        cand = cand[clear == clear.max()]
    k = int(cand[np.argmax(sides[cand])])
    return np.delete(quads, k, axis=0), float(sides[k])


def _tile_like(D: np.ndarray, Q: np.ndarray, L: float, tol: float) -> np.ndarray:
    """Whether each quad of ``Q`` is congruent (within ``tol``) to some design tile of ``D``: fitted to
    the design's nearest shape classes (:func:`.matching.match_by_shape`'s keys), not one to one."""
    from ..kdtree import KDTree
    from .matching import _descriptor, _shape_classes, _shift_fit

    reps = np.unique(_shape_classes(D, L), return_index=True)[1]
    kk = min(8, len(reps))
    _, near = KDTree(_descriptor(D[reps], L)).query(_descriptor(Q, L), k=kk)
    near = np.asarray(near).reshape(len(Q), kk)
    res, _ = _shift_fit(D[reps[near.ravel()]], np.repeat(Q, kk, axis=0))
    return res.reshape(len(Q), kk).min(axis=1) <= tol


def _feature_geometry(poly: Any) -> shapely.Polygon | shapely.MultiPolygon:
    """A hinge feature: one ring ``[[x, y], ...]`` or several ``[[[x, y], ...], ...]``."""
    try:
        arr = np.asarray(poly, dtype=float)
        if arr.ndim == 2 and arr.shape[1] == 2:
            return shapely.Polygon(arr)
        return shapely.MultiPolygon([shapely.Polygon(np.asarray(r, dtype=float)) for r in poly])
    except (TypeError, ValueError) as exc:
        raise VerifyError(f"malformed hinge feature polygon in the manifest ({exc})") from None


MAX_SIMPLIFIED_AREA = (
    0.25  # dropping the extra vertices of a bevelled or notched tile changes its area less
)


def _drop_collinear(pts: np.ndarray, eps: float) -> np.ndarray:
    """``pts`` without the vertices within ``eps`` of the line through their neighbours (collinear,
    T-junctions, noding points) or of the previous vertex (duplicates), one at a time, down to three."""
    changed = True
    while changed and len(pts) > 3:
        changed = False
        prv, nxt = np.roll(pts, 1, 0), np.roll(pts, -1, 0)
        d = point_segment_distance(pts, prv, nxt)
        dup = np.linalg.norm(pts - prv, axis=1) <= eps
        bad = (d <= eps) | dup
        if bad.any():
            k = int(np.flatnonzero(bad)[0])
            pts = np.delete(pts, k, axis=0)
            changed = True
    return pts


def quad_corners(poly: shapely.Polygon, eps: float = SNAP_MM, n: int = 4) -> np.ndarray | None:
    """The ``n`` corners (CCW; ``n`` the tile arity, four for quads) of a recovered tile region, or None.

    Collinear and duplicate vertices (T-junctions, noding points) are dropped;
    if more than ``n`` corners remain (bevelled or notched corners), the
    polygon is simplified to ``n`` corners, then each corner is moved to where
    the longest original edges along its two sides meet.
    """
    if poly.is_empty or poly.geom_type != "Polygon":
        return None
    pts = np.asarray(poly.exterior.coords)[:-1]
    if shapely.LinearRing(pts).is_ccw is False:
        pts = pts[::-1]
    pts = _drop_collinear(pts, eps)
    if len(pts) == n:
        return pts
    if len(pts) < n:
        return None
    # more than four corners (bevelled or notched corners): drop the vertex
    # that costs the least area until four remain (Visvalingam-Whyatt) ...
    keep = list(range(len(pts)))
    while len(keep) > n:
        q = pts[keep]
        prv, nxt = np.roll(q, 1, 0), np.roll(q, -1, 0)
        cost = np.abs(geometry.cross2(prv - q, nxt - q))
        keep.pop(int(np.argmin(cost)))
    coarse = pts[keep]
    area = abs(geometry.signed_areas(pts[None])[0])
    if abs(abs(geometry.signed_areas(coarse[None])[0]) - area) > MAX_SIMPLIFIED_AREA * area:
        return None  # not an n-gon with a bevel or notch (e.g. a square is no triangle)
    # ... then put each corner where the longest original edges along its two
    # sides meet, which restores an apex cut off by a bevel or notch
    e = np.roll(pts, -1, 0) - pts
    elen = np.linalg.norm(e, axis=1)
    mid = pts + 0.5 * e
    lines = []
    for i in range(n):
        a, b = coarse[i], coarse[(i + 1) % n]
        d = b - a
        dl = np.linalg.norm(d)
        if dl == 0:
            return None
        # parallel within 10° (quad corners are far sharper turns) and close to the side
        along = (np.abs(geometry.cross2(e, d)) <= 0.17 * elen * dl) & (geometry.dot2(e, d) > 0)
        near = np.abs(geometry.cross2(mid - a, d)) / dl <= 0.1 * dl
        # and lying along this side, not its neighbour past a corner that turns by only a few
        # degrees (a sliver tile's): that line would move the far corner by millimetres
        s = geometry.dot2(mid - a, d) / dl**2
        cand = np.flatnonzero(along & near & (s > 0.0) & (s < 1.0))
        longest = cand[np.argmax(elen[cand])] if len(cand) else None
        lines.append((a, d) if longest is None else (pts[longest], e[longest]))
    out = []
    for i in range(n):
        (p1, d1), (p2, d2) = lines[i - 1], lines[i]
        den = geometry.cross2(d1, d2)
        if abs(den) < 1e-9 * np.linalg.norm(d1) * np.linalg.norm(d2):
            out.append(coarse[i])
            continue
        x = p1 + geometry.cross2(p2 - p1, d2) / den * d1
        size = np.linalg.norm(coarse - coarse.mean(0), axis=1).max()
        out.append(x if np.linalg.norm(x - coarse[i]) <= 0.5 * size else coarse[i])
    return np.asarray(out)


def quads_of(polys: np.ndarray, arity: int = 4) -> tuple[np.ndarray, int]:
    """Corners ``(n, arity, 2)`` of recovered regions and how many are not ``arity``-gons.

    Plain ``arity``-vertex rings take a vectorised path; the rest go through
    :func:`quad_corners`.
    """
    C, ok = tiles_of(polys, arity)
    return C, int((~ok).sum())


def tiles_of(polys: np.ndarray, arity: int = 4) -> tuple[np.ndarray, np.ndarray]:
    """:func:`quads_of` with, per region, whether it gave a tile (the corners: plain rings first, then
    the others, each in the regions' order)."""
    polys = np.asarray(polys, dtype=object)
    if len(polys) == 0:
        return np.zeros((0, arity, 2)), np.zeros(0, dtype=bool)
    simple = (shapely.get_type_id(polys) == 3) & (shapely.get_num_interior_rings(polys) == 0)
    rings = shapely.get_exterior_ring(polys[simple])
    four = np.zeros(len(polys), dtype=bool)
    out = []
    if len(rings):
        xy, ring = shapely.get_coordinates(rings, return_index=True)
        n = np.bincount(ring, minlength=len(rings))
        start = np.concatenate([[0], np.cumsum(n)[:-1]])
        last = start + n - 1  # the closing repeat of the first point
        keep = np.ones(len(xy), dtype=bool)
        keep[last] = False
        pos = np.arange(len(xy))
        m = n - 1  # distinct points per ring
        local = pos - start[ring]
        prv = start[ring] + (local - 1) % np.maximum(m[ring], 1)
        nxt = start[ring] + (local + 1) % np.maximum(m[ring], 1)
        # drop collinear and repeated vertices (T-junction and noding points) in one pass
        d = point_segment_distance(xy, xy[prv], xy[nxt])
        dup = np.linalg.norm(xy - xy[prv], axis=1) <= SNAP_MM
        keep &= ~((d <= SNAP_MM) | dup)
        cnt = np.bincount(ring[keep], minlength=len(rings))
        ok4 = cnt == arity
        if ok4.any():
            C = xy[keep & ok4[ring]].reshape(-1, arity, 2)
            cw = geometry.signed_areas(C) < 0
            C[cw] = C[cw, ::-1]
            out.append(C)
            four[np.flatnonzero(simple)[ok4]] = True
    rest = [quad_corners(p, n=arity) for p in polys[~four]]
    good = [q for q in rest if q is not None]
    ok = four.copy()
    ok[np.flatnonzero(~four)] = [q is not None for q in rest]
    if good:
        out.append(np.asarray(good))
    return (np.concatenate(out) if out else np.zeros((0, arity, 2))), ok
