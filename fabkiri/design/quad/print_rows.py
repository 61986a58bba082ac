"""Fabrication rows of printed strips: the pad each strip glues onto each of its two tiles.

``print`` (``fabkiri.fabricate.print.geometry.strip_outlines``) lays the strip of hinge h as a band across its
closed seam: ``[t0, t0 + w]`` along the seam from the hinge point, ``reach + d`` either side of it, and keeps
the part inside the two tiles shrunk by ``d`` (half the printer's gap). The pad on tile A is the band
clipped by A shrunk by ``d``; ``print`` refuses a hinge whose pad is under ``0.25 w min(reach, w)`` mm².

A tile is rigid, so its pad is the same in the deployed frame: the band anchored at the tile's hinge corner
along its seam edge (the fold rule's edge of the printed closed state). ``t0`` is where the seam line enters
the two tiles shrunk by ``d``: ``d / sin`` of the sharper of the two hinge corners (``d`` where both are
obtuse). :func:`pad_rows` is that area, exactly (the clipped polygon's boundary integral, Cyrus-Beck clipping
of each edge), divided by ``w`` (a mean pad depth, a length like every other row), minus the plan's.
Gradients are carried forward (:class:`~..core.dual.Dual`) and checked against finite differences and the
area ``print`` measures in ``tests/design/test_print_rows.py``.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from ..core.dual import (
    Dual,
    dual_corner,
    inward_normal,
    is_values_only,
    roll,
    stack,
    vec_dot,
    vec_sub,
)
from .constraints import Family, Stencils
from .row_family import ineq_family, pick
from .row_values import pad_values

if TYPE_CHECKING:  # fabrication.py builds on this module's rows
    from .fabrication import FabricationLimits


def where(cond: np.ndarray, a: Dual, b: Dual) -> Dual:
    """Row-wise choice between two :class:`~..core.dual.Dual` values."""
    g = None if a.g is None else np.where(cond[..., None], a.g, b.g)
    return Dual(np.where(cond, a.v, b.v), g)


def _cross(a, b) -> Dual:
    return a[0] * b[1] - a[1] * b[0]


def _stacked(points: list) -> tuple[Dual, Dual]:
    """A polygon given as a list of ``(x, y)`` Duals as one ``(x, y)`` pair with a column per corner."""
    return stack([p[0] for p in points]), stack([p[1] for p in points])


def _column(P: tuple, j: int) -> tuple[Dual, Dual]:
    return P[0].take([j]), P[1].take([j])


def _clipped_boundary(P: tuple, Q: tuple) -> Dual:
    """Twice the signed area the edges of convex CCW polygon ``P`` contribute inside convex CCW ``Q`` (both a
    column per corner): every edge of ``P`` at once clipped to each edge of ``Q`` in turn (Cyrus-Beck), then
    ``cross(start, end)`` of what is left, summed over the edges in order."""
    a = P
    b = (roll(P[0], -1), roll(P[1], -1))
    ab = vec_sub(b, a)
    zero = Dual.lift(0.0, P[0])
    lo, hi = zero, Dual.lift(1.0, P[0])
    empty = np.zeros(P[0].v.shape, dtype=bool)
    nq = Q[0].v.shape[1]
    for j in range(nq):
        c, d = _column(Q, j), _column(Q, (j + 1) % nq)
        n = (c[1] - d[1], d[0] - c[0])  # inward (left) normal of the CCW edge c -> d
        f0, f1 = vec_dot(n, vec_sub(a, c)), vec_dot(n, vec_sub(b, c))
        out0, out1 = f0.v < 0, f1.v < 0
        empty |= out0 & out1
        den = f0 - f1
        den = where(np.abs(den.v) > 0, den, Dual.lift(1.0, den))
        lam = f0 / den
        lo = where(out0 & ~out1 & (lam.v > lo.v), lam, lo)
        hi = where(out1 & ~out0 & (lam.v < hi.v), lam, hi)
    p = (a[0] + ab[0] * lo, a[1] + ab[1] * lo)
    q = (a[0] + ab[0] * hi, a[1] + ab[1] * hi)
    terms = where(~empty & (hi.v > lo.v), _cross(p, q), zero)
    total = Dual.lift(0.0, terms.take(0))
    for i in range(terms.v.shape[1]):
        total = total + terms.take(i)
    return total


def _area(P: tuple, Q: tuple) -> Dual:
    return (_clipped_boundary(P, Q) + _clipped_boundary(Q, P)) * 0.5


def clipped_area(P: list, Q: list) -> Dual:
    """Area of the intersection of two convex counter-clockwise polygons (lists of ``(x, y)`` Duals)."""
    return _area(_stacked(P), _stacked(Q))


def _sine(x, polys, rows, k, n, base) -> Dual:
    """sin of corner ``k`` (per row) of the ``n``-gon at nodes ``base..base+n`` of ``polys``' rows, 1 where it
    is obtuse (the seam line is then ``shrink`` from that tile's edge once ``t >= shrink``)."""
    v = dual_corner(x, polys, rows, base + k)
    a = vec_sub(dual_corner(x, polys, rows, base + (k + 1) % n), v)
    b = vec_sub(dual_corner(x, polys, rows, base + (k - 1) % n), v)
    s = _cross(a, b) / (vec_dot(a, a) * vec_dot(b, b)).sqrt()
    return where(vec_dot(a, b).v < 0, Dual.lift(1.0, s), s)


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
) -> Dual:
    """Pad area over ``width`` minus ``need`` over ``width`` for every pad of :func:`pad_polygons`: the band
    ``[t0, t0 + width]`` along the seam (own ``corner`` to ``end``), ``reach + shrink`` either side of it,
    clipped by the own tile shrunk by ``shrink`` (mitre); ``t0`` from both tiles' hinge corners. A residual-only
    call takes :func:`~.row_values.pad_values` (the same bits, a fraction of the time)."""
    if is_values_only(x):
        return Dual(
            pad_values(x, polys, corner, end, other_corner, shrink, width, reach, need), None
        )
    n = polys.shape[1] // 2
    rows = np.arange(len(polys))
    p = dual_corner(x, polys, rows, corner)
    ev = vec_sub(dual_corner(x, polys, rows, end), p)
    ln = vec_dot(ev, ev).sqrt()
    e = (ev[0] / ln, ev[1] / ln)
    s_own = _sine(x, polys, rows, corner, n, 0)
    s_other = _sine(x, polys, rows, other_corner, n, n)
    sharper = where(s_own.v < s_other.v, s_own, s_other)
    t0 = Dual.lift(shrink, sharper) / sharper
    t1 = t0 + width
    R = reach + shrink
    # t e + r (-e_y, e_x) from the hinge corner: (t0, -R), (t1, -R), (t1, R), (t0, R) run counter-clockwise
    band = [
        (p[0] + e[0] * t - e[1] * r, p[1] + e[1] * t + e[0] * r)
        for t, r in ((t0, -R), (t1, -R), (t1, R), (t0, R))
    ]
    return _area(_stacked(band), _shrunk(x, polys, rows, n, shrink)) / width - need / width


