"""The smooth-shape-change regulariser (docs/algorithm.md#objective) as least-squares residuals.

    E_reg(x) = (1/|Π|) Σ_{(T,U)∈Π} Σ_k [(ℓ_T,k - ℓ_U,k)² + (θ_T,k - θ_U,k)²]

over pairs of same-parity tiles two apart in a row or a column. It is written
as ``E_reg = |r|²`` with ``r`` the stacked differences divided by ``√|Π|``, so
the solver can treat it with Gauss-Newton like every other family. Lengths are
in normalised units (initial tile edge 1).

Every tile corner's length and angle is computed once (:func:`tile_corners`)
and the rows are differences of those: a tile sits in up to four pairs.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ...pattern.geometry import cross2, dot2, wrap_angle
from .constraints import TWO_PI, Family, Stencils, regularizer_pairs


@dataclass(frozen=True)
class TileCorners:
    """Per tile corner ``(T, 4)`` of quads ``x[quads]``: edge ``A`` to the next corner (edge k runs from
    corner k to k+1), edge ``B`` to the previous one, their lengths, the interior angle ``theta`` (turning
    ``A`` onto ``B``), ``cross(A, B)`` and the angle's gradients ``ga``, ``gb`` with respect to ``A``, ``B``."""

    A: np.ndarray
    B: np.ndarray
    length: np.ndarray
    theta: np.ndarray
    cross: np.ndarray
    ga: np.ndarray
    gb: np.ndarray


NEXT = np.array([1, 2, 3, 0])  # the corner after / before corner k of a CCW quad
PREV = np.array([3, 0, 1, 2])


def tile_corners(x: np.ndarray, quads: np.ndarray) -> TileCorners:
    """:class:`TileCorners` of the quads ``x[quads]`` (the same formulas as ``constraints.corner_angle``)."""
    P = x[quads]
    A = P[:, NEXT] - P
    B = P[:, PREV] - P
    Ax, Ay, Bx, By = A[..., 0], A[..., 1], B[..., 0], B[..., 1]
    la2 = dot2(A, A)
    lb2 = la2[:, PREV]
    cr = cross2(A, B)
    th = np.mod(
        np.arctan2(cr, dot2(A, B)), TWO_PI
    )  # geometry.signed_angle, keeping its cross product
    ga = np.empty_like(A)
    ga[..., 0], ga[..., 1] = Ay / la2, -Ax / la2
    gb = np.empty_like(B)
    gb[..., 0], gb[..., 1] = -By / lb2, Bx / lb2
    return TileCorners(A, B, np.sqrt(la2), th, cr, ga, gb)


@dataclass(frozen=True)
class RegularizerRows:
    """Row ``i`` of each half (lengths, then angles) compares flat tile corner ``first[i]`` with
    ``second[i]`` (index ``4 t + k``), weighted by ``weight`` = 1/√|Π|."""

    first: np.ndarray
    second: np.ndarray
    weight: float

    def residual(self, tc: TileCorners) -> np.ndarray:
        ln, th = tc.length.reshape(-1), tc.theta.reshape(-1)
        i, j, w = self.first, self.second, self.weight
        return w * np.concatenate([ln[i] - ln[j], wrap_angle(th[i] - th[j])])


def regularizer_rows(st: Stencils) -> RegularizerRows:
    pairs = regularizer_pairs(st)
    k = np.arange(4)
    first = (4 * pairs[:, 0, None] + k).reshape(-1)
    second = (4 * pairs[:, 1, None] + k).reshape(-1)
    return RegularizerRows(first, second, 1.0 / np.sqrt(max(len(pairs), 1)))


