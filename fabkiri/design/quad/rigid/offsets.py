"""The rigid-deployable family with parallelogram holes: one offset per hole.

Parallelogram holes: docs/algorithm.md#parallelogram-holes.

Every tile turns rigidly by ``-σ_T ψ`` (σ = ±1 in a checkerboard) from closed state 1 (ψ = 0) to closed
state 2 (ψ = π/2), as in the rhombus family (``family.py``), but the holes are parallelograms. Write ``y`` for
the deployed nodes' positions in state 1. Tile ``T``'s copy of node ``v`` sits at

    x(T, v; ψ) = Rot(-σ_T ψ) y_v + sin ψ · τ_T,

and the two tiles of a hinge ``h`` agree iff ``τ_B - τ_A = -2 σ_A J y_h``. Integrated around a hole (corners
S, E, N, W) that holds iff ``y_S + y_N = y_E + y_W``: the hole is a parallelogram at every ψ (its opposite
sides belong to tiles that turn alike). State 1 is closed iff every hole is flat there: its merge corners
lie on the segment of its fold corners, split by the hole's **offset** ``t`` (|t| < 1; 0 is a rhombus):

    y_m - y_m' = t (y_f - y_f'),

and then state 2 is closed too (the relative turn of the hole's sides is π). A boundary hinge whose notch is
closed in state 1 has its two far corners at one point; one whose notch is open is their midpoint (so it
closes in state 2). All rows are linear in ``y`` for fixed offsets: ``A(t) y = 0`` (per coordinate), with
``M + N + 2`` free nodes per coordinate (``seeds``, those of the rhombus family), the rest from one sparse LU.
So the members are ``y = Z(t) S``, every closed state linear in ``y``:

    x(ψ) = cos ψ · y + sin ψ · J (W y),    W = τ-integration minus σ (a sparse ``(V, V)`` map).

This is the additive-kirigami demo's freedom (an offset per hole) in closed form; its closed states have
straight slits with T-junctions, no gaps and no overlaps.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import sparse
from scipy.sparse.linalg import splu

from ....errors import SolveError
from ....pattern.topology import SpanningTree
from ...core.stencils import Stencils
from .family import RigidFamily


@dataclass(eq=False)
class OffsetFamily:
    """Closed-form rigid-deployable patterns with parallelogram holes of one lattice."""

    A0: sparse.csc_matrix  # (m, V) the rows at zero offsets
    off_row: np.ndarray  # (K,) row of each hole's offset equation
    off_a: np.ndarray  # (K,) its fold corners f, f' (the row reads y_m - y_m' - t (y_f - y_f'))
    off_b: np.ndarray
    seeds: np.ndarray  # (nf,) free nodes
    dep: np.ndarray  # (V - nf,) the other nodes
    W: sparse.csr_matrix  # (V, V) x(ψ) = cos ψ y + sin ψ J (W y)

    @property
    def n_seeds(self) -> int:
        return len(self.seeds)

    @property
    def n_holes(self) -> int:
        return len(self.off_row)

    @classmethod
    def build(cls, st: Stencils, tree: SpanningTree) -> OffsetFamily:
        V = st.n_nodes
        tl = st.tiles
        hn = st.hole_nodes
        K = len(hn)
        folds = st.folds[1].hole_folds
        j = np.where(
            folds[:, 0], 1, 0
        )  # first merge corner (0 or 1): the hole folds at the other pair
        ar = np.arange(K)
        m0, f0, m1, f1 = hn[ar, j], hn[ar, (j + 1) % 4], hn[ar, (j + 2) % 4], hn[ar, (j + 3) % 4]
        rows, cols, vals = [], [], []

        def add(r, c, v):
            rows.append(r)
            cols.append(c)
            vals.append(np.broadcast_to(np.asarray(v, dtype=float), np.shape(r)))

        # parallelogram: y_0 + y_2 - y_1 - y_3 = 0
        for c, v in ((hn[:, 0], 1.0), (hn[:, 2], 1.0), (hn[:, 1], -1.0), (hn[:, 3], -1.0)):
            add(ar, c, v)
        # flat in state 1: y_m - y_m' - t (y_f - y_f') = 0 (the t part in ``matrix``)
        add(K + ar, m0, 1.0)
        add(K + ar, m1, -1.0)
        # boundary hinges: far corners of the exterior gap together (notch closed in state 1) or the hinge
        # at their midpoint (open in state 1)
        fold = st.folds[1]
        A, B = st.hinge_tiles.T
        cA, cB = st.hinge_corner.T
        ext = (st.gap_face < 0).any(1)
        ext_folds = st.gap_face[np.arange(st.n_hinges), fold.fold_gap] < 0
        closed = np.flatnonzero(ext & ext_folds)
        opened = np.flatnonzero(ext & ~ext_folds)
        r0 = 2 * K
        a, b = fold.fold_ends[closed, 0], fold.fold_ends[closed, 1]
        add(r0 + np.arange(len(closed)), a, 1.0)
        add(r0 + np.arange(len(closed)), b, -1.0)
        r0 += len(closed)
        h = opened
        nA, pA = tl[A[h], (cA[h] + 1) % 4], tl[A[h], (cA[h] + 3) % 4]
        nB, pB = tl[B[h], (cB[h] + 1) % 4], tl[B[h], (cB[h] + 3) % 4]
        oa = np.where(nA == fold.fold_ends[h, 0], pA, nA)
        ob = np.where(nB == fold.fold_ends[h, 1], pB, nB)
        ro = r0 + np.arange(len(h))
        add(ro, st.hinge_node[h], 1.0)
        add(ro, oa, -0.5)
        add(ro, ob, -0.5)
        m = r0 + len(h)
        A0 = sparse.csc_matrix(
            (np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))), shape=(m, V)
        )
        # seeds: one node at each seed vertex of the rhombus family (at t = 0 the two systems agree)
        rig = RigidFamily.build(st, tree)
        first = np.full(int(rig.node_vertex.max()) + 1, -1)
        order = np.argsort(rig.node_vertex, kind="stable")
        nv_sorted = rig.node_vertex[order]
        starts = np.r_[0, np.flatnonzero(np.diff(nv_sorted)) + 1]
        first[nv_sorted[starts]] = order[starts]
        seeds = first[rig.seeds]
        dep = np.setdiff1d(np.arange(V), seeds)
        if len(dep) != m or (seeds < 0).any():
            raise SolveError(f"offset family: {m} rows for {len(dep)} dependent nodes")
        # τ per tile (per unit sin ψ), J (tau @ y): integrated along the tree from tile 0
        T = len(tl)
        N = st.cols
        sigma = np.where(np.arange(T) // N % 2 == np.arange(T) % N % 2, 1.0, -1.0)
        tau = np.zeros((T, V))
        for lvl in tree.levels():
            child, parent = tree.children[lvl], tree.parents[lvl]
            tau[child] = tau[parent]
            tau[child, st.hinge_node[tree.hinges[lvl]]] -= 2.0 * sigma[parent]
        use_t = np.empty(V, dtype=np.int64)
        use_t[tl.ravel()] = np.repeat(np.arange(T), 4)
        W = tau[use_t]
        W[np.arange(V), np.arange(V)] -= sigma[use_t]
        # sparse: a row holds the hinges on its tile's tree path (about M + N of V)
        return cls(A0, K + np.arange(K), f0, f1, seeds, dep, sparse.csr_matrix(W))

    # ---------------------------------------------------------------- maps
    def matrix(self, t: np.ndarray) -> sparse.csc_matrix:
        """``A(t)``."""
        At = sparse.csc_matrix(
            (np.r_[-t, t], (np.r_[self.off_row, self.off_row], np.r_[self.off_a, self.off_b])),
            shape=self.A0.shape,
        )
        return (self.A0 + At).tocsc()

    def _blocks(self) -> tuple[_Columns, _Columns]:
        """``A(t)``'s dependent and seed columns as fixed sparsity patterns (built once)."""
        if getattr(self, "_cols", None) is None:
            self._cols = (_Columns.build(self, self.dep), _Columns.build(self, self.seeds))
        return self._cols

    def _factor(self, t: np.ndarray):
        """``A(t)``'s seed columns and the LU of its dependent columns; the last one is kept (LM's step limiting
        and its next evaluation ask for the same offsets)."""
        key = np.asarray(t, dtype=float).tobytes()
        cached = getattr(self, "_last", None)
        if cached is not None and cached[0] == key:
            return cached[1], cached[2]
        dep, seeds = self._blocks()
        try:
            lu = splu(dep.at(t), permc_spec="COLAMD")
        except RuntimeError as exc:
            raise SolveError(f"offset family: singular at these offsets ({exc})") from None
        self._last = (key, seeds.at(t), lu)
        return self._last[1], lu

    def state1(self, S: np.ndarray, t: np.ndarray, jac: bool = False):
        """State-1 nodes ``y`` ``(V, 2)`` of seeds ``S`` ``(nf, 2)`` and offsets ``t``; with ``jac`` also
        ``Z = ∂y/∂S`` ``(V, nf)`` (both coordinates) and ``Dt = ∂y/∂t`` ``(V, 2, K)``."""
        As, lu = self._factor(t)
        V = self.W.shape[0]
        y = np.zeros((V, 2))
        y[self.seeds] = S
        y[self.dep] = -lu.solve(np.asarray(As @ S))
        if not jac:
            return y
        Z = np.zeros((V, self.n_seeds))
        Z[self.seeds, np.arange(self.n_seeds)] = 1.0
        Z[self.dep] = -lu.solve(As.toarray())
        K = self.n_holes
        # A dy/dt_k = -(∂A/∂t_k) y: one row per hole, value (y_f - y_f')
        R = np.zeros((self.A0.shape[0], 2 * K))
        d = y[self.off_a] - y[self.off_b]
        R[self.off_row, np.arange(K)] = d[:, 0]
        R[self.off_row, K + np.arange(K)] = d[:, 1]
        Dt = np.zeros((V, 2, K))
        sol = lu.solve(R)
        Dt[self.dep, 0] = sol[:, :K]
        Dt[self.dep, 1] = sol[:, K:]
        return y, Z, Dt

    def at(self, y: np.ndarray, psi: float) -> np.ndarray:
        """Nodes at deployment angle ψ: ``cos ψ y + sin ψ J (W y)`` (ψ = π/2: closed state 2)."""
        w = self.W @ y
        return np.cos(psi) * y + np.sin(psi) * np.stack([-w[:, 1], w[:, 0]], -1)


