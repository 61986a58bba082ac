"""Initial guesses (docs/algorithm.md#initial-guesses), in normalised units (standard tile edge 1).

* ``standard``: the standard deployed pattern (ψ = π/4) scaled so its bounding
  box spans the target's larger dimension; it satisfies every equality exactly.
* ``rescaled``: the standard pattern scaled so the polygon of its boundary tips
  has the target's area (the spec's λ·X_std with λ chosen from the target).
* ``conformal``: a discrete harmonic map of the standard pattern onto the
  target. Boundary tips go to their arcs by relative position along their side;
  every other node is the average of its tile-graph neighbours (a Tutte-style
  embedding, solved with scipy.sparse). It violates the constraints and is only
  a starting point, but it puts the tiles where the target needs them.
* ``coarse``: coarse to fine. The same problem is solved at half resolution
  (recursively down to 16 tiles a side, then from ``rescaled``) and mapped onto
  the fine standard pattern scaled to the coarse one's extent, tile by tile
  (:func:`coarse_tile_map`; a node map breaks the hinge sums by ~1 rad). The
  coarse solve lives in ``solve.py`` (it needs the solver).
"""

from __future__ import annotations

import numpy as np
from scipy import sparse
from scipy.sparse.linalg import spsolve

from ...errors import InputError, Param, SolveError
from ...pattern import geometry
from ..core.stencils import Stencils
from ..targets.curve import Target
from .inverse_map import inverse_harmonic_map

INITS = ("standard", "rescaled", "conformal", "coarse")


def tip_polygon(x: np.ndarray, st: Stencils) -> np.ndarray:
    """Boundary tips in CCW order around the pattern."""
    tips = st.tip_nodes
    side = st.tip_side
    p = x[tips]
    key = np.select(
        [side == 0, side == 1, side == 2, side == 3], [p[:, 0], p[:, 1], -p[:, 0], -p[:, 1]]
    )
    order = np.lexsort((key, side))
    return p[order]


def polygon_area(p: np.ndarray) -> float:
    return 0.5 * float(np.sum(p[:, 0] * np.roll(p[:, 1], -1) - np.roll(p[:, 0], -1) * p[:, 1]))


def side_fractions(x: np.ndarray, st: Stencils) -> np.ndarray:
    """Relative position in (0, 1) of every boundary tip along its side, CCW."""
    p = x[st.tip_nodes]
    lo, hi = x.min(0), x.max(0)
    fx = (p[:, 0] - lo[0]) / (hi[0] - lo[0])
    fy = (p[:, 1] - lo[1]) / (hi[1] - lo[1])
    s = st.tip_side
    return np.select([s == 0, s == 1, s == 2, s == 3], [fx, fy, 1 - fx, 1 - fy])


def scale_for(base: np.ndarray, st: Stencils, target: Target, how: str) -> float:
    """Tile size (mm) of the initial guess for ``target`` (mm)."""
    if how == "standard":
        ext = (base.max(0) - base.min(0)).max()
        return target.size / ext
    return float(np.sqrt(abs(target.area) / abs(polygon_area(tip_polygon(base, st)))))


def harmonic_map(base: np.ndarray, st: Stencils, target: Target) -> np.ndarray:
    """Tutte-style harmonic map of the pattern onto ``target`` (same units as target)."""
    n = len(base)
    tl = st.tiles
    a = tl.ravel()
    b = np.roll(tl, -1, 1).ravel()
    c = np.roll(tl, 2, 1).ravel()  # diagonals keep tiles from collapsing to lines
    i = np.concatenate([a, b, a, c])
    j = np.concatenate([b, a, c, a])
    w = np.concatenate([np.ones(2 * len(a)), 0.5 * np.ones(2 * len(a))])
    W = sparse.csr_matrix((w, (i, j)), shape=(n, n))
    W.sum_duplicates()
    L = sparse.diags(np.asarray(W.sum(1)).ravel()) - W
    tips = st.tip_nodes
    f = side_fractions(base, st)
    u = np.empty(len(tips))
    for s in range(4):
        sel = st.tip_side == s
        lo, hi = target.arc_range(s)
        u[sel] = lo + f[sel] * (hi - lo)
    fixed = target.point(u)
    free = np.setdiff1d(np.arange(n), tips)
    L = L.tocsr()
    Lff = L[free][:, free].tocsc()
    Lfb = L[free][:, tips]
    out = np.empty((n, 2))
    out[tips] = fixed
    rhs = -(Lfb @ fixed)
    out[free] = np.column_stack([spsolve(Lff, rhs[:, 0]), spsolve(Lff, rhs[:, 1])])
    return out


