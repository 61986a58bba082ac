"""The symmetric reduced solver's dense path (small lattices) formed over q's columns (``reduced_mirror.py``).

On the dense path the merit forms the reduced Jacobian of its node and convexity rows and the regulariser's
normal matrix ``w² Fᵀ (ΔᵀΔ) F`` over p's ``2 nf + 1`` columns, and the symmetric solver then took ``Pᵀ H P``:
a symmetric 32x32 step cost what a free one costs (drop, 27 against 30 ms). Here every product that meets
p's columns goes through ``P`` first, from bases formed once per solve: the tile corners' edges ``ZE B_d``,
``ZB B_d`` (``reduced_tiles.TileShapeRows``) and the nodes' ``Zn B_d``, ``Y B_d`` (``rigid.jacobian_at``),
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

from .reduced_mirror_normal import HalfBlocks
from .reduced_tiles import TileShapeRows
from .rigid import RigidFamily


class HalfTileRows(TileShapeRows):
    """``TileShapeRows`` whose Jacobians are over q's seed columns (``nq - 1``: q without ψ), not p's."""

    def __init__(self, t: TileShapeRows, halves: HalfBlocks):
        self.__dict__.update(t.__dict__)
        self.cols = [_span(c) for c in halves.cols]
        self.nq = halves.nq
        self.ZEB = [np.einsum("tkf,fc->tkc", t.ZE, B) for B in halves.B]
        self.ZBB = [np.einsum("tkf,fc->tkc", t.ZB, B) for B in halves.B]
        self._Fq = np.zeros((2, *t.ZE.shape[:2], self.nq - 1))

    def features(self, tc, out: np.ndarray | None = None) -> np.ndarray:
        """``(2 n, nq - 1)``: ``∂ℓ/∂q`` of every tile corner, then ``∂θ/∂q`` (``TileShapeRows.features`` P)."""
        T = self.ZE.shape[0]
        F = self._Fq if out is not None else np.zeros_like(self._Fq)
        e = tc.A / tc.length[..., None]
        for d, c in enumerate(self.cols):  # the coordinates reach disjoint columns of q
            F[0][..., c] = e[..., d, None] * self.ZEB[d]
            F[1][..., c] = tc.ga[..., d, None] * self.ZEB[d] + tc.gb[..., d, None] * self.ZBB[d]
        return F.reshape(8 * T, self.nq - 1)

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


def _span(cols: np.ndarray) -> slice | np.ndarray:
    """``cols`` as a slice when contiguous (``mirror_map`` numbers each coordinate's columns in one run)."""
    if len(cols) and np.array_equal(cols, np.arange(cols[0], cols[0] + len(cols))):
        return slice(int(cols[0]), int(cols[0]) + len(cols))
    return cols


def halved(merit: Any, P: sparse.csr_matrix, halves: HalfBlocks) -> Any:
    """A dense-path merit (``reduced._Merit`` with ``_tiles``) whose Jacobian and normal matrix are over q;
    any other merit unchanged (the block path has ``reduced_mirror_normal.half_normal``)."""
    if merit._tiles is None or merit._half is not None:
        return merit
    new = copy.copy(merit)
    new._tiles = HalfTileRows(merit._tiles, halves)
    new._half = HalfNodes(merit.fam, P, halves)
    return new
