"""The tile-shape rows of the rigid-family solver (``reduced.py``) with their dense Jacobian in ``S``.

Small lattices form the reduced Jacobian directly: per tile corner once, then a regulariser row as the
difference of two corners' rows (``TileShapeRows``).
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
from scipy import sparse

from ...core.stencils import Family, Stencils
from ..constraints import convexity
from ..objective import NEXT, PREV, RegularizerRows, TileCorners, regularizer
from .family import RigidFamily

# families that see only tile shapes: on a member every tile is a rigid copy of its closed-state-1 grid cell,
# so they are evaluated on the grid c = Z S (G vertices, no ψ) instead of the V deployed nodes
TILE_SHAPE = ("regularizer", "convexity")


def grid_families(fam: RigidFamily, st: Stencils, families: list[Family]) -> list[Family]:
    """The ``TILE_SHAPE`` families among ``families``, rebuilt on the closed-state-1 grid of ``fam``."""
    G = fam.Z.shape[0]
    # only ``tiles``, ``rows`` and ``cols`` are read by these families; the hinge and fold fields still index
    # deployed nodes and are not used on the grid
    grid = replace(st, tiles=fam.node_vertex[st.tiles], n_nodes=G)
    build = {"regularizer": lambda: regularizer(grid, G), "convexity": lambda: convexity(grid, G)}
    return [build[f.name]() for f in families if f.name in TILE_SHAPE]


class TileShapeRows:
    """The ``TILE_SHAPE`` rows on the closed-state-1 grid with their dense Jacobian in ``S``.

    Every tile corner's edge ``A`` (to the next corner) and ``B`` (to the previous one) is linear in the
    seeds, ``∂A/∂S = ZE`` and ``∂B/∂S = ZB`` per coordinate (constant ``(T, 4, nf)``), so each corner's
    length, angle and cross product gets its gradient in ``S`` once, and a regulariser row is the
    difference of two corners' (a tile sits in up to four pairs).
    """

    def __init__(self, fam: RigidFamily, quads: np.ndarray, rows: RegularizerRows, margin: float):
        Z = fam.Z
        self.quads = quads
        self.ZE = Z[quads[:, NEXT]] - Z[quads]
        self.ZB = Z[quads[:, PREV]] - Z[quads]
        self.rows = rows
        self.margin = margin
        n = quads.size
        m = len(rows.first)
        # Δ: row i of each half is corner first[i] minus corner second[i] (lengths: 0..n-1, angles: n..2n-1)
        i = np.arange(2 * m)
        first = np.concatenate([rows.first, n + rows.first])
        second = np.concatenate([rows.second, n + rows.second])
        self.diff = sparse.csr_matrix(
            (np.r_[np.ones(2 * m), -np.ones(2 * m)], (np.r_[i, i], np.r_[first, second])),
            shape=(2 * m, 2 * n),
        )
        self.diff_t = self.diff.T.tocsr()
        self.laplacian = (self.diff_t @ self.diff).tocsr()
        # reused by every evaluation: fresh megabyte-size temporaries cost page faults
        self._F = np.empty((2, *self.ZE.shape[:2], 2, self.ZE.shape[2]))

    def features(self, tc: TileCorners, out: np.ndarray | None = None) -> np.ndarray:
        """``(2 n, 2 nf)``: ``∂ℓ/∂S`` of every tile corner, then ``∂θ/∂S`` (``n = 4 T``)."""
        T, _, nf = self.ZE.shape
        ZE, ZB = self.ZE, self.ZB
        e = tc.A / tc.length[..., None]
        F = np.empty((2, T, 4, 2, nf)) if out is None else out
        np.multiply(e[..., None], ZE[:, :, None, :], out=F[0])
        np.multiply(tc.ga[..., None], ZE[:, :, None, :], out=F[1])
        F[1] += tc.gb[..., None] * ZB[:, :, None, :]
        return F.reshape(8 * T, 2 * nf)

    def regularizer_jacobian(self, tc: TileCorners) -> np.ndarray:
        """``(2 m, 2 nf)``: length rows, then angle rows, as ``RegularizerRows.residual`` stacks them."""
        return self.rows.weight * (self.diff @ self.features(tc))

    def regularizer_normal(self, tc: TileCorners, r: np.ndarray, scale: float):
        """``JᵀJ`` and ``Jᵀ r`` of the rows ``scale · regulariser`` without forming ``J = w Δ F``:
        ``w² Fᵀ (ΔᵀΔ) F`` and ``w Fᵀ Δᵀ r`` (a tile corner sits in up to four rows)."""
        F = self.features(tc, self._F)
        w = scale * self.rows.weight
        return w * w * (F.T @ (self.laplacian @ F)), w * (F.T @ (self.diff_t @ r))

    def convexity_jacobian(self, tc: TileCorners, corners: np.ndarray) -> np.ndarray:
        """``∂ cross(A, B) / ∂S`` at flat corners ``corners`` (index ``4 t + k``)."""
        t, k = np.divmod(corners, 4)
        A, B, ZE, ZB = tc.A[t, k], tc.B[t, k], self.ZE[t, k], self.ZB[t, k]
        return np.hstack(
            [B[:, 1, None] * ZE - A[:, 1, None] * ZB, A[:, 0, None] * ZB - B[:, 0, None] * ZE]
        )
