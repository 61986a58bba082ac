"""The symmetric reduced solver's dense path (small lattices) formed over q's columns (``mirror.py``).

On the dense path the merit forms the reduced Jacobian of its node and convexity rows and the regulariser's
normal matrix ``w² Fᵀ (ΔᵀΔ) F`` over p's ``2 nf + 1`` columns, and the symmetric solver then took ``Pᵀ H P``:
a symmetric 32x32 step cost about what a free one costs (drop). Here every product that meets
p's columns goes through ``P`` first, from bases formed once per solve: the tile corners' edges ``ZE B_d``,
``ZB B_d`` (``tiles.TileShapeRows``) and the nodes' ``Zn B_d``, ``Y B_d`` (``family.jacobian_at``),
``B_d`` the rows of ``P`` of seed coordinate d on the columns of q it reaches (``HalfBlocks``). The
regulariser's features then have about half the columns and its normal matrix a quarter of the products.
The same rows and the same matrix to round-off (tests); the rows themselves are still evaluated over the
whole pattern.
"""

from __future__ import annotations

import copy
from typing import Any

import numpy as np
from scipy import sparse

from ....errors import SolveError
from ....kdtree import KDTree
from .family import RigidFamily
from .mirror_normal import HalfBlocks
from .tiles import TileShapeRows


class HalfTileRows(TileShapeRows):
    """``TileShapeRows`` whose Jacobians are over q's seed columns (``nq - 1``: q without ψ), not p's, with the
    regulariser's corner features evaluated on half the tiles.

    On a symmetric member the grid is its own mirror image, so a tile corner's edge length and angle equal its
    mirror image's (``corner_mirror``) for every q, and so do their gradients in q: ``F = E F_R``, ``F_R`` the
    features of the corners of one tile of each mirror pair (``R``) and ``E`` the 0/1 map of every corner onto
    its own or its mirror image's row there. The regulariser's rows ``w Δ F`` are ``w (Δ E) F_R`` and its
    normal matrix ``w² F_Rᵀ (Eᵀ ΔᵀΔ E) F_R``, both from about half the features.
    """

    def __init__(self, t: TileShapeRows, halves: HalfBlocks, vertex_mirror: np.ndarray):
        self.__dict__.update(t.__dict__)
        self.cols = [_span(c) for c in halves.cols]
        self.nq = halves.nq
        self.ZEB = [np.einsum("tkf,fc->tkc", t.ZE, B) for B in halves.B]
        self.ZBB = [np.einsum("tkf,fc->tkc", t.ZB, B) for B in halves.B]
        self.R, E = corner_mirror(t.quads, vertex_mirror)
        self.diff = (t.diff @ E).tocsr()
        self.diff_t = self.diff.T.tocsr()
        self.laplacian = (E.T @ t.laplacian @ E).tocsr()
        self._Fq = np.zeros((2, len(self.R), 4, self.nq - 1))

    def features(self, tc, out: np.ndarray | None = None) -> np.ndarray:
        """``(8 |R|, nq - 1)``: ``∂ℓ/∂q`` of the corners of the tiles ``R``, then ``∂θ/∂q`` (``F_R``)."""
        R = self.R
        F = self._Fq if out is not None else np.zeros_like(self._Fq)
        e = tc.A[R] / tc.length[R][..., None]
        ga, gb = tc.ga[R], tc.gb[R]
        for d, c in enumerate(self.cols):  # the coordinates reach disjoint columns of q
            ZE, ZB = self.ZEB[d][R], self.ZBB[d][R]
            F[0][..., c] = e[..., d, None] * ZE
            F[1][..., c] = ga[..., d, None] * ZE + gb[..., d, None] * ZB
        return F.reshape(8 * len(R), self.nq - 1)

    def convexity_jacobian(self, tc, corners: np.ndarray) -> np.ndarray:
        """``∂ cross(A, B) / ∂q`` at flat corners ``corners`` (index ``4 t + k``)."""
        t, k = np.divmod(corners, 4)
        A, B = tc.A[t, k], tc.B[t, k]
        (cx, cy), J = self.cols, np.zeros((len(corners), self.nq - 1))
        J[:, cx] = B[:, 1, None] * self.ZEB[0][t, k] - A[:, 1, None] * self.ZBB[0][t, k]
        J[:, cy] = A[:, 0, None] * self.ZBB[1][t, k] - B[:, 0, None] * self.ZEB[1][t, k]
        return J


