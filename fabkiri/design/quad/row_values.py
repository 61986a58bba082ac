"""The fabrication rows' values alone, on plain arrays: a residual-only call (:func:`~..core.dual.values_only`)
of the strip pad, strip clearance, width and shrunk edge rows without the :class:`~..core.dual.Dual` wrapping.

Each value is computed by the same IEEE operations in the same order as the Dual path (``print_rows.pad_rows``,
``fabrication.strip_rows``, ``width_rows``, ``shrunk_edge_rows``), so the bits are the same
(``tests/design/test_print_rows.py`` compares them); only the layout changes: the pads' Cyrus-Beck clipping
of every edge of one polygon against every edge of the other in one broadcast instead of a loop of small
ones, each corner's mitre once, the strip rows' four axes at once. The solvers ask these values at every
trial step, the gradients only where a row is active.
"""

from __future__ import annotations

import numpy as np


def _next(a: np.ndarray, shift: int = 1) -> np.ndarray:
    """``np.roll(a, -shift, 0)`` (the next corner's values; an index copy, cheaper than ``np.roll``)."""
    k = len(a)
    return a[(np.arange(k) + shift) % k]


def _normal(a0, a1, b0, b1):
    """Inward unit normal of the CCW edge a -> b (as ``dual.inward_normal``)."""
    e0, e1 = b0 - a0, b1 - a1
    ln = np.sqrt(e0 * e0 + e1 * e1)
    return -e1 / ln, e0 / ln


def _clipped_boundary(P: tuple, Q: tuple) -> np.ndarray:
    """``print_rows._clipped_boundary`` on ``(x, y)`` pairs of ``(corners, rows)`` arrays (rows last: the
    broadcasts run over long contiguous rows)."""
    a0, a1 = np.ascontiguousarray(P[0]), np.ascontiguousarray(P[1])
    ab0, ab1 = _next(a0) - a0, _next(a1) - a1
    # Q's edge j first, P's edges next, the rows last (contiguous: strided broadcasts cost three times as much)
    c0, c1 = np.ascontiguousarray(Q[0])[:, None], np.ascontiguousarray(Q[1])[:, None]
    n0, n1 = c1 - _next(c1), _next(c0) - c0
    f0 = n0 * (a0 - c0) + n1 * (a1 - c1)
    # an edge's end is the next edge's start: the same operations on the same corner
    f1 = f0[:, _next(np.arange(len(a0)))]
    out0 = f0 < 0
    out1 = out0[:, _next(np.arange(len(a0)))]
    both = out0 & out1
    empty = both[0]
    for b in both[1:]:  # an edge of P outside an edge of Q is outside Q
        empty = empty | b
    enter, leave = out0 > out1, out1 > out0
    den = f0 - f1
    np.copyto(den, 1.0, where=~(np.abs(den) > 0))
    lam = f0 / den
    lo, hi = np.zeros(a0.shape), np.ones(a0.shape)
    for j in range(len(lam)):  # in Q's edge order, as the Dual path: the same running bounds
        lo = np.where(enter[j] & (lam[j] > lo), lam[j], lo)
        hi = np.where(leave[j] & (lam[j] < hi), lam[j], hi)
    p0, p1 = a0 + ab0 * lo, a1 + ab1 * lo
    q0, q1 = a0 + ab0 * hi, a1 + ab1 * hi
    terms = np.where(~empty & (hi > lo), p0 * q1 - p1 * q0, 0.0)
    total = np.zeros(terms.shape[1])
    for t in terms:  # summed in order, as the Dual path
        total = total + t
    return total


