"""Inverse design of kagome patterns: a reconfigurable kagome whose deployed outline follows a target.

Unknowns are the deployed nodes in normalised units (the standard tile edge is 1). The equalities
are both closed states' edge pairs and rings (:mod:`fabkiri.design.kagome`); the fit asks every free
corner (boundary tip) to lie on the target curve (its signed distance). The solve has two stages:

1. a penalty least-squares (``scipy.optimize.least_squares``, sparse analytic Jacobian): the
   equalities weighted by ``EQ_WEIGHT``, the tips' signed distances, and a small pull towards the
   initial guess that keeps the problem well posed along the curve;
2. a projection onto the equalities by minimum-norm Gauss-Newton steps, so the design closes in
   both states to rounding (the fit moves by the tiny amount the penalty left).

The initial guess maps the standard R x C kagome onto the target: its boundary tips spread along the
target by arc length, the other nodes by a harmonic (Tutte-style) embedding.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
from scipy import sparse
from scipy.optimize import least_squares
from scipy.sparse.linalg import spsolve

from ..pattern import conformance as pc
from ..pattern.model import Pattern
from . import kagome as K
from .target_curve import Target

EQ_WEIGHT = 30.0  # penalty weight of the equalities in stage 1 (normalised units)
PULL = 1e-3  # pull towards the initial guess, per coordinate
TIP_PULL = 0.1  # the tips' pull towards their initial places: keeps them spread along the target
MIN_AREA = 0.2  # smallest tile area (normalised; the standard triangle's is 0.433) before a penalty


@dataclass(frozen=True)
class KagomeDesign:
    """A designed kagome pattern (mm) and how the solve went."""

    pattern: Pattern
    max_equality: float  # largest |edge pair| (normalised squared length) or |ring| (rad)
    max_tip_distance_mm: float  # largest distance of a boundary tip from the target
    iterations: int
    converged: bool  # the projection onto the equalities reached |r| <= 1e-13
    penalty_status: int  # scipy least_squares status of stage 1 (0: stopped at max_nfev)


def initial_nodes(standard: Pattern, target: Target) -> np.ndarray:
    """The standard kagome mapped onto the target, normalised units: its boundary tips placed on the
    target at the arc-length fractions they have along the standard outline (from the direction of
    the first tip), every other node where the tile-edge graph's Laplacian puts it (a Tutte-style
    harmonic embedding, free of fold-overs for a convex target)."""
    top = standard.topology
    x = standard.nodes / standard.tile_size
    order = pc.boundary_tip_order(top.tiles, top.hole_nodes, top.hole_tiles, top.free_nodes)
    tips = x[order]
    seg = np.linalg.norm(np.roll(tips, -1, 0) - tips, axis=1)
    frac = np.r_[0.0, np.cumsum(seg)[:-1]] / seg.sum()
    curve = target.sample(4096) / standard.tile_size
    centre = curve.mean(0)
    start = int(np.argmin(np.abs(_angle(curve - centre) - _angle(tips[:1] - x.mean(0)))))
    curve = np.roll(curve, -start, axis=0)
    arc = np.r_[0.0, np.cumsum(np.linalg.norm(np.diff(np.vstack([curve, curve[:1]]), axis=0), axis=1))]
    closed = np.vstack([curve, curve[:1]])
    placed = np.stack([np.interp(frac * arc[-1], arc, closed[:, k]) for k in range(2)], -1)
    # harmonic interior: L x = 0 on the tile-edge graph with the tips fixed
    n = top.n_nodes
    e = np.stack([top.tiles, np.roll(top.tiles, -1, 1)], -1).reshape(-1, 2)
    W = sparse.csr_matrix((np.ones(len(e)), (e[:, 0], e[:, 1])), shape=(n, n))
    W = ((W + W.T) > 0).astype(float)
    L = (sparse.diags(np.asarray(W.sum(1)).ravel()) - W).tocsr()
    free = np.setdiff1d(np.arange(n), order)
    out = np.zeros((n, 2))
    out[order] = placed
    rhs = -L[free][:, order] @ placed
    out[free] = np.column_stack([spsolve(L[free][:, free].tocsc(), rhs[:, k]) for k in range(2)])
    return out


def _angle(v: np.ndarray) -> np.ndarray:
    return np.arctan2(v[:, 1], v[:, 0])


def _tip_family(target: Target, tips: np.ndarray, scale: float, nv: int):
    """Signed distances (normalised) of the tips from the target (mm = normalised × scale)."""
    def fn(x):
        _, _, d, grad = target.project(x[tips] * scale)
        rows = np.repeat(np.arange(len(tips)), 2)
        cols = (2 * tips[:, None] + np.arange(2)[None, :]).ravel()
        J = sparse.csr_matrix((grad.ravel(), (rows, cols)), shape=(len(tips), 2 * nv))
        return d / scale, J
    return fn


def design(standard: Pattern, target: Target, *, max_nfev: int = 200) -> KagomeDesign:
    """A reconfigurable kagome on ``standard``'s tiles whose deployed tips lie on ``target`` (mm).

    ``standard`` fixes the lattice and the tile size (its mm scale); ``target`` is in mm.
    """
    fams = K.families(standard, (1, 2))
    top = standard.topology
    nv = top.n_nodes
    scale = standard.tile_size
    x0 = initial_nodes(standard, target)
    tips = _tip_family(target, top.free_nodes, scale, nv)

    pull: np.ndarray = np.full((nv, 2), PULL)
    pull[top.free_nodes] = TIP_PULL
    pull = pull.ravel()
    tl = top.tiles

    def areas(x):
        """Tile areas below MIN_AREA (0 above) and their gradient: keeps tiles from folding over."""
        p0, p1, p2 = x[tl[:, 0]], x[tl[:, 1]], x[tl[:, 2]]
        a = 0.5 * ((p1[:, 0] - p0[:, 0]) * (p2[:, 1] - p0[:, 1]) - (p1[:, 1] - p0[:, 1]) * (p2[:, 0] - p0[:, 0]))
        short = np.minimum(a - MIN_AREA, 0.0)
        act = (a < MIN_AREA).astype(float)[:, None]
        g = 0.5 * np.stack([np.stack([p1[:, 1] - p2[:, 1], p2[:, 0] - p1[:, 0]], -1),
                            np.stack([p2[:, 1] - p0[:, 1], p0[:, 0] - p2[:, 0]], -1),
                            np.stack([p0[:, 1] - p1[:, 1], p1[:, 0] - p0[:, 0]], -1)], 1) * act[:, None]
        cols = (2 * tl[:, :, None] + np.arange(2)).reshape(len(tl), -1)
        J = sparse.csr_matrix((g.reshape(len(tl), -1).ravel(), (np.repeat(np.arange(len(tl)), 6), cols.ravel())),
                              shape=(len(tl), 2 * nv))
        return short, J

    def residuals(v):
        x = v.reshape(-1, 2)
        r, _ = K.stacked(fams, x)
        d, _ = tips(x)
        return np.concatenate([EQ_WEIGHT * r, d, pull * (v - x0.ravel()), areas(x)[0]])

    def jacobian(v):
        x = v.reshape(-1, 2)
        _, J = K.stacked(fams, x)
        _, Jt = tips(x)
        return sparse.vstack([EQ_WEIGHT * J, Jt, sparse.diags(pull), areas(x)[1]]).tocsr()

    sol = least_squares(residuals, x0.ravel(), jac=jacobian, method="trf", tr_solver="lsmr",
                        x_scale=1.0, max_nfev=max_nfev, xtol=1e-12, ftol=1e-12, gtol=1e-12)
    x, converged, it = _project(fams, sol.x.reshape(-1, 2))

    r, _ = K.stacked(fams, x)
    d, _ = tips(x)
    pattern = replace(standard, nodes=x * scale, contracted={}, name=f"kagome {target.name}",
                      design={"target": target.to_dict(), "solver": "kagome penalty + projection"})
    return KagomeDesign(pattern, float(np.abs(r).max()), float(np.abs(d).max() * scale),
                        int(sol.nfev) + it, converged, int(sol.status))


def _project(fams, x: np.ndarray, tol: float = 1e-13, max_iter: int = 30):
    """Minimum-norm Gauss-Newton steps onto the equalities; (x, converged, steps)."""
    for k in range(max_iter):
        r, J = K.stacked(fams, x)
        if np.abs(r).max(initial=0.0) <= tol:
            return x, True, k
        dx = np.linalg.lstsq(J.toarray(), -r, rcond=1e-10)[0]
        x = x + dx.reshape(x.shape)
    r, _ = K.stacked(fams, x)
    return x, bool(np.abs(r).max(initial=0.0) <= tol), max_iter

