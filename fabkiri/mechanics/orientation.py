"""An orientation term for the spring energy: every tile's signed area held to its design.

A tile's springs (its edges, and a quad's diagonals) fix its shape only up to a mirror image:
a triangle turned over has the same edge lengths and zero spring energy. A path solver that lets
a tile pass through zero area can therefore land in a mirrored branch and never reach the closed
state (the designed kagome patterns did, with up to 10 triangles turned over). This term,

    E_A(x) = w · Σ_T ((A_T(x) - A⁰_T) / A⁰_T)²,

with ``A_T`` the shoelace signed area and ``A⁰_T`` its deployed value, is zero exactly when every
tile has its designed area and orientation, so adding it changes no state's energy; it only
makes turning a tile over cost energy. Its gradient and Hessian are exact (the area is quadratic
in the corners, so its Hessian is a constant per tile) and sparse.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import sparse

from ..errors import PatternError
from ..pattern.model import Pattern


@dataclass(frozen=True, eq=False)
class AreaTerm:
    """``w Σ_T ((A_T - A⁰_T)/A⁰_T)²`` over the tiles of a pattern (flat interleaved coordinates)."""

    tiles: np.ndarray  # (T, k) node indices, CCW
    rest: np.ndarray  # (T,) deployed signed areas, mm²
    weight: float
    n_nodes: int

    def _parts(self, x: np.ndarray):
        c = np.asarray(x, dtype=float).reshape(self.n_nodes, 2)[self.tiles]  # (T, k, 2)
        nxt, prv = np.roll(c, -1, axis=1), np.roll(c, 1, axis=1)
        area = 0.5 * (c[..., 0] * nxt[..., 1] - c[..., 1] * nxt[..., 0]).sum(axis=1)
        # ∂A/∂x_k = (y_{k+1} - y_{k-1}) / 2, ∂A/∂y_k = (x_{k-1} - x_{k+1}) / 2
        grad = 0.5 * np.stack([nxt[..., 1] - prv[..., 1], prv[..., 0] - nxt[..., 0]], -1)
        return (area - self.rest) / self.rest, grad / self.rest[:, None, None]  # r, ∂r (T, k, 2)

    def residuals(self, x: np.ndarray) -> np.ndarray:
        return self._parts(x)[0]

    def energy(self, x: np.ndarray) -> float:
        r = self.residuals(x)
        return float(self.weight * (r @ r))

    def gradient(self, x: np.ndarray) -> np.ndarray:
        r, dr = self._parts(x)
        g = np.zeros((self.n_nodes, 2))
        np.add.at(g, self.tiles, (2.0 * self.weight * r)[:, None, None] * dr)
        return g.ravel()

    def hessian(self, x: np.ndarray) -> sparse.csr_matrix:
        """``2w Σ_T (∇r_T ∇r_Tᵀ + r_T ∇²r_T)``; ``∇²A`` pairs ``x_k`` with ``y_{k±1}`` (±½)."""
        r, dr = self._parts(x)
        T, k = self.tiles.shape
        dof = np.stack([2 * self.tiles, 2 * self.tiles + 1], -1).reshape(T, 2 * k)
        outer = dr.reshape(T, -1)[:, :, None] * dr.reshape(T, -1)[:, None, :]
        second = np.zeros((2 * k, 2 * k))
        for j in range(k):  # ∂²A/∂x_j∂y_{j+1} = ½, ∂²A/∂x_j∂y_{j-1} = -½
            second[2 * j, 2 * ((j + 1) % k) + 1] += 0.5
            second[2 * j, 2 * ((j - 1) % k) + 1] -= 0.5
        second = second + second.T
        block = 2.0 * self.weight * (outer + (r / self.rest)[:, None, None] * second)
        rows = np.repeat(dof, 2 * k, axis=1).ravel()
        cols = np.tile(dof, (1, 2 * k)).ravel()
        n2 = 2 * self.n_nodes
        return sparse.csr_matrix((block.ravel(), (rows, cols)), shape=(n2, n2))


def area_term(pattern: Pattern, weight: float = 1.0) -> AreaTerm:
    """The orientation term of ``pattern`` with its deployed areas as rest values."""
    c = pattern.corners()
    rest = 0.5 * (
        c[..., 0] * np.roll(c, -1, 1)[..., 1] - c[..., 1] * np.roll(c, -1, 1)[..., 0]
    ).sum(1)
    flat = np.abs(rest) <= 1e-12 * pattern.tile_size**2  # a tile designed clockwise keeps its sign
    if flat.any():
        t = int(np.flatnonzero(flat)[0])
        raise PatternError(
            f"tile {t} has no area in the deployed state; it has no orientation to keep"
        )
    return AreaTerm(pattern.tiles, rest, float(weight), len(pattern.nodes))