def pad_values(
    x: np.ndarray,
    polys: np.ndarray,
    corner: np.ndarray,
    end: np.ndarray,
    other_corner: np.ndarray,
    shrink: float,
    width: float,
    reach: float,
    need: float,
) -> np.ndarray:
    """The values of ``print_rows.pad_rows`` (same arguments), to the same bits."""
    n = polys.shape[1] // 2
    rows = np.arange(len(polys))
    x = np.asarray(x)
    x0, x1 = x[:, 0], x[:, 1]

    def at(k):
        i = polys[rows, k]
        return x0[i], x1[i]

    def sine(k, base):
        v0, v1 = at(base + k)
        a0, a1 = at(base + (k + 1) % n)
        b0, b1 = at(base + (k - 1) % n)
        a0, a1, b0, b1 = a0 - v0, a1 - v1, b0 - v0, b1 - v1
        s = (a0 * b1 - a1 * b0) / np.sqrt((a0 * a0 + a1 * a1) * (b0 * b0 + b1 * b1))
        return np.where(a0 * b0 + a1 * b1 < 0, 1.0, s)

    p0, p1 = at(corner)
    q0, q1 = at(end)
    ev0, ev1 = q0 - p0, q1 - p1
    ln = np.sqrt(ev0 * ev0 + ev1 * ev1)
    e0, e1 = ev0 / ln, ev1 / ln
    s_own, s_other = sine(corner, 0), sine(other_corner, n)
    t0 = shrink / np.where(s_own < s_other, s_own, s_other)
    t1 = t0 + width
    R = reach + shrink
    corners = ((t0, -R), (t1, -R), (t1, R), (t0, R))
    band = (
        np.stack([p0 + e0 * t - e1 * r for t, r in corners]),
        np.stack([p1 + e1 * t + e0 * r for t, r in corners]),
    )
    own = polys[:, :n].T
    tile = _shrunk(x0[own], x1[own], shrink)
    area = (_clipped_boundary(band, tile) + _clipped_boundary(tile, band)) * 0.5
    return area * (1.0 / width) - need / width


def _shrunk(c0: np.ndarray, c1: np.ndarray, shrink: float) -> tuple:
    """``print_rows._shrunk``: every corner moved by ``shrink`` times its mitre vector."""
    if not shrink:
        return c0, c1
    m0, m1 = _mitre_vectors(c0, c1)
    return c0 + m0 * shrink, c1 + m1 * shrink


def _at(x: np.ndarray, quads: np.ndarray, rows: np.ndarray, k) -> tuple:
    """Corner ``k`` (per row) of quads ``rows`` (as ``dual.dual_corner``, values only)."""
    p = x[quads[rows, k]]
    return p[:, 0], p[:, 1]


def _dot(a: tuple, b: tuple) -> np.ndarray:
    return a[0] * b[0] + a[1] * b[1]


def _mitres(x, quads) -> tuple:
    """``fabrication._mitre`` at every corner of every polygon of ``quads`` (all of its nodes), once: ``(x, y)``
    arrays indexed ``[corner, polygon]`` (the rows ask each corner's mitre twice)."""
    return _mitre_vectors(x[quads.T, 0], x[quads.T, 1])


def _mitre_vectors(c0: np.ndarray, c1: np.ndarray) -> tuple:
    """The mitre vector at every corner of ``(x, y)`` arrays indexed ``[corner, polygon]``."""
    na = _normal(_next(c0, -1), _next(c1, -1), c0, c1)
    nb = _normal(c0, c1, _next(c0), _next(c1))
    s = _dot(na, nb) + 1.0
    return (na[0] + nb[0]) / s, (na[1] + nb[1]) / s


def _smooth_max(a: np.ndarray, b: np.ndarray, eps: float) -> np.ndarray:
    """``fabrication.smooth_max``."""
    h = (a - b) * 0.5
    return (a + b) * 0.5 + np.sqrt(h * h + eps * eps) - eps


def edge_index(quads: np.ndarray, sel: np.ndarray | None = None):
    """``(rows, e)``: the quad and edge of every quad's edge e (quad-major; rows ``sel`` of them only)."""
    n = quads.shape[1]
    rows = np.repeat(np.arange(len(quads)), n)
    e = np.tile(np.arange(n), len(quads))
    if sel is not None:
        rows, e = rows[sel], e[sel]
    return rows, e


def _edges(x, quads, sel):
    """``fabrication._edges``: rows, edge index and the two ends of every quad's edge (rows ``sel``)."""
    rows, e = edge_index(quads, sel)
    n = quads.shape[1]
    return rows, e, _at(x, quads, rows, e), _at(x, quads, rows, (e + 1) % n)


