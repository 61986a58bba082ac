"""Spring model of a kirigami pattern (docs/algorithm.md#spring-energy).

Every quad carries six springs: its four edges and its two diagonals (a kagome triangle its
three edges: enough to keep any tile rigid). Their
rest lengths ``l`` are the designed (deployed) tile dimensions; the nodes are
the deployed nodes, so a hinge shared by two tiles is an ideal pin. With
``d = |x_i - x_j|`` the residual of a spring is its relative strain
``r = (d - l) / l`` and the energy is

    E(x) = Σ_s r_s²,

zero exactly when every tile is congruent to its design (any closed state and
the deployed state). The per-tile energy ``e_T`` is the sum of its six terms.

Everything is vectorised over springs; the gradient, the residual Jacobian and
the Hessian are analytic, the last two as ``scipy.sparse`` matrices in the
interleaved ordering ``[x0, y0, x1, y1, ...]``.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property
from typing import Protocol

import numpy as np
from scipy import sparse

from ..errors import PatternError
from ..pattern.model import Pattern

# corner pairs of a quad: 4 edges, then the 2 diagonals
SPRING_CORNERS = np.array([[0, 1], [1, 2], [2, 3], [3, 0], [0, 2], [1, 3]])


def spring_corners(n: int) -> np.ndarray:
    """Corner pairs that carry a spring in an ``n``-corner tile: its edges, then its diagonals
    (every other pair), so the tile is rigid (a triangle needs only its three edges)."""
    if n == 4:
        return SPRING_CORNERS
    edges = [[k, (k + 1) % n] for k in range(n)]
    diagonals = [[i, j] for i in range(n) for j in range(i + 2, n) if (i, j) != (0, n - 1)]
    return np.array(edges + diagonals, dtype=np.int64)


@dataclass(frozen=True, eq=False)
class Springs:
    """The springs of a pattern: node pairs, rest lengths and owning tiles."""

    pairs: np.ndarray  # (S, 2) node indices
    rest: np.ndarray  # (S,) rest lengths, mm
    tile: np.ndarray  # (S,) tile owning each spring (6 per quad, 3 per triangle, in tile order)
    n_nodes: int
    n_tiles: int

    @property
    def n_springs(self) -> int:
        return len(self.pairs)

    @cached_property
    def _pattern_index(self) -> tuple[np.ndarray, np.ndarray]:
        """Row/column indices of the 16 Hessian entries of every spring (COO)."""
        i, j = self.pairs.T
        dof = np.stack([2 * i, 2 * i + 1, 2 * j, 2 * j + 1], -1)  # (S, 4)
        rows = np.repeat(dof, 4, axis=1)
        cols = np.tile(dof, (1, 4))
        return rows.ravel(), cols.ravel()

    def _geometry(self, x: np.ndarray):
        x = np.asarray(x, dtype=float).reshape(self.n_nodes, 2)
        v = x[self.pairs[:, 0]] - x[self.pairs[:, 1]]
        d = np.hypot(v[:, 0], v[:, 1])
        u = v / np.where(d > 0, d, 1.0)[:, None]  # a zero-length spring has no direction
        r = (d - self.rest) / self.rest
        return v, d, u, r

    def strains(self, x: np.ndarray) -> np.ndarray:
        """Relative strain ``(d - l)/l`` of every spring."""
        return self._geometry(x)[3]

    def energy(self, x: np.ndarray) -> float:
        r = self.strains(x)
        return float(r @ r)

    def tile_energy(self, x: np.ndarray) -> np.ndarray:
        """``(T,)`` energy of every tile (sum of its spring terms)."""
        r = self.strains(x)
        return (r * r).reshape(self.n_tiles, -1).sum(axis=1)

    def tile_energies(self, frames: np.ndarray) -> np.ndarray:
        """``(F, T)`` tile energies of many node arrays ``(F, n, 2)`` at once."""
        frames = np.asarray(frames, dtype=float)
        v = frames[:, self.pairs[:, 0]] - frames[:, self.pairs[:, 1]]
        r = (np.hypot(v[..., 0], v[..., 1]) - self.rest) / self.rest
        return (r * r).reshape(len(frames), self.n_tiles, -1).sum(axis=2)

    def gradient(self, x: np.ndarray) -> np.ndarray:
        """``∇E`` as a flat ``(2n,)`` array."""
        _, _, u, r = self._geometry(x)
        f = (2.0 * r / self.rest)[:, None] * u  # dE_s/dx_i; dE_s/dx_j = -f
        g = np.zeros((self.n_nodes, 2))
        np.add.at(g, self.pairs[:, 0], f)
        np.add.at(g, self.pairs[:, 1], -f)
        return g.ravel()

    def jacobian(self, x: np.ndarray) -> sparse.csr_matrix:
        """``(S, 2n)`` Jacobian of the strains: ``∂r_s/∂x_i = u_sᵀ / l_s``."""
        _, _, u, _ = self._geometry(x)
        w = u / self.rest[:, None]
        i, j = self.pairs.T
        S = self.n_springs
        rows = np.repeat(np.arange(S), 4)
        cols = np.stack([2 * i, 2 * i + 1, 2 * j, 2 * j + 1], -1).ravel()
        vals = np.concatenate([w, -w], axis=1).ravel()
        return sparse.csr_matrix((vals, (rows, cols)), shape=(S, 2 * self.n_nodes))

    def hessian(self, x: np.ndarray) -> sparse.csr_matrix:
        """Exact ``(2n, 2n)`` Hessian of ``E``.

        Per spring, ``K = 2/l² u uᵀ + 2r/(l d) (I - u uᵀ)`` enters the (i, i)
        and (j, j) blocks with ``+`` and the (i, j), (j, i) blocks with ``-``.
        The second term makes ``K`` indefinite for compressed springs.
        """
        _, d, u, r = self._geometry(x)
        uu = u[:, :, None] * u[:, None, :]
        a = 2.0 / self.rest**2
        b = 2.0 * r / (self.rest * np.where(d > 0, d, 1.0))
        K = a[:, None, None] * uu + b[:, None, None] * (np.eye(2) - uu)
        block = np.block([[K, -K], [-K, K]])  # (S, 4, 4)
        rows, cols = self._pattern_index
        n2 = 2 * self.n_nodes
        return sparse.csr_matrix((block.ravel(), (rows, cols)), shape=(n2, n2))

    def gauss_newton(self, x: np.ndarray) -> sparse.csr_matrix:
        """``2 JᵀJ``: the positive semi-definite part of the Hessian."""
        J = self.jacobian(x)
        return (2.0 * (J.T @ J)).tocsr()


def springs(pattern: Pattern) -> Springs:
    """The six springs of every tile, rest lengths from the deployed nodes."""
    tiles = pattern.tiles
    corner_pairs = spring_corners(tiles.shape[1])
    pairs = tiles[:, corner_pairs].reshape(-1, 2)
    x = pattern.nodes
    rest = np.linalg.norm(x[pairs[:, 0]] - x[pairs[:, 1]], axis=1)
    short = rest <= 1e-9 * max(float(rest.max(initial=0.0)), 1e-300)
    if short.any():  # a relative strain needs a length to be relative to
        s = int(np.flatnonzero(short)[0])
        raise PatternError(
            f"tile {s // len(corner_pairs)} has a zero-length edge or diagonal; it cannot carry a "
            f"spring"
        )
    tile = np.repeat(np.arange(len(tiles)), len(corner_pairs))
    return Springs(pairs=pairs, rest=rest, tile=tile, n_nodes=len(x), n_tiles=len(tiles))


def corner_energy(sp: Springs, corners: np.ndarray) -> np.ndarray:
    """``(T,)`` energy of tiles given by their own corners ``(T, n, 2)``.

    Used for states stored per tile (closed states, rigid-path frames), where
    the two copies of a hinge are separate points: it measures tile distortion
    only, not hinge gaps.
    """
    c = np.asarray(corners, dtype=float)
    cp = spring_corners(c.shape[1])
    v = c[:, cp[:, 0]] - c[:, cp[:, 1]]  # (T, springs per tile, 2)
    rest = sp.rest.reshape(len(c), -1)
    r = (np.hypot(v[..., 0], v[..., 1]) - rest) / rest
    return (r * r).sum(axis=1)


class Term(Protocol):
    """An energy term added to the springs (orientation, contact): value, gradient, Hessian."""

    def energy(self, x: np.ndarray) -> float: ...

    def gradient(self, x: np.ndarray) -> np.ndarray: ...

    def hessian(self, x: np.ndarray) -> sparse.spmatrix: ...


@dataclass(frozen=True, eq=False)
class WithTerm:
    """Springs (or springs with terms) plus one more term, with the interface the path's minimiser uses
    (``energy``, ``gradient``, ``hessian``, ``rest``, ``n_springs``); the energy reported along a path
    stays the springs' own."""

    base: Springs | WithTerm
    term: Term

    @property
    def rest(self) -> np.ndarray:
        return self.base.rest

    @property
    def n_springs(self) -> int:
        return self.base.n_springs

    def energy(self, x: np.ndarray) -> float:
        return self.base.energy(x) + self.term.energy(x)

    def gradient(self, x: np.ndarray) -> np.ndarray:
        return self.base.gradient(x) + self.term.gradient(x)

    def hessian(self, x: np.ndarray) -> sparse.csr_matrix:
        return (self.base.hessian(x) + self.term.hessian(x)).tocsr()