@dataclass(eq=False)
class _Columns:
    """Columns ``cols`` of ``A(t) = A0 + offsets`` on a fixed CSC pattern: ``A(t)[:, cols]`` without the sparse
    sum and the column slicing (two thirds of an 81-tile offset solve's member evaluations), same entries."""

    pattern: sparse.csc_matrix  # the union of A0's entries and the offset entries in these columns
    base: np.ndarray  # A0's values on the pattern
    pos_a: (
        np.ndarray
    )  # the pattern positions of the offset entries -t (hole k's fold corner f) in these columns
    k_a: np.ndarray  # their holes
    pos_b: np.ndarray  # and of +t (fold corner f')
    k_b: np.ndarray

    @classmethod
    def build(cls, fam: OffsetFamily, cols: np.ndarray) -> _Columns:
        A0 = fam.A0.tocoo()
        m, K, n0 = fam.A0.shape[0], fam.n_holes, A0.nnz
        where = np.full(fam.A0.shape[1], -1)
        where[cols] = np.arange(len(cols))
        r = np.concatenate([A0.row, fam.off_row, fam.off_row])
        c = where[np.concatenate([A0.col, fam.off_a, fam.off_b])]
        keep = c >= 0
        P = sparse.csc_matrix((np.ones(int(keep.sum())), (r[keep], c[keep])), shape=(m, len(cols)))
        P.sum_duplicates()
        P.sort_indices()
        # an entry's position on the pattern: CSC order is (column, row) order
        keys = np.repeat(np.arange(len(cols)), np.diff(P.indptr)) * m + P.indices
        slot = np.full(len(r), -1)
        slot[keep] = np.searchsorted(keys, c[keep] * m + r[keep])
        base = np.zeros(P.nnz)
        base[slot[:n0][keep[:n0]]] = A0.data[keep[:n0]]
        sa, sb = slot[n0 : n0 + K], slot[n0 + K :]
        return cls(
            P, base, sa[sa >= 0], np.flatnonzero(sa >= 0), sb[sb >= 0], np.flatnonzero(sb >= 0)
        )

    def at(self, t: np.ndarray) -> sparse.csc_matrix:
        """``A(t)[:, cols]`` (CSC, sorted, no stored zeros: the entries of ``(A0 + At)[:, cols]``)."""
        data = self.base.copy()
        data[self.pos_a] += -t[self.k_a]
        data[self.pos_b] += t[self.k_b]
        P = self.pattern
        M = sparse.csc_matrix((data, P.indices.copy(), P.indptr.copy()), shape=P.shape)
        M.eliminate_zeros()  # in place: hence the copies of the pattern's index arrays
        return M