def width_values(x, quads, width: float, shrink: float, sel, smooth: float) -> np.ndarray:
    """The values of ``fabrication.width_rows`` (its smooth max's ``smooth``), to the same bits."""
    x = np.asarray(x)
    n = quads.shape[1]
    rows, e, a, b = _edges(x, quads, sel)
    nrm = _normal(*a, *b)
    mitre = _mitres(x, quads) if shrink else None
    far = []
    for off in range(2, n):
        j = (e + off) % n
        q0, q1 = _at(x, quads, rows, j)
        g = _dot(nrm, (q0 - a[0], q1 - a[1]))
        if mitre is not None:
            g = g + (_dot(nrm, (mitre[0][j, rows], mitre[1][j, rows])) - 1.0) * shrink
        far.append(g)
    top = far[0]
    for g in far[1:]:
        top = _smooth_max(top, g, smooth)
    return top - width


def shrunk_edge_values(x, quads, shrink: float, min_edge: float, sel) -> np.ndarray:
    """The values of ``fabrication.shrunk_edge_rows``, to the same bits."""
    x = np.asarray(x)
    rows, e, a, b = _edges(x, quads, sel)
    E0, E1 = b[0] - a[0], b[1] - a[1]
    ln = np.sqrt(E0 * E0 + E1 * E1)
    u = E0 / ln, E1 / ln
    m0, m1 = _mitres(x, quads)
    f = (e + 1) % quads.shape[1]
    ma, mb = (m0[e, rows], m1[e, rows]), (m0[f, rows], m1[f, rows])
    return ln + _dot(u, (mb[0] - ma[0], mb[1] - ma[1])) * shrink - min_edge


def _strip_box(x, quads, t, c, end):
    """``fabrication._strip_box``: the hinge corner, its seam's unit direction and that edge's inward normal."""
    p = _at(x, quads, t, c)
    q0, q1 = _at(x, quads, t, end)
    ev0, ev1 = q0 - p[0], q1 - p[1]
    ln = np.sqrt(ev0 * ev0 + ev1 * ev1)
    e0, e1 = ev0 / ln, ev1 / ln
    sgn = np.where(end == (c + 1) % quads.shape[1], 1.0, -1.0)
    return p, (e0, e1), (-e1 * sgn, e0 * sgn)


def strip_values(x, quads, pairs: tuple, box: tuple, soft: float, smooth: float) -> np.ndarray:
    """The values of ``fabrication.strip_rows`` (``pairs``: its ``t, ch, eh, ck, ek``; its ``SOFT`` and
    ``STRIP_SMOOTH``), to the same bits."""
    x = np.asarray(x)
    t, ch, eh, ck, ek = pairs
    a0, along, across, clearance = box
    ph, e_h, n_h = _strip_box(x, quads, t, ch, eh)
    pk, e_k, n_k = _strip_box(x, quads, t, ck, ek)

    # the four axes at once, a row each: the same operations per axis as the Dual path's loop over them
    u = np.stack([e_h[0], n_h[0], e_k[0], n_k[0]]), np.stack([e_h[1], n_h[1], e_k[1], n_k[1]])

    def extents(e, n):
        eu, nu = _dot(e, u), _dot(n, u)
        re, rn = np.sqrt(eu * eu + soft * soft), np.sqrt(nu * nu + soft * soft)
        base = eu * a0
        lower = base + (eu - re) * 0.5 * along + (nu - rn) * 0.5 * across
        return lower, base + (eu + re) * 0.5 * along + (nu + rn) * 0.5 * across

    dp = _dot((pk[0] - ph[0], pk[1] - ph[1]), u)
    (lo_h, hi_h), (lo_k, hi_k) = extents(e_h, n_h), extents(e_k, n_k)
    # the balanced tree of smooth maxima: each axis's two gaps, then the axes in pairs, then the two pairs
    top = _smooth_max(dp + lo_k - hi_h, -dp + lo_h - hi_k, smooth)
    top = _smooth_max(top[0::2], top[1::2], smooth)
    return _smooth_max(top[0], top[1], smooth) - clearance
