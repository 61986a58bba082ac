"""Building blocks of every constraint family: sparse Jacobians, corner stencils, ``Family`` and ``Stencils``.

``Stencils`` holds the index tables of a standard quad lattice (hinges, holes,
boundary tips, closed-state grid coordinates); the stencil helpers return
residuals with per-row node indices and gradients that :func:`jac` assembles
into CSR (see ``constraints.py`` for the conventions).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from scipy import sparse

from ...errors import SolveError
from ...pattern.geometry import cross2
from ...pattern.kinds.quad.lattice import DX, DY
from ...pattern.model import Pattern

TWO_PI = 2.0 * np.pi

# side (0 B, 1 R, 2 T, 3 L) of a free corner by tile parity and corner
# (docs/algorithm.md#shape-matching)
TIP_SIDE = np.array([[3, 0, 1, 2], [0, 1, 2, 3]])


def jac(m: int, nvar_nodes: int, nodes: np.ndarray, grads: np.ndarray) -> sparse.csr_matrix:
    """CSR Jacobian from per-row node indices ``(m, k)`` and gradients ``(m, k, 2)``."""
    return StencilPattern(m, nvar_nodes, nodes).matrix(grads)


def _same(kept: np.ndarray, nodes: np.ndarray) -> bool:
    """Whether a stencil's node array is the one a CSR structure was built for: the same object, or equal
    entries (most families build their node array afresh on every call, with the same entries)."""
    return kept is nodes or (kept.shape == nodes.shape and np.array_equal(kept, nodes))


class StencilPattern:
    """The CSR structure of a stencil Jacobian (rows of ``k`` nodes, ``2k`` entries before merging a node
    repeated in a row), sorted and merged once: a family whose stencil nodes are fixed fills only the values
    on every evaluation (``matrix``)."""

    def __init__(self, m: int, nvar_nodes: int, nodes: np.ndarray):
        k = nodes.shape[1] if nodes.ndim == 2 else 0
        self.nodes, self.shape = nodes, (m, 2 * nvar_nodes)
        cols = (2 * nodes[:, :, None] + np.arange(2)[None, None, :]).reshape(m, 2 * k)
        # per row by column, stably: entries of one node in a row are summed in stencil order
        self.order = np.argsort(cols, axis=1, kind="stable") + (2 * k * np.arange(m))[:, None]
        self.order = self.order.reshape(-1)
        c = cols.reshape(-1)[self.order]
        first = np.ones(len(c), dtype=bool)
        if k:
            first.reshape(m, 2 * k)[:, 1:] = (
                c.reshape(m, 2 * k)[:, 1:] != c.reshape(m, 2 * k)[:, :-1]
            )
        self.starts = np.flatnonzero(first)
        self.merged = len(self.starts) < len(c)  # a node repeated in some row
        self.indices = c[self.starts].astype(np.int32)
        counts = first.reshape(m, 2 * k).sum(1) if k else np.zeros(m, dtype=np.intp)
        self.indptr = np.concatenate([[0], np.cumsum(counts)]).astype(np.int32)
        lens = np.diff(np.append(self.starts, len(self.order)))
        self._runs = _Runs(self.order, self.starts, lens) if self.merged else None

    def matrix(self, grads: np.ndarray) -> sparse.csr_matrix:
        """The Jacobian with gradients ``(m, k, 2)`` on this pattern (canonical CSR)."""
        g = np.asarray(grads, dtype=float).reshape(-1)
        if self._runs is not None and self._runs.short:
            v = self._runs.sums(g)
        else:
            v = g[self.order]
            if self.merged and len(v):
                v = np.add.reduceat(v, self.starts)
        J = sparse.csr_matrix(
            (v, self.indices.copy(), self.indptr.copy()), shape=self.shape, copy=False
        )
        J.has_sorted_indices = True
        J.has_canonical_format = True
        return J


class _Runs:
    """The merged entries of a stencil pattern summed as ``np.add.reduceat`` sums them, without gathering every
    entry first: a run of entries (one node repeated in a row) is its first entry plus the sum of the others in
    order (numpy's reduction of a run shorter than its pairwise block, 8), so each entry is one gather and the
    runs of two or more get their few additions (``lens``: the entries of each run). ``short``: no run is 8
    entries or longer."""

    def __init__(self, order: np.ndarray, starts: np.ndarray, lens: np.ndarray):
        self.first = order[starts]
        self.multi = np.flatnonzero(lens > 1)
        ms, ml = starts[self.multi], lens[self.multi]
        self.short = bool(len(lens) == 0 or lens.max() < 8)
        # the second entry of every run of two or more, then each later entry where its run reaches that far
        self.second = order[ms + 1]
        self.later = [
            (sel := np.flatnonzero(ml > j), order[ms[sel] + j])
            for j in range(2, int(ml.max(initial=0)))
        ]

    def sums(self, g: np.ndarray) -> np.ndarray:
        v = g[self.first]
        if len(self.multi):
            rest = g[self.second]
            for sel, idx in self.later:
                rest[sel] += g[idx]
            v[self.multi] += rest
        return v


def _indptr(row: np.ndarray, m: int) -> np.ndarray:
    """CSR row pointers of entries in row order, ``row`` the row of each."""
    return np.concatenate([[0], np.cumsum(np.bincount(row, minlength=m))]).astype(np.int32)


class CoordinateColumns:
    """The x and y columns of a stencil Jacobian over the nodes, ``J[:, d::2]`` (CSR, ``jac``'s ``J``), and their
    transposes ``J[:, d::2].T.tocsr()``, as index tables: the same entries in the same order and each value the
    same sum of the same gradients (``_Runs``), so the four matrices come straight from the gradients, bit for
    bit what scipy's slicing and conversion of ``J`` give, without the 2n-column matrix or its pattern.

    In a row of ``J`` the entries sort by column ``2 node + d``, a repeated node's in stencil order: the x
    entries are the row's nodes sorted stably, the y entries the same with every gradient index one higher.
    A transpose orders the entries by node, then by row (``csr_tocsc``): one permutation ``t`` of the values.
    ``short``: no node repeats 8 times in a row (else ``StencilPattern`` sums by ``reduceat``)."""

    def __init__(self, m: int, n: int, nodes: np.ndarray):
        k = nodes.shape[1]
        on = np.argsort(nodes, axis=1, kind="stable")
        sn = np.take_along_axis(nodes, on, 1)
        first = np.ones((m, k), dtype=bool)
        first[:, 1:] = sn[:, 1:] != sn[:, :-1]
        starts = np.flatnonzero(first)
        lens = np.diff(np.append(starts, m * k))
        self.runs = _Runs((2 * (on + k * np.arange(m)[:, None])).reshape(-1), starts, lens)
        self.short = self.runs.short
        node = sn.reshape(-1)[starts]
        row = np.repeat(np.arange(m), first.sum(1))
        self.shape = (m, n)
        self.indices, self.indptr = node.astype(np.int32), _indptr(row, m)
        self.t = np.argsort(node, kind="stable")
        self.t_indices, self.t_indptr = row[self.t].astype(np.int32), _indptr(node, n)

    def matrices(self, grads: np.ndarray, scale: float, d: int):
        """``scale ·`` coordinate ``d``'s columns (CSR, m × n) and their transpose (CSR, n × m)."""
        v = self.runs.sums(np.asarray(grads, dtype=float).reshape(-1)[d:])
        v *= scale
        return (
            sparse.csr_matrix((v, self.indices, self.indptr), shape=self.shape, copy=False),
            sparse.csr_matrix(
                (v[self.t], self.t_indices, self.t_indptr), shape=self.shape[::-1], copy=False
            ),
        )


@dataclass(frozen=True, eq=False)
class StencilBlock:
    """``scale ·`` the per-row stencil Jacobian ``(nodes, grads)`` of ``family``, unassembled (``Family.block``)."""

    family: Family
    nodes: np.ndarray
    grads: np.ndarray
    scale: float

    @property
    def n_rows(self) -> int:
        return len(self.nodes)

    def matrix(self) -> sparse.csr_matrix:
        return self.scale * self.family._csr(len(self.nodes), self.nodes, self.grads)


class StackedJacobian:
    """A Jacobian kept as its blocks of rows, each a CSR matrix or a ``StencilBlock``. ``csr`` stacks them;
    ``columns`` and ``transposes`` give its x and y columns over the nodes and their transposes, the same arrays
    as ``J[:, d::2].tocsr()`` and its ``.T.tocsr()``, a stencil block's straight from its gradients
    (``CoordinateColumns``)."""

    def __init__(self, blocks: list, n_cols: int):
        self.blocks = blocks
        m = sum(b.n_rows if isinstance(b, StencilBlock) else b.shape[0] for b in blocks)
        self.shape = (m, n_cols)
        self._csr: sparse.csr_matrix | None = None
        self._by: list | None = None

    def csr(self) -> sparse.csr_matrix:
        """The stacked CSR matrix."""
        if self._csr is None:
            mats = [b.matrix() if isinstance(b, StencilBlock) else b for b in self.blocks]
            self._csr = sparse.vstack(mats, format="csr") if mats else sparse.csr_matrix(self.shape)
        return self._csr

    def __matmul__(self, other):
        return self.csr() @ other

    def _coordinates(self) -> list:
        """``[(J[:, 0::2], its transpose), (J[:, 1::2], its transpose)]``, formed once."""
        if self._by is None:
            parts = [self._block_coordinates(b) for b in self.blocks]
            if len(parts) == 1:
                self._by = parts[0]
            elif not parts:
                m, n = self.shape[0], self.shape[1] // 2
                self._by = [(sparse.csr_matrix((m, n)), sparse.csr_matrix((n, m)))] * 2
            else:  # the blocks' rows one after another: in a transpose, their columns
                self._by = [
                    (
                        sparse.vstack([p[d][0] for p in parts], format="csr"),
                        sparse.hstack([p[d][1] for p in parts], format="csr"),
                    )
                    for d in (0, 1)
                ]
        return self._by

    @staticmethod
    def _block_coordinates(b) -> list:
        if isinstance(b, StencilBlock):
            cols = b.family._columns_of(b.n_rows, b.nodes)
            if cols.short:
                return [cols.matrices(b.grads, b.scale, d) for d in (0, 1)]
            b = b.matrix()
        return [(Jd, Jd.T.tocsr()) for Jd in (b[:, 0::2].tocsr(), b[:, 1::2].tocsr())]

    def columns(self) -> tuple[sparse.csr_matrix, sparse.csr_matrix]:
        """``(J[:, 0::2], J[:, 1::2])`` as CSR matrices over the nodes."""
        (Ja, _), (Jb, _) = self._coordinates()
        return Ja, Jb

    def transposes(self) -> tuple[sparse.csr_matrix, sparse.csr_matrix]:
        """The transposes of ``columns`` (CSR)."""
        (_, AT), (_, BT) = self._coordinates()
        return AT, BT


def corner_angle(x: np.ndarray, tiles: np.ndarray, t: np.ndarray, k: np.ndarray):
    """Interior angle of CCW tiles ``t`` at corner ``k`` and its gradient.

    Returns ``θ (m,)``, nodes ``(m, 3)`` = (corner, next, prev) and gradients
    ``(m, 3, 2)``; θ turns the edge to ``next`` onto the edge to ``prev``.
    """
    n = tiles.shape[1]  # corners per tile
    v = tiles[t, k]
    a = tiles[t, (k + 1) % n]
    b = tiles[t, (k + n - 1) % n]
    A = x[a] - x[v]
    B = x[b] - x[v]
    cr = A[:, 0] * B[:, 1] - A[:, 1] * B[:, 0]
    dt = A[:, 0] * B[:, 0] + A[:, 1] * B[:, 1]
    th = np.mod(np.arctan2(cr, dt), TWO_PI)
    ga = np.stack([A[:, 1], -A[:, 0]], -1) / (A * A).sum(1, keepdims=True)
    gb = np.stack([-B[:, 1], B[:, 0]], -1) / (B * B).sum(1, keepdims=True)
    return th, np.stack([v, a, b], -1), np.stack([-(ga + gb), ga, gb], 1)


def cross_value(x: np.ndarray, h: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """g = cross(x_a - x_h, x_b - x_h) (``cross_term`` without the gradient)."""
    return cross2(x[a] - x[h], x[b] - x[h])


def cross_term(x: np.ndarray, h: np.ndarray, a: np.ndarray, b: np.ndarray):
    """g = cross(x_a - x_h, x_b - x_h) with its gradient (nodes h, a, b)."""
    A = x[a] - x[h]
    B = x[b] - x[h]
    g = A[:, 0] * B[:, 1] - A[:, 1] * B[:, 0]
    ga = np.stack([B[:, 1], -B[:, 0]], -1)
    gb = np.stack([-A[:, 1], A[:, 0]], -1)
    return g, np.stack([h, a, b], -1), np.stack([-(ga + gb), ga, gb], 1)


def sqlen_value(
    x: np.ndarray, p: np.ndarray, q: np.ndarray, u: np.ndarray, v: np.ndarray
) -> np.ndarray:
    """½(|x_q - x_p|² - |x_v - x_u|²)."""
    E = x[q] - x[p]
    F = x[v] - x[u]
    return 0.5 * ((E * E).sum(1) - (F * F).sum(1))


def sqlen_diff(x: np.ndarray, p: np.ndarray, q: np.ndarray, u: np.ndarray, v: np.ndarray):
    """½(|x_q - x_p|² - |x_v - x_u|²) with its gradient (nodes p, q, u, v)."""
    E = x[q] - x[p]
    F = x[v] - x[u]
    r = 0.5 * ((E * E).sum(1) - (F * F).sum(1))
    return r, np.stack([p, q, u, v], -1), np.stack([-E, E, F, -F], 1)


@dataclass
class Family:
    """One constraint family: ``kind`` is 'eq', 'ineq', 'fit' or 'reg'."""

    name: str
    kind: str
    # callable x -> (r, J): J is a sparse matrix or, for the usual per-row stencil, a pair ``(nodes (m, k),
    # gradients (m, k, 2))`` that becomes CSR only when asked (residual-only calls skip it)
    fn: Callable[[np.ndarray], tuple[np.ndarray, Any]]
    dim: int = 2  # residual units: length**dim (2: squared-length forms, 1: lengths, 0: angles)
    meta: dict = field(default_factory=dict)
    nv: int = 0  # nodes in the node array (Jacobian columns / 2)
    # optional x -> r without the gradients (inequalities are checked far more often than they are active)
    res: Callable[[np.ndarray], np.ndarray] | None = None
    # optional (x, act) -> the per-row stencil ``(nodes, grads)`` with the gradients of rows outside the boolean
    # mask ``act`` left zero (an inequality's gradient is asked only where it is inside its margin)
    active: Callable[[np.ndarray, np.ndarray], tuple[np.ndarray, np.ndarray]] | None = None

    # the CSR structure of the last stencil Jacobian, reused while its node array has the same entries (``_same``)
    _pattern: StencilPattern | None = field(default=None, repr=False, compare=False)
    # the same for its coordinate columns (``block``'s Jacobians split by coordinate), with the nodes they are of
    _columns: tuple | None = field(default=None, repr=False, compare=False)

    def __call__(self, x: np.ndarray):
        """Residuals ``r`` and their Jacobian (CSR)."""
        r, J = self.fn(x)
        if isinstance(J, tuple):
            J = self._csr(len(r), *J)
        return r, J

    def _csr(self, m: int, nodes: np.ndarray, grads: np.ndarray) -> sparse.csr_matrix:
        return self._pattern_of(m, nodes).matrix(grads)

    def _pattern_of(self, m: int, nodes: np.ndarray) -> StencilPattern:
        pat = self._pattern
        if pat is None or pat.shape != (m, 2 * self.nv) or not _same(pat.nodes, nodes):
            pat = self._pattern = StencilPattern(m, self.nv, nodes)
        return pat

    def _columns_of(self, m: int, nodes: np.ndarray) -> CoordinateColumns:
        """The ``CoordinateColumns`` of the stencil ``nodes``, kept while they have the same entries."""
        kept = self._columns
        if kept is None or kept[1].shape != (m, self.nv) or not _same(kept[0], nodes):
            kept = self._columns = (nodes, CoordinateColumns(m, self.nv, nodes))
        return kept[1]

    def block(self, x: np.ndarray, scale: float):
        """Residuals and ``scale ·`` their Jacobian as a block of ``StackedJacobian``: a per-row stencil kept
        unassembled (``StencilBlock``), else the scaled CSR matrix."""
        r, J = self.fn(x)
        if isinstance(J, tuple):
            return r, StencilBlock(self, J[0], J[1], scale)
        return r, scale * J

    def rows_jacobian(
        self, x: np.ndarray, rows: np.ndarray, m: int | None = None
    ) -> sparse.csr_matrix:
        """The Jacobian's ``rows`` only (CSR): an inequality family's active rows. Given the family's row
        count ``m``, a family with ``active`` computes those rows' gradients alone (:meth:`stencil_where`)."""
        if self.active is not None and m is not None:
            act = np.zeros(m, dtype=bool)
            act[rows] = True
            J = self.stencil_where(x, act)
        else:
            J = self.fn(x)[1]
        if isinstance(J, tuple):
            return jac(len(rows), self.nv, J[0][rows], J[1][rows])
        return J[rows]

    def residual(self, x: np.ndarray) -> np.ndarray:
        """Residuals only (no Jacobian assembly)."""
        return self.fn(x)[0] if self.res is None else self.res(x)

    def stencil_where(self, x: np.ndarray, act: np.ndarray):
        """The Jacobian of a per-row stencil family as ``(nodes, grads)``, of the rows in the boolean mask ``act``
        at least (all rows without ``active``; the others' gradients zero with it)."""
        return self.fn(x)[1] if self.active is None else self.active(x, act)

    def jacobian_where(self, x: np.ndarray, act: np.ndarray) -> sparse.csr_matrix:
        """The Jacobian (CSR, every row's sparsity) of the rows in ``act`` at least, as :meth:`stencil_where`."""
        if self.active is None:
            return self(x)[1]
        return self._csr(len(act), *self.active(x, act))  # every row's nodes: the kept structure


# ------------------------------------------------------------------ stencils
@dataclass(eq=False)
class Stencils:
    """Index arrays of a standard quad lattice pattern, used by every family."""

    rows: int
    cols: int
    tiles: np.ndarray
    n_nodes: int
    hinge_node: np.ndarray
    hinge_tiles: np.ndarray
    hinge_corner: np.ndarray
    folds: dict  # state -> FoldRule
    hole_nodes: np.ndarray
    gap_face: np.ndarray
    tip_nodes: np.ndarray
    tip_side: np.ndarray
    tip_tile: np.ndarray
    tip_corner: np.ndarray
    phi: dict  # state -> (T, 4, 2) integer pattern-grid coordinates of every tile corner

    @classmethod
    def from_pattern(cls, pattern: Pattern) -> Stencils:
        lat = pattern.lattice or {}
        rows, cols = int(lat.get("rows", 0)), int(lat.get("cols", 0))
        if rows * cols != pattern.n_tiles or pattern.parity != 0:
            raise SolveError(
                "inverse design needs a standard quad lattice pattern (rows x cols, parity 0)"
            )
        top = pattern.topology
        T = top.n_tiles
        r, c = np.divmod(np.arange(T), cols)
        par = (r + c) % 2
        k = np.arange(4)
        P = np.stack([c[:, None] + DX[None, :], r[:, None] + DY[None, :]], -1).astype(np.int64)
        kq = (k[None, :] - 1 + 2 * par[:, None]) % 4
        Q = np.stack([c[:, None] + DX[kq], r[:, None] + DY[kq]], -1).astype(np.int64)
        tiles = top.tiles
        use_t = np.full(top.n_nodes, -1)
        use_k = np.full(top.n_nodes, -1)
        use_t[tiles.ravel()] = np.repeat(np.arange(T), 4)
        use_k[tiles.ravel()] = np.tile(k, T)
        tips = top.free_nodes
        tt, tk = use_t[tips], use_k[tips]
        side = TIP_SIDE[par[tt], tk]
        return cls(
            rows=rows,
            cols=cols,
            tiles=tiles,
            n_nodes=top.n_nodes,
            hinge_node=top.hinge_node,
            hinge_tiles=top.hinge_tiles,
            hinge_corner=top.hinge_corner,
            folds={s: top.fold(s) for s in (1, 2)},
            hole_nodes=top.hole_nodes,
            gap_face=top.gap_face,
            tip_nodes=tips,
            tip_side=side,
            tip_tile=tt,
            tip_corner=tk,
            phi={1: P, 2: Q},
        )

    @property
    def n_hinges(self) -> int:
        return len(self.hinge_node)


# ------------------------------------------------------------- families


def corner_convexity(name: str, quads: np.ndarray, nv: int, margin: float = 0.0) -> Family:
    """cross(next - v, prev - v) - margin >= 0 at every corner of CCW ``quads`` (node indices)."""
    v = quads.ravel()
    a = np.roll(quads, -1, 1).ravel()
    b = np.roll(quads, 1, 1).ravel()

    def fn(x):
        g, nodes, gr = cross_term(x, v, a, b)
        return g - margin, (nodes, gr)

    return Family(
        name,
        "ineq",
        fn,
        2,
        meta={"quads": quads},
        nv=nv,
        res=lambda x: cross_value(x, v, a, b) - margin,
    )


def regularizer_pairs(st: Stencils) -> np.ndarray:
    """Tile pairs (r,c)-(r,c+2) and (r,c)-(r+2,c): same face in adjacent unit cells.

    (docs/algorithm.md#objective)"""
    M, N = st.rows, st.cols
    idx = np.arange(M * N).reshape(M, N)
    h = np.stack([idx[:, :-2].ravel(), idx[:, 2:].ravel()], -1)
    v = np.stack([idx[:-2, :].ravel(), idx[2:, :].ravel()], -1)
    return np.concatenate([h, v]).astype(np.int64)