class HalfNodes:
    """``∂x[nodes]/∂q`` of a symmetric member (``rigid.RigidFamily.jacobian_at`` times ``P``), from the nodes'
    bases ``Zn B_d`` and ``Y B_d``; and any dense ``∂r/∂p`` through ``P``."""

    def __init__(self, fam: RigidFamily, P: sparse.csr_matrix, halves: HalfBlocks):
        self.fam, self.P, self.nq = fam, P, halves.nq
        self.cols = [_span(c) for c in halves.cols]
        self.ZnB = [fam.Zn @ B for B in halves.B]
        self.YB = [fam.Y @ B for B in halves.B]

    def jacobian_at(self, S: np.ndarray, psi: float, nodes: np.ndarray) -> np.ndarray:
        """``(n, 2, nq)``: coordinate ``d`` of node ``i`` in ``[i, d]``, ψ last as in ``jacobian_at``."""
        c, s = np.cos(psi), np.sin(psi)
        (cx, cy), D = self.cols, np.empty((len(nodes), 2, self.nq))
        D[:, 0, cx] = c * self.ZnB[0][nodes]
        D[:, 0, cy] = -s * self.YB[1][nodes]
        D[:, 1, cx] = s * self.YB[0][nodes]
        D[:, 1, cy] = c * self.ZnB[1][nodes]
        a = self.fam.Zn[nodes] @ S
        b = self.fam.Y[nodes] @ S
        D[:, 0, -1] = -s * a[:, 0] - c * b[:, 1]
        D[:, 1, -1] = -s * a[:, 1] + c * b[:, 0]
        return D

    def through(self, J: np.ndarray) -> np.ndarray:
        """``J P`` (dense ``∂r/∂p`` of a few rows: the contact and axis rows)."""
        return np.asarray((self.P.T @ J.T).T)


def corner_mirror(
    quads: np.ndarray, vertex_mirror: np.ndarray
) -> tuple[np.ndarray, sparse.csr_matrix]:
    """``(R, E)`` of ``HalfTileRows``: one tile of each mirror pair (every tile on the axis), and ``E``
    ``(8 T, 8 |R|)`` taking each corner's length row (edge to the next corner) and angle row to its own row in
    ``R`` or its mirror image's (the mirror reverses a tile's turn: the edge from corner k to k+1 is the edge
    from the image of k+1 to the image of k)."""
    T = len(quads)
    key = {tuple(sorted(q)): t for t, q in enumerate(quads.tolist())}
    partner = np.array([key[tuple(sorted(vertex_mirror[q]))] for q in quads.tolist()])
    R = np.flatnonzero(np.arange(T) <= partner)
    slot = np.full(T, -1)
    slot[R] = np.arange(len(R))
    img = vertex_mirror[quads]  # (T, 4): each corner's vertex mirrored
    # the corner of the partner tile at the mirrored vertex (angles), and at the mirrored next vertex (lengths)
    at = np.argmax(quads[partner][:, None, :] == img[:, :, None], axis=2)
    at_next = np.roll(at, -1, axis=1)
    t = np.repeat(np.arange(T), 4)
    own = np.isin(t, R)
    k = np.tile(np.arange(4), T)
    length = np.where(own, 4 * slot[t] + k, 4 * slot[partner[t]] + at_next.reshape(-1))
    angle = np.where(own, 4 * slot[t] + k, 4 * slot[partner[t]] + at.reshape(-1))
    n = 4 * len(R)
    rows = np.arange(8 * T)
    E = sparse.csr_matrix(
        (np.ones(8 * T), (rows, np.concatenate([length, n + angle]))), shape=(8 * T, 2 * n)
    )
    return R, E


def vertex_mirror(fam: RigidFamily, P: sparse.csr_matrix) -> np.ndarray:
    """``(G,)`` each grid vertex's mirror image, read off a generic symmetric member's grid ``Z S``: ``P``
    negates one seed coordinate (the one the mirror flips), and the grid maps onto itself."""
    nf = fam.n_seeds
    flipped = int((P[nf : 2 * nf].data < 0).any())
    q = np.random.default_rng(0).normal(size=P.shape[1])
    p = P @ q
    c = fam.Z @ np.stack([p[:nf], p[nf : 2 * nf]], -1)
    image = c.copy()
    image[:, flipped] *= -1.0
    d, k = KDTree(c).query(image)
    if (d > 1e-9 * max(1.0, float(np.abs(c).max()))).any():
        raise SolveError("symmetric member: its grid is not its own mirror image")
    return np.asarray(k, dtype=np.int64)


def _span(cols: np.ndarray) -> slice | np.ndarray:
    """``cols`` as a slice when contiguous (``mirror_map`` numbers each coordinate's columns in one run)."""
    if len(cols) and np.array_equal(cols, np.arange(cols[0], cols[0] + len(cols))):
        return slice(int(cols[0]), int(cols[0]) + len(cols))
    return cols


def halved(merit: Any, P: sparse.csr_matrix, halves: HalfBlocks) -> Any:
    """A dense-path merit (``reduced._Merit`` with ``_tiles``) whose Jacobian and normal matrix are over q;
    any other merit unchanged (the block path has ``mirror_normal.half_normal``)."""
    if merit._tiles is None or merit._half is not None:
        return merit
    new = copy.copy(merit)
    new._tiles = HalfTileRows(merit._tiles, halves, vertex_mirror(merit.fam, P))
    new._half = HalfNodes(merit.fam, P, halves)
    return new
