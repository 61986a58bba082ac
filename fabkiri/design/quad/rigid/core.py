"""A sparse factor of the rigid family's grid basis: ``Z = E Z[core]`` (``family.py``).

The closed-state-1 grid ``c = Z S`` of a member satisfies one midpoint row per dependent vertex,
``c_z = (c_a + c_b) / 2``. ``Z`` is dense (every interior vertex depends on every boundary seed), but a
dependent vertex whose two ends are kept is their mean: eliminating such a set of vertices leaves the
rest determined by the same kind of rows on the kept vertices alone (the eliminated ends substituted,
each row a few entries longer). After a couple of such levels

    Z = E Z[core],   E sparse (G × g, a few entries a row),   g ≈ G / 4,

exactly (the rows hold for every member; round-off apart). The grid block of the reduced normal matrix
``Zᵀ K Z`` (``reduced._Merit._grid_normal``) is then ``Z[core]ᵀ (Eᵀ K E) Z[core]``: the dense products
run over g rows instead of G.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import sparse
from scipy.sparse import csgraph

# two levels: the third makes the rows of ``Eᵀ K E`` about twice as long for a quarter fewer vertices, and
# the sparse product ``(Eᵀ K E) Z[core]`` then costs more than the dense one saves (128x128 grid block)
LEVELS = 2


@dataclass(frozen=True, eq=False)
class GridCore:
    """``Z = E @ Zc``: the kept grid vertices ``core``, the sparse ``E`` and ``Zc = Z[core]`` (with its
    transpose, contiguous, for the products ``Zcᵀ W``)."""

    core: np.ndarray  # (g,) kept grid vertices, seeds among them
    E: sparse.csr_matrix  # (G, g)
    ET: sparse.csr_matrix  # (g, G)
    Zc: np.ndarray  # (g, nf)
    ZcT: np.ndarray  # (nf, g)

    def reduce(self, K: sparse.spmatrix) -> sparse.csr_matrix:
        """``Eᵀ K E`` of a grid matrix ``K`` (G × G)."""
        return (self.ET @ (K @ self.E)).tocsr()

    def quadratic(self, K: sparse.spmatrix) -> np.ndarray:
        """``Zᵀ K Z`` through the core: ``Zcᵀ ((Eᵀ K E) Zc)``."""
        return self.ZcT @ (self.reduce(K) @ self.Zc)


def grid_core(midpoint: np.ndarray, Z: np.ndarray, levels: int = LEVELS) -> GridCore:
    """The core of the grid basis ``Z`` (G × nf) whose rows ``midpoint`` ``(z, a, b)`` hold
    (``c_z = (c_a + c_b) / 2``, one row per dependent vertex ``z``).

    Each level takes a set of the rows' vertices ``z`` (``_independent_rows``) no two of which meet in a
    taken row, eliminates them and substitutes them in the other rows. Falls back to the
    whole grid (``E`` the identity) if the product does not give ``Z`` back."""
    G = Z.shape[0]
    m = len(midpoint)
    z, a, b = midpoint.T
    A = sparse.csr_matrix(
        (np.r_[np.ones(m), np.full(2 * m, -0.5)], (np.tile(np.arange(m), 3), np.r_[z, a, b])),
        shape=(m, G),
    )  # repeated ends (a == b) are summed
    pivot = z.astype(np.int64)
    T = sparse.identity(G, format="csr")
    keep = np.ones(G, dtype=bool)
    for _ in range(levels):
        chosen = _independent_rows(A, pivot)
        if not len(chosen):
            break
        keep[pivot[chosen]] = False
        A, pivot, step = _eliminate(A, pivot, chosen, G)
        T = (T @ step).tocsr()
    core = np.flatnonzero(keep)
    E = T[:, core].tocsr()
    Zc = np.ascontiguousarray(Z[core])
    if _largest(E @ Zc - Z) > 1e-12 * max(1.0, _largest(Z)):
        core, E = np.arange(G), sparse.identity(G, format="csr")  # pragma: no cover - rows exact
        Zc = np.ascontiguousarray(Z)
    return GridCore(core, E, E.T.tocsr(), Zc, np.ascontiguousarray(Zc.T))


def _largest(a: np.ndarray) -> float:
    """``np.abs(a).max(initial=0.0)``, without the (G, nf) array of absolute values."""
    return float(np.maximum(a.max(initial=0.0), -a.min(initial=0.0)))


def _independent_rows(A: sparse.csr_matrix, pivot: np.ndarray) -> np.ndarray:
    """Rows whose pivots can be eliminated together: no chosen pivot appears in another chosen row (and
    none whose pivot's coefficient has cancelled). Greedily, shortest rows first, then by the pivot's
    colour (``_colours``: on the lattice a row's ends are its pivot's neighbours, so one colour class of
    pivots is independent; by vertex alone 5047 of the 128x128 grid's 16641 vertices stay, 4416 so)."""
    lengths = np.diff(A.indptr)
    order = np.lexsort((pivot, _colours(A, pivot)[pivot], lengths))
    order = order[np.asarray(A[order, pivot[order]]).ravel() != 0.0]
    chosen, blocked, taken = [], set(), set()
    ind, ptr = A.indices, A.indptr
    for k in order.tolist():
        p = int(pivot[k])
        others = [int(v) for v in ind[ptr[k] : ptr[k + 1]] if v != p]
        if p in blocked or any(v in taken for v in others):
            continue
        chosen.append(k)
        taken.add(p)
        blocked.update(others)
    return np.array(chosen, dtype=np.int64)


def _colours(A: sparse.csr_matrix, pivot: np.ndarray) -> np.ndarray:
    """``(G,)`` parity of each vertex's distance from the first vertex of its component in the graph that
    joins a row's pivot to its other vertices (a 2-colouring where that graph is bipartite)."""
    G = A.shape[1]
    coo = A.tocoo()
    graph = sparse.csr_matrix((np.ones(coo.nnz), (pivot[coo.row], coo.col)), shape=(G, G))
    _, label = csgraph.connected_components(graph, directed=False)
    roots = np.unique(label, return_index=True)[1]
    d = csgraph.dijkstra(graph, directed=False, indices=roots, unweighted=True, min_only=True)
    return np.where(np.isfinite(d), d, 0).astype(np.int64) % 2


def _eliminate(A: sparse.csr_matrix, pivot: np.ndarray, chosen: np.ndarray, G: int):
    """Eliminate the pivots of rows ``chosen``: ``(A', pivot', T)`` with ``c = T c`` on every solution
    (``T``: identity on the other vertices, a chosen pivot's row ``-A[k, others] / A[k, p]``) and ``A' = A T``
    on the rows left."""
    P = pivot[chosen]
    rows = A[chosen].tocoo()
    diag = np.asarray(A[chosen, P]).ravel()
    off = rows.col != P[rows.row]
    B = sparse.csr_matrix(
        (-rows.data[off] / diag[rows.row[off]], (P[rows.row[off]], rows.col[off])), shape=(G, G)
    )
    ident = np.ones(G)
    ident[P] = 0.0
    step = (sparse.diags(ident, format="csr") + B).tocsr()
    left = np.setdiff1d(np.arange(A.shape[0]), chosen)
    A2 = (A[left] @ step).tocsr()
    A2.eliminate_zeros()
    return A2, pivot[left], step