def coarse_tile_map(
    base_coarse: np.ndarray,
    x_coarse: np.ndarray,
    tiles_coarse: np.ndarray,
    cols_coarse: int,
    base_fine: np.ndarray,
    tiles_fine: np.ndarray,
    cols_fine: int,
) -> np.ndarray:
    """Coarse-to-fine by tiles: fine tile centres go through the piecewise-linear centre map; each fine
    tile takes the rotation and scale (a complex factor) of the nearest coarse tile of its checkerboard
    parity, so the alternating counter-rotation of the deployed pattern survives; shared nodes average."""
    from scipy.interpolate import LinearNDInterpolator

    from ...kdtree import KDTree

    lo_c, hi_c = base_coarse.min(0), base_coarse.max(0)
    lo_f, hi_f = base_fine.min(0), base_fine.max(0)
    k = (hi_c - lo_c) / (hi_f - lo_f)
    bf = lo_c + (base_fine - lo_f) * k
    Pc, Qc = base_coarse[tiles_coarse], x_coarse[tiles_coarse]
    cc, qc = Pc.mean(1), Qc.mean(1)
    pz = (Pc - cc[:, None]) @ np.array([1, 1j])
    qz = (Qc - qc[:, None]) @ np.array([1, 1j])
    a = (np.conj(pz) * qz).sum(1) / (np.abs(pz) ** 2).sum(1)
    Pf = bf[tiles_fine]
    cf = Pf.mean(1)
    lin = LinearNDInterpolator(cc, qc)(cf)
    bad = ~np.isfinite(lin).all(1)
    if (
        bad.any()
    ):  # outside the hull of coarse centres: extend by the nearest coarse tile's similarity
        _, nn = KDTree(cc).query(cf[bad])
        z = qc[nn] @ np.array([1, 1j]) + a[nn] * ((cf[bad] - cc[nn]) @ np.array([1, 1j]))
        lin[bad] = np.stack([z.real, z.imag], -1)
    par_c = np.add(*np.divmod(np.arange(len(tiles_coarse)), cols_coarse)) % 2
    par_f = np.add(*np.divmod(np.arange(len(tiles_fine)), cols_fine)) % 2
    af = np.empty(len(tiles_fine), complex)
    for p in (0, 1):
        sc, sf = np.flatnonzero(par_c == p), np.flatnonzero(par_f == p)
        _, idx = KDTree(cc[sc]).query(cf[sf])
        af[sf] = a[sc[idx]]
    off = (Pf - cf[:, None]) @ np.array([1, 1j])
    wz = (lin @ np.array([1, 1j]))[:, None] + af[:, None] * off
    out = np.zeros((len(base_fine), 2))
    cnt = np.zeros(len(base_fine))
    np.add.at(out, tiles_fine.ravel(), np.stack([wz.real.ravel(), wz.imag.ravel()], -1))
    np.add.at(cnt, tiles_fine.ravel(), 1.0)
    return out / cnt[:, None]


def initial_guess(
    base: np.ndarray, st: Stencils, target: Target | None, how: str
) -> tuple[np.ndarray, float]:
    """Initial node positions (normalised) and the tile size L0 (mm) of the normalisation.

    ``base`` is the standard deployed pattern with unit tiles centred on the
    origin. Without a deployed target the standard pattern is returned as is.
    """
    if how not in INITS:
        raise InputError(Param("init"), f" must be one of {', '.join(INITS)}, not {how!r}")
    if target is None:
        return base.copy(), 1.0
    lo, hi = target.bbox
    centre = 0.5 * (lo + hi)
    if how == "coarse":
        raise SolveError(
            "the coarse initial guess needs the solver (fabkiri.design.quad.solve builds it)"
        )
    if how in ("standard", "rescaled"):
        L0 = scale_for(base, st, target, how)
        return base + centre / L0, L0
    L0 = scale_for(base, st, target, "rescaled")
    x = harmonic_map(base, st, target.transformed(1.0 / L0))
    area = geometry.signed_areas(x[st.tiles])
    # a non-convex target split elsewhere than by default (design/quad/corner_split.py): map the target onto
    # the lattice instead (no folds); on the default split an L's reflex corner shares an arc with a
    # convex one and the solve from that map did not converge (8x8: residual 0.67)
    off = np.mod(target.corners - target.default_corner_split() + 0.5, 1.0) - 0.5  # parameters wrap
    resplit = bool(np.abs(off).max() > 1e-9)
    if (area <= 0).any() and resplit:
        tgt = target.transformed(1.0 / L0)
        x = inverse_harmonic_map(base, st.tip_nodes, st.tip_side, tgt, st.tiles)
        area = geometry.signed_areas(x[st.tiles])
    if (area <= 0).any():
        raise SolveError(
            f"the harmonic map onto {target.name!r} folds {int((area <= 0).sum())} tiles "
            f"(a non-convex target); use --init rescaled or standard"
        )
    return x, L0
