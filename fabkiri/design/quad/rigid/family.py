"""The rigid-deployable reconfigurable family in closed form (reduced coordinates).

With rhombus holes and hinge sums π (docs/algorithm.md#rigid-deployability) every tile turns
rigidly by ``-σ_T ψ`` (σ = ±1 in a checkerboard) between closed state 1 (ψ = 0) and
closed state 2 (ψ = π/2). Write the pattern vertices of closed state 1 as
``c`` (an (M+1)×(N+1) grid of points). Tile ``T``'s corner ``k`` then sits at

    x(T, k; ψ) = Rot(-σ_T ψ) c[P(T, k)] + sin ψ · τ_T,

and the two tiles of a hinge at grid vertex ``g`` agree iff their translations
differ by ``τ_B - τ_A = -2 σ_A J c_g`` (``J``: quarter turn). Integrated around
a hole this holds iff the hole's merge vertex is the midpoint of its two fold
vertices in closed state 1 (its slit is straight and split in half); the same
midpoint rule at every boundary hinge whose notch is open in state 1 makes the
notch close in state 2. So the family is

    {x(ψ, c) : A c = 0},   A = one midpoint row per hole and per open notch,

a linear space of dimension M+N+2 per coordinate (2(M+N)+2 with ψ, modulo rigid motions:
docs/algorithm.md#reconfigurability). Every member satisfies the edge pairs of both states
and the hinge sums exactly, for every ψ.

The basis is anchored on the boundary: the 4 grid corners and every boundary
vertex not pinned by an open-notch midpoint row are free (``seeds``); the
interior follows from one sparse LU solve. In these coordinates the deployed
nodes are ``x = cos ψ · Zn S + sin ψ · J (Y S)`` with ``S`` the seed points
``(nf, 2)`` and ``Zn``, ``Y`` dense ``(V, nf)`` matrices, so the design problem
keeps only the shape fit, the regulariser and the inequalities.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np
from scipy import sparse
from scipy.linalg import cho_factor, cho_solve
from scipy.sparse.linalg import splu

from ....errors import SolveError
from ....pattern.topology import SpanningTree
from ...core.stencils import Stencils

if TYPE_CHECKING:
    from .core import GridCore

# above this many grid vertices (64x64 tiles and up) ``grid`` and ``nodes`` take the cheaper products (the core's
# ``E (Z[core] S)``, the tiles' ``τ S``): the same maps to round-off; smaller lattices keep ``Z S`` and ``Y S``
# (at 48x48 the two ways cost the same)
LARGE_GRID = 4000
# above this many grid vertices (above 96x96 tiles, past issue #37's table, whose outputs stay the lstsq fits'
# and products'): a fine start's seeds by the normal equations (``seeds_for_grid``), a coarse member's from its
# seed tiles (``member_seeds``), a reduced solve's result by ``exact_nodes``
EXACT_GRID = 97 * 97
# a pattern within this of a member (relative to its largest coordinate) is that member (``member_seeds``)
MEMBER_ROUNDOFF = 1e-11
# nodes per block when ``Y`` is formed
Y_BLOCK = 4096


@dataclass(eq=False)
class RigidFamily:
    """Closed-form rigid-deployable reconfigurable patterns of one lattice."""

    node_vertex: np.ndarray  # (V,) closed-state-1 grid vertex of every deployed node
    midpoint: np.ndarray  # (m, 3) grid vertices (z, a, b): c_z = (c_a + c_b) / 2
    seeds: np.ndarray  # (nf,) free grid vertices
    Z: np.ndarray  # (G, nf) closed-state-1 grid = Z @ S
    # (τ per tile, tile of each node, σ per node (V, 1)): ``Y = τ[tile] - σ Zn``
    parts: tuple = field(repr=False)
    # a ``Y`` other than the parts' (``mirror.centred``); the parts' own is made on first use
    given_Y: np.ndarray | None = field(default=None, repr=False)
    # (midpoint rows A (csc), LU of their dependent columns, dependent vertices, the spanning tree's steps
    # (child tiles, parent tiles, 2 σ_parent, hinge grid vertex) per level): ``exact_nodes``' (``build``'s own)
    exact: tuple | None = field(default=None, repr=False)
    _core: GridCore | None = field(default=None, init=False, repr=False)
    # ``Zn`` and the parts' ``Y`` (dense (V, nf) each, the largest arrays here), made on first use: the large lattices'
    # solves read the rows of a few nodes (``rows``) and ``Y S`` once
    _zn: np.ndarray | None = field(default=None, init=False, repr=False)
    _y: np.ndarray | None = field(default=None, init=False, repr=False)

    @property
    def Zn(self) -> np.ndarray:
        """``(V, nf)``: ``Z`` at each node's grid vertex."""
        if self._zn is None:
            self._zn = self.Z[self.node_vertex]
        return self._zn

    @property
    def Y(self) -> np.ndarray:
        """``(V, nf)``: the tile-translation part minus σ ``Zn``, per node."""
        if self.given_Y is not None:
            return self.given_Y
        if self._y is None:
            tau, use_t, sigma = self.parts
            y = tau[use_t]
            # σ Zn subtracted by blocks of nodes: the same numbers without a second (V, nf) array, whose fresh
            # pages cost more than the arithmetic at 128x128
            for a in range(0, len(y), Y_BLOCK):
                b = slice(a, a + Y_BLOCK)
                zn = self.Z[self.node_vertex[b]] if self._zn is None else self._zn[b]
                y[b] -= sigma[b] * zn
            self._y = y
        return self._y

    def rows(self, nodes: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``(Zn[nodes], Y[nodes])``, the same numbers, without making ``Zn`` or ``Y`` whole."""
        zn = self.Z[self.node_vertex[nodes]] if self._zn is None else self._zn[nodes]
        if self.given_Y is not None or self._y is not None:
            return zn, self.Y[nodes]
        tau, use_t, sigma = self.parts
        return zn, tau[use_t[nodes]] - sigma[nodes] * zn

    @property
    def n_seeds(self) -> int:
        return len(self.seeds)

    @property
    def core(self) -> GridCore:
        """``Z = E Z[core]`` with a sparse ``E`` (``core.py``), made on first use."""
        if self._core is None:
            # loaded here: only the large lattices' products (``LARGE_GRID``) use the core
            from .core import grid_core

            self._core = grid_core(self.midpoint, self.Z)
        return self._core

    @classmethod
    def build(cls, st: Stencils, tree: SpanningTree) -> RigidFamily:
        """``tree``: a spanning tree of the tile graph (``Topology.spanning_tree``)."""
        M, N = st.rows, st.cols
        tl = st.tiles
        G = (M + 1) * (N + 1)
        vid = st.phi[1][..., 1] * (N + 1) + st.phi[1][..., 0]  # (T, 4) grid vertex of each corner
        node_vertex = np.empty(st.n_nodes, dtype=np.int64)
        node_vertex[tl.ravel()] = vid.ravel()
        # the gap that stays open in state 1 at each hinge: its two edges are straight and equal there
        A, B = st.hinge_tiles.T
        cA, cB = st.hinge_corner.T
        fold = st.folds[1]
        nA = tl[A, (cA + 1) % 4]
        pA = tl[A, (cA + 3) % 4]
        nB = tl[B, (cB + 1) % 4]
        pB = tl[B, (cB + 3) % 4]
        openA = np.where(nA == fold.fold_ends[:, 0], pA, nA)
        openB = np.where(nB == fold.fold_ends[:, 1], pB, nB)
        z = node_vertex[st.hinge_node]
        a, b = node_vertex[openA], node_vertex[openB]
        # both merge corners of a hole give the same row: keep one
        mid = np.unique(np.stack([z, np.minimum(a, b), np.maximum(a, b)], 1), axis=0)
        m = len(mid)
        Am = sparse.csr_matrix(
            (np.r_[np.ones(m), np.full(2 * m, -0.5)], (np.tile(np.arange(m), 3), mid.T.ravel())),
            shape=(m, G),
        )
        gi, gj = np.divmod(np.arange(G), N + 1)
        boundary = (gi == 0) | (gi == M) | (gj == 0) | (gj == N)
        pinned = np.zeros(G, dtype=bool)
        pinned[mid[:, 0]] = True
        seeds = np.flatnonzero(boundary & ~pinned)
        dep = np.setdiff1d(np.arange(G), seeds)
        if len(dep) != m:
            raise SolveError(f"rigid family: {m} midpoint rows for {len(dep)} dependent vertices")
        Am = Am.tocsc()
        try:
            lu = splu(Am[:, dep], permc_spec="COLAMD")
        except (
            RuntimeError
        ) as exc:  # pragma: no cover - the anchoring above is exact for quad lattices
            raise SolveError(f"rigid family: boundary anchoring is singular ({exc})") from None
        Z = np.zeros((G, len(seeds)))
        Z[seeds, np.arange(len(seeds))] = 1.0
        Z[dep] = -lu.solve(Am[:, seeds].toarray())
        # tile translations τ (per unit sin ψ), integrated along a spanning tree from tile 0 (τ_0 = 0)
        T = len(tl)
        sigma = np.where(np.arange(T) // N % 2 == np.arange(T) % N % 2, 1.0, -1.0)  # (r + c) even
        hinge_vertex = node_vertex[st.hinge_node]
        tau = np.zeros(
            (T, len(seeds))
        )  # τ_T = J (tau[T] @ S); τ_root = 0 fixes the translation gauge
        steps = []
        for lvl in tree.levels():
            child, parent = tree.children[lvl], tree.parents[lvl]
            steps.append((child, parent, 2.0 * sigma[parent, None], hinge_vertex[tree.hinges[lvl]]))
            tau[child] = tau[parent] - steps[-1][2] * Z[steps[-1][3]]
        use_t = np.empty(st.n_nodes, dtype=np.int64)
        use_t[tl.ravel()] = np.repeat(np.arange(T), 4)
        return cls(
            node_vertex, mid, seeds, Z, (tau, use_t, sigma[use_t, None]), exact=(Am, lu, dep, steps)
        )

    @classmethod
    def of_standard(cls, st: Stencils, tree: Callable[[], SpanningTree]) -> RigidFamily:
        """``build`` for the standard ``st.rows`` x ``st.cols`` lattice, kept for the last two lattices: a
        coarse-to-fine design needs each level's family twice (its own solve, then the next level's start;
        building it is costly at 128x128). ``tree``: makes the spanning tree on a miss."""
        key = (st.rows, st.cols)
        fam = _STANDARD.pop(key, None) or cls.build(st, tree())
        _STANDARD[key] = fam
        while len(_STANDARD) > 2:
            del _STANDARD[next(iter(_STANDARD))]
        return fam

    @staticmethod
    def deployment_angle(X: np.ndarray, st: Stencils) -> float:
        """ψ of a pattern near the family: half the median hole angle at the state-1 fold corners.

        (Every hole of a member is a rhombus with angle 2ψ there:
        docs/algorithm.md#rigid-deployability.)
        """
        hn = st.hole_nodes
        if not len(hn):
            return float(np.pi / 4)
        folds = st.folds[1].hole_folds
        v = X[hn]
        a = np.roll(v, -1, 1) - v
        b = np.roll(v, 1, 1) - v
        ang = np.arctan2(a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0], (a * b).sum(-1))
        ang = np.abs(ang[folds])
        # members exist up to the closed states themselves (a rigid 16x16 ellipse opens to 1.533)
        return float(np.clip(0.5 * np.median(ang), 1e-3, np.pi / 2 - 1e-3))

    # ---------------------------------------------------------------- maps
    def grid(self, S: np.ndarray) -> np.ndarray:
        """Closed-state-1 pattern vertices ``(G, 2)``."""
        if len(self.Z) > LARGE_GRID:
            core = self.core
            return core.E @ (core.Zc @ S)
        return self.Z @ S

    def nodes(self, S: np.ndarray, psi: float, grid: np.ndarray | None = None) -> np.ndarray:
        """Deployed nodes ``(V, 2)`` at deployment angle ``psi`` (``grid``: ``self.grid(S)`` when known)."""
        # Zn S is the grid's rows: the product over the G grid vertices, not the V nodes (twice as many)
        a = (self.grid(S) if grid is None else grid)[self.node_vertex]
        b = self.translations(S, a)
        c, s = np.cos(psi), np.sin(psi)
        return np.stack([c * a[:, 0] - s * b[:, 1], c * a[:, 1] + s * b[:, 0]], -1)

    def exact_nodes(self, S: np.ndarray, psi: float) -> np.ndarray:
        """``nodes(S, psi)`` with the family's rows met to round-off of the coordinates: the grid solved from
        the seeds by the midpoint rows (the build's LU, refined twice) instead of ``Z S``, whose stored
        round-off leaves them off by some hundred times more, and the tile translations integrated on that
        grid along the spanning tree (``build``'s ``τ``) instead of ``τ S``. The same member otherwise."""
        assert self.exact is not None and self.given_Y is None, "a built family's own gauge"
        A, lu, dep, steps = self.exact
        c = np.zeros((len(self.Z), 2))
        c[self.seeds] = S
        for _ in range(3):  # the solve, then two refinements on its residual
            c[dep] -= lu.solve(A @ c)
        _, use_t, sigma = self.parts
        t = np.zeros((int(use_t.max()) + 1, 2))
        for child, parent, two_sigma, vertex in steps:
            t[child] = t[parent] - two_sigma * c[vertex]
        a = c[self.node_vertex]
        b = t[use_t] - sigma * a
        co, si = np.cos(psi), np.sin(psi)
        return np.stack([co * a[:, 0] - si * b[:, 1], co * a[:, 1] + si * b[:, 0]], -1)

    def translations(self, S: np.ndarray, a: np.ndarray) -> np.ndarray:
        """``Y S`` given ``a = Zn S``; on a large lattice as ``(τ S)[tile] - σ a`` (T tile rows, not V nodes)."""
        if len(self.Z) <= LARGE_GRID or self.given_Y is not None:
            return self.Y @ S
        tau, use_t, sigma = self.parts
        return (tau @ S)[use_t] - sigma * a

    def jacobian(self, S: np.ndarray, psi: float) -> np.ndarray:
        """``∂vec(x)/∂p`` (dense, ``(2V, 2 nf + 1)``) for ``p = (S[:, 0], S[:, 1], ψ)``."""
        return self.jacobian_at(S, psi).reshape(2 * len(self.Zn), -1)

    def jacobian_at(self, S: np.ndarray, psi: float, nodes: np.ndarray | None = None) -> np.ndarray:
        """``∂x[nodes]/∂p`` as ``(n, 2, 2 nf + 1)``: coordinate ``d`` of node ``i`` in ``[i, d]`` (all nodes
        when ``nodes`` is None)."""
        Zn, Y = (self.Zn, self.Y) if nodes is None else self.rows(nodes)
        c, s = np.cos(psi), np.sin(psi)
        n, nf = Zn.shape
        D = np.empty((n, 2, 2 * nf + 1))
        D[:, 0, :nf] = c * Zn
        D[:, 0, nf : 2 * nf] = -s * Y
        D[:, 1, :nf] = s * Y
        D[:, 1, nf : 2 * nf] = c * Zn
        a = Zn @ S
        b = Y @ S
        D[:, 0, -1] = -s * a[:, 0] - c * b[:, 1]
        D[:, 1, -1] = -s * a[:, 1] + c * b[:, 0]
        return D

    def seeds_for_grid(self, grid: np.ndarray, normal: bool = False) -> np.ndarray:
        """Seeds ``S`` whose closed-state-1 grid is closest to ``grid`` ``(G, 2)`` (least squares); with
        ``normal``, above ``EXACT_GRID``, by the normal equations through the core (``Zᵀ Z = Zcᵀ (Eᵀ E) Zc``, ``Zᵀ grid = Zcᵀ (Eᵀ grid)``):
        ``Z`` holds the identity on its seed rows and the rest are means of them, so ``Zᵀ Z`` is well conditioned."""
        if not normal or len(self.Z) <= EXACT_GRID:
            S, *_ = np.linalg.lstsq(self.Z, grid, rcond=None)
            return S
        core = self.core
        ZtZ = core.ZcT @ ((core.ET @ core.E) @ core.Zc)
        return cho_solve(cho_factor(ZtZ), core.ZcT @ (core.ET @ grid))

    def member_seeds(self, X: np.ndarray, psi: float) -> np.ndarray | None:
        """Seeds of ``X`` where it is a member of this family at ``psi`` to round-off (a reduced solve's result),
        by least squares over the nodes of the tiles at a seed vertex alone; None where the member they give
        is further than round-off from ``X`` at any node (then ``fit`` over all nodes is the nearest)."""
        _, use_t, _ = self.parts
        at_seed = np.isin(use_t, use_t[np.isin(self.node_vertex, self.seeds)])
        nodes = np.flatnonzero(at_seed)
        zn, y = self.rows(nodes)
        c, s = np.cos(psi), np.sin(psi)
        nf = self.n_seeds
        K = np.empty((2 * len(nodes), 2 * nf))
        K[: len(nodes), :nf], K[: len(nodes), nf:] = c * zn, -s * y
        K[len(nodes) :, :nf], K[len(nodes) :, nf:] = s * y, c * zn
        sol, *_ = np.linalg.lstsq(K, np.concatenate([X[nodes, 0], X[nodes, 1]]), rcond=None)
        S = np.stack([sol[:nf], sol[nf:]], -1)
        off = float(np.abs(self.nodes(S, psi) - X).max())
        return S if off <= MEMBER_ROUNDOFF * float(np.abs(X).max()) else None

    def fit(self, X: np.ndarray, psi: float) -> tuple[np.ndarray, float]:
        """Seeds ``S`` whose pattern at ``psi`` is closest to ``X`` (least squares), and the rms gap."""
        c, s = np.cos(psi), np.sin(psi)
        V, nf = self.Zn.shape
        # x = c Zn Sx - s Y Sy ; y = c Zn Sy + s Y Sx
        # filled in place: ``np.block`` of the four products made each as a temporary first (the same numbers)
        K = np.empty((2 * V, 2 * nf))
        np.multiply(c, self.Zn, out=K[:V, :nf])
        np.multiply(-s, self.Y, out=K[:V, nf:])
        np.multiply(s, self.Y, out=K[V:, :nf])
        np.multiply(c, self.Zn, out=K[V:, nf:])
        rhs = np.concatenate([X[:, 0], X[:, 1]])
        sol, *_ = np.linalg.lstsq(K, rhs, rcond=None)
        S = np.stack([sol[:nf], sol[nf:]], -1)
        gap = float(np.sqrt(np.mean((self.nodes(S, psi) - X) ** 2)))
        return S, gap


_STANDARD: dict[tuple[int, int], RigidFamily] = {}  # ``of_standard``'s, the newest last


def resample_grid(grid: np.ndarray, rows: int, cols: int) -> np.ndarray:
    """The closed-state grid ``(m+1, n+1, 2)`` resampled to ``(rows+1, cols+1, 2)`` vertices, bilinear per cell.

    A coarse-to-fine start inside the rigid family. Doubling splits every cell in four, and the four
    quads of a convex cell are convex, so that refined grid folds no cell (a map of the deployed tiles
    can fold tiles); other ratios sample the same piecewise-bilinear map. (numpy, not scipy's
    ``RegularGridInterpolator``: importing ``scipy.interpolate`` cost more than the resampling.)
    """
    m, n = grid.shape[0] - 1, grid.shape[1] - 1
    yi, xi = np.linspace(0.0, m, rows + 1), np.linspace(0.0, n, cols + 1)
    i = np.minimum(np.floor(yi).astype(np.int64), m - 1)
    j = np.minimum(np.floor(xi).astype(np.int64), n - 1)
    a, b = (yi - i)[:, None, None], (xi - j)[None, :, None]
    g00, g01 = grid[i][:, j], grid[i][:, j + 1]
    g10, g11 = grid[i + 1][:, j], grid[i + 1][:, j + 1]
    return (1 - a) * ((1 - b) * g00 + b * g01) + a * ((1 - b) * g10 + b * g11)