def regularizer(st: Stencils, nv: int) -> Family:
    rows = regularizer_rows(st)
    tl = st.tiles
    i, j, w = rows.first, rows.second, rows.weight
    flat = tl.reshape(-1)
    nxt = np.roll(tl, -1, 1).reshape(-1)
    prv = np.roll(tl, 1, 1).reshape(-1)
    # one stencil of 6 nodes a row: a length row uses 4 (the other two repeat a node with zero gradient)
    len_nodes = np.stack([flat[i], nxt[i], flat[j], nxt[j], flat[i], flat[i]], -1)
    ang_nodes = np.stack([flat[i], nxt[i], prv[i], flat[j], nxt[j], prv[j]], -1)
    nodes = np.concatenate([len_nodes, ang_nodes])

    m = len(i)

    def fn(x):
        tc = tile_corners(x, tl)
        e = (tc.A / tc.length[..., None]).reshape(-1, 2)
        ga, gb = tc.ga.reshape(-1, 2), tc.gb.reshape(-1, 2)
        g = np.empty((2 * m, 6, 2))  # length rows (4 nodes, two repeats at zero), then angle rows
        ei, ej, gai, gbi, gaj, gbj = e[i], e[j], ga[i], gb[i], ga[j], gb[j]
        np.negative(ei, out=g[:m, 0])
        g[:m, 1], g[:m, 2] = ei, ej
        np.negative(ej, out=g[:m, 3])
        g[:m, 4:] = 0.0
        np.negative(gai + gbi, out=g[m:, 0])
        g[m:, 1], g[m:, 2] = gai, gbi
        np.add(gaj, gbj, out=g[m:, 3])
        np.negative(gaj, out=g[m:, 4])
        np.negative(gbj, out=g[m:, 5])
        g *= w
        return rows.residual(tc), (nodes, g)

    def lean(x):
        """The residuals at ``x`` and ``y -> Jᵀ y`` as ``(nv, 2)`` (node, coordinate), ``J`` the rows' Jacobian
        (``fn``'s) without its stencil: each tile corner's length and angle take their rows' ``y`` first (a row
        adds it at its first corner and subtracts it at its second), then one gradient per corner goes to its
        three nodes (a corner's length moves with its own and the next node, its angle with those and the
        previous one)."""
        tc = tile_corners(x, tl)

        def transposed(y):
            nc = flat.size
            yl, ya = w * y[:m], w * y[m:]
            Yl = np.bincount(i, yl, minlength=nc) - np.bincount(j, yl, minlength=nc)
            Ya = np.bincount(i, ya, minlength=nc) - np.bincount(j, ya, minlength=nc)
            el = (tc.A / tc.length[..., None]).reshape(-1, 2) * Yl[:, None]
            ga, gb = tc.ga.reshape(-1, 2) * Ya[:, None], tc.gb.reshape(-1, 2) * Ya[:, None]
            at = np.concatenate([flat, nxt, prv])
            v = np.concatenate([-(el + ga + gb), el + ga, gb])
            return np.stack([np.bincount(at, v[:, d], minlength=nv) for d in (0, 1)], -1)

        return rows.residual(tc), transposed

    return Family(
        "regularizer",
        "reg",
        fn,
        0,
        meta={"rows": rows, "lean": lean},
        nv=nv,
        res=lambda x: rows.residual(tile_corners(x, tl)),
    )


def energy(fam: Family, x: np.ndarray) -> float:
    r = fam.residual(x)
    return float(r @ r)


def weighted(fam: Family, w: np.ndarray) -> Family:
    """``fam`` with row i multiplied by ``w[i]`` (residuals and Jacobian): a weighted least-squares fit.

    The unweighted family stays in ``meta["unweighted"]`` so reports measure the real distances."""
    w = np.asarray(w, dtype=float)

    def fn(x):
        r, J = fam.fn(x)
        if isinstance(J, tuple):  # the per-row stencil (nodes, gradients)
            return w * r, (J[0], J[1] * w[:, None, None])
        return w * r, J.multiply(w[:, None]).tocsr()

    return Family(
        fam.name,
        fam.kind,
        fn,
        fam.dim,
        meta={**fam.meta, "unweighted": fam},
        nv=fam.nv,
        res=lambda x: w * fam.residual(x),
    )
