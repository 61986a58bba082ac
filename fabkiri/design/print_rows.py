"""Fabrication rows of printed strips: the pad each strip glues onto each of its two tiles.

``print`` (``fabkiri.fabricate.printgeom.strip_outlines``) lays the strip of hinge h as a band across its
closed seam: ``[t0, t0 + w]`` along the seam from the hinge point, ``reach + d`` either side of it, and keeps
the part inside the two tiles shrunk by ``d`` (half the printer's gap). The pad on tile A is the band
clipped by A shrunk by ``d``; ``print`` refuses a hinge whose pad is under ``0.25 w min(reach, w)`` mm².

A tile is rigid, so its pad is the same in the deployed frame: the band anchored at the tile's hinge corner
along its seam edge (the fold rule's edge of the printed closed state). ``t0`` is where the seam line enters
the two tiles shrunk by ``d``: ``d / sin`` of the sharper of the two hinge corners (``d`` where both are
obtuse). :func:`pad_rows` is that area, exactly (the clipped polygon's boundary integral, Cyrus-Beck clipping
of each edge), divided by ``w`` (a mean pad depth, a length like every other row), minus the plan's.
Gradients are carried forward (:class:`~.fabrication.Dual`) and checked against finite differences and the
area ``print`` measures in ``tests/test_print_rows.py``.
"""

from __future__ import annotations

import numpy as np

from . import fabrication as F
from .constraints import Family, Stencils


def where(cond: np.ndarray, a: F.Dual, b: F.Dual) -> F.Dual:
    """Row-wise choice between two :class:`~.fabrication.Dual` values."""
    g = None if a.g is None else np.where(cond[:, None], a.g, b.g)
    return F.Dual(np.where(cond, a.v, b.v), g)


def _cross(a, b) -> F.Dual:
    return a[0] * b[1] - a[1] * b[0]


def _clipped_boundary(P: list, Q: list) -> F.Dual:
    """Twice the signed area the edges of convex CCW polygon ``P`` contribute inside convex CCW ``Q``:
    each edge clipped to ``Q`` (Cyrus-Beck), then ``cross(start, end)`` of what is left."""
    like = P[0][0]
    zero = F.Dual.lift(0.0, like)
    total = zero
    for i in range(len(P)):
        a, b = P[i], P[(i + 1) % len(P)]
        ab = F._sub(b, a)
        lo, hi = zero, F.Dual.lift(1.0, like)
        empty = np.zeros(like.v.shape, dtype=bool)
        for j in range(len(Q)):
            c, d = Q[j], Q[(j + 1) % len(Q)]
            n = (c[1] - d[1], d[0] - c[0])  # inward (left) normal of the CCW edge c -> d
            f0, f1 = F._dot(n, F._sub(a, c)), F._dot(n, F._sub(b, c))
            out0, out1 = f0.v < 0, f1.v < 0
            empty |= out0 & out1
            den = f0 - f1
            den = where(np.abs(den.v) > 0, den, F.Dual.lift(1.0, like))
            lam = f0 / den
            lo = where(out0 & ~out1 & (lam.v > lo.v), lam, lo)
            hi = where(out1 & ~out0 & (lam.v < hi.v), lam, hi)
        p = (a[0] + ab[0] * lo, a[1] + ab[1] * lo)
        q = (a[0] + ab[0] * hi, a[1] + ab[1] * hi)
        total = total + where(~empty & (hi.v > lo.v), _cross(p, q), zero)
    return total


def clipped_area(P: list, Q: list) -> F.Dual:
    """Area of the intersection of two convex counter-clockwise polygons (lists of ``(x, y)`` Duals)."""
    return (_clipped_boundary(P, Q) + _clipped_boundary(Q, P)) * 0.5


def _sine(x, polys, rows, k, n, base) -> F.Dual:
    """sin of corner ``k`` (per row) of the ``n``-gon at nodes ``base..base+n`` of ``polys``' rows, 1 where it
    is obtuse (the seam line is then ``shrink`` from that tile's edge once ``t >= shrink``)."""
    v = F._corners(x, polys, rows, base + k)
    a = F._sub(F._corners(x, polys, rows, base + (k + 1) % n), v)
    b = F._sub(F._corners(x, polys, rows, base + (k - 1) % n), v)
    s = _cross(a, b) / (F._dot(a, a) * F._dot(b, b)).sqrt()
    return where(F._dot(a, b).v < 0, F.Dual.lift(1.0, s), s)