def _shrunk(x, polys, rows, n, shrink) -> tuple[Dual, Dual]:
    """The own tile (the first ``n`` nodes of ``polys``) shrunk by ``shrink``, a column per corner: corner k
    moves by ``shrink`` times its mitre vector (as :func:`~.fabrication._mitre`, every corner at once)."""
    c = _stacked([dual_corner(x, polys, rows, np.full(len(rows), k)) for k in range(n)])
    if not shrink:
        return c
    prev = (roll(c[0], 1), roll(c[1], 1))
    nxt = (roll(c[0], -1), roll(c[1], -1))
    na, nb = inward_normal(prev, c), inward_normal(c, nxt)
    s = 1.0 + vec_dot(na, nb)
    m = (na[0] + nb[0]) / s, (na[1] + nb[1]) / s
    return c[0] + m[0] * shrink, c[1] + m[1] * shrink


def pad_args(
    tiles: np.ndarray, hinge_tiles: np.ndarray, hinge_corner: np.ndarray, fold_ends: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """``(polys, corner, end, other_corner)`` of :func:`pad_rows` for every pad (hinge-major, A's then B's)."""
    polys = pad_polygons(tiles, hinge_tiles)
    return polys, hinge_corner.ravel(), fold_ends.ravel(), hinge_corner[:, ::-1].ravel()


def strip_pad(limits: FabricationLimits, unit_mm: float) -> tuple[float, float, float, float]:
    """``(shrink, width, reach, need)`` of :func:`pad_rows` for ``limits`` in units of ``unit_mm``."""
    u = unit_mm
    return (
        limits.shrink_mm / u,
        limits.strip_width_mm / u,
        limits.strip_reach_mm / u,
        limits.strip_pad_mm2 / (u * u),
    )


def families(st: Stencils, nv: int, limits: FabricationLimits, unit_mm: float) -> list[Family]:
    """The pad rows of a quad design (seams of closed state ``limits.print_state``, the one ``print`` makes)."""
    if limits.strip_pad_mm2 <= 0 or limits.strip_width_mm <= 0 or not len(st.hinge_tiles):
        return []
    args = pad_args(
        st.tiles, st.hinge_tiles, st.hinge_corner, st.folds[limits.print_state].fold_corner_ends
    )
    box = strip_pad(limits, unit_mm)
    polys = args[0]
    return [
        ineq_family(
            "fabrication_strip_pads",
            polys,
            lambda x, sel: pad_rows(x, *pick(args, sel), *box),
            nv,
            {"quad_of_row": np.arange(len(polys))},
        )
    ]