def pad_polygons(tiles: np.ndarray, hinge_tiles: np.ndarray) -> np.ndarray:
    """Per pad (hinge-major: tile A's, then tile B's) the nodes it reads: its own tile, then the other."""
    A, B = hinge_tiles.T
    own = np.stack([A, B], 1).ravel()
    other = np.stack([B, A], 1).ravel()
    return np.concatenate([tiles[own], tiles[other]], 1)


def pad_rows(
    x: np.ndarray,
    polys: np.ndarray,
    corner: np.ndarray,
    end: np.ndarray,
    other_corner: np.ndarray,
    shrink: float,
    width: float,
    reach: float,
    need: float,
) -> F.Dual:
    """Pad area over ``width`` minus ``need`` over ``width`` for every pad of :func:`pad_polygons`: the band
    ``[t0, t0 + width]`` along the seam (own ``corner`` to ``end``), ``reach + shrink`` either side of it,
    clipped by the own tile shrunk by ``shrink`` (mitre); ``t0`` from both tiles' hinge corners."""
    n = polys.shape[1] // 2
    rows = np.arange(len(polys))
    p = F._corners(x, polys, rows, corner)
    ev = F._sub(F._corners(x, polys, rows, end), p)
    ln = F._dot(ev, ev).sqrt()
    e = (ev[0] / ln, ev[1] / ln)
    s_own = _sine(x, polys, rows, corner, n, 0)
    s_other = _sine(x, polys, rows, other_corner, n, n)
    sharper = where(s_own.v < s_other.v, s_own, s_other)
    t0 = F.Dual.lift(shrink, sharper) / sharper
    t1 = t0 + width
    R = reach + shrink
    # t e + r (-e_y, e_x) from the hinge corner: (t0, -R), (t1, -R), (t1, R), (t0, R) run counter-clockwise
    band = [
        (p[0] + e[0] * t - e[1] * r, p[1] + e[1] * t + e[0] * r)
        for t, r in ((t0, -R), (t1, -R), (t1, R), (t0, R))
    ]
    return clipped_area(band, _shrunk(x, polys, rows, n, shrink)) / width - need / width


def _shrunk(x, polys, rows, n, shrink) -> list:
    """The own tile (the first ``n`` nodes of ``polys``) shrunk by ``shrink``: corner k moves by ``shrink``
    times its mitre vector (:func:`~.fabrication._mitre`)."""
    ks = [np.full(len(rows), k) for k in range(n)]
    c = [F._corners(x, polys, rows, k) for k in ks]
    if not shrink:
        return c
    out = []
    for ck, k in zip(c, ks):
        m = F._mitre(x, polys, rows, k, n)
        out.append((ck[0] + m[0] * shrink, ck[1] + m[1] * shrink))
    return out


def pad_args(
    tiles: np.ndarray, hinge_tiles: np.ndarray, hinge_corner: np.ndarray, fold_ends: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """``(polys, corner, end, other_corner)`` of :func:`pad_rows` for every pad (hinge-major, A's then B's)."""
    polys = pad_polygons(tiles, hinge_tiles)
    return polys, hinge_corner.ravel(), fold_ends.ravel(), hinge_corner[:, ::-1].ravel()


def strip_pad(limits: F.FabricationLimits, unit_mm: float) -> tuple[float, float, float, float]:
    """``(shrink, width, reach, need)`` of :func:`pad_rows` for ``limits`` in units of ``unit_mm``."""
    u = unit_mm
    return (
        limits.shrink_mm / u,
        limits.strip_width_mm / u,
        limits.strip_reach_mm / u,
        limits.strip_pad_mm2 / (u * u),
    )


def families(st: Stencils, nv: int, limits: F.FabricationLimits, unit_mm: float) -> list[Family]:
    """The pad rows of a quad design (seams of closed state ``limits.print_state``, the one ``print`` makes)."""
    if limits.strip_pad_mm2 <= 0 or limits.strip_width_mm <= 0 or not len(st.hinge_tiles):
        return []
    args = pad_args(
        st.tiles, st.hinge_tiles, st.hinge_corner, st.folds[limits.print_state].fold_corner_ends
    )
    box = strip_pad(limits, unit_mm)
    polys = args[0]
    return [
        F._family(
            "fabrication_strip_pads",
            polys,
            lambda x: pad_rows(x, *args, *box),
            nv,
            {"quad_of_row": np.arange(len(polys))},
        )
    ]
