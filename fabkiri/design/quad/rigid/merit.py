"""One evaluation of the rigid-family solver's merit (``reduced._Merit``): its rows now, their normal
matrix or Jacobian on demand."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np
from scipy import sparse

from ...core.stencils import StackedJacobian, StencilBlock

if TYPE_CHECKING:
    from .reduced import _Merit


class _Evaluation:
    """The merit (or hard-fit) rows of one member ``p`` and, on demand, its normal matrix or Jacobian.

    The dense path hands over its rows ``r`` (``rows``, formed on the first ask: a trial step refused for a new
    inequality violation needs none) and, formed on the first ask, the dense Jacobian ``J`` of the first
    ``len(J)`` of them and, for the regulariser rows after those, ``reg = (tile corners, JᵀJ, Jᵀr)``;
    the block path computes its sparse rows only when asked (a step refused for a new inequality violation
    needs none).
    """

    def __init__(
        self,
        merit: _Merit,
        p: np.ndarray,
        Xc,
        gviol: float,
        hard: bool,
        rows=None,
        dense=None,
        values: dict | None = None,
    ):
        self.merit, self.p, self.Xc, self.gviol, self.hard = merit, p, Xc, gviol, hard
        self._r: np.ndarray | None = None
        self._lazy = rows  # dense path: () -> the rows
        self._k: tuple | None = None  # block path: the contact rows and their Jacobian
        self._blocks: tuple | None = None
        self._J: np.ndarray | None = None
        self._reg: tuple[Any, Any, Any] | None = (
            None  # the regulariser's (residual, normal matrix, gradient)
        )
        self._dense = (
            dense  # dense path: () -> (J, reg), called once, when a Jacobian is first asked for
        )
        self._values = (
            values  # block path: the inequality values gviol came from, reused by the rows
        )

    @property
    def X(self) -> np.ndarray:
        return self.Xc[0]

    def _rows(self):
        """``(r, Jx, Jc, Jk)``: the merit's rows with the contact rows (``Jk``, dense) after them."""
        if self._blocks is None:
            _, Jx, Jc = self.merit.rows(self.Xc, self.hard, self._values)
            _, Jk = self._contact()
            self._blocks = (self.r, Jx, Jc, Jk)
        return self._blocks

    def _contact(self):
        if self._k is None:
            self._k = self.merit.contact_rows(self.Xc, self.hard)
        return self._k

    @property
    def r(self) -> np.ndarray:
        """The rows (block path: without their Jacobians, which only an accepted step needs)."""
        if self._r is None and self._lazy is not None:
            self._r = self._lazy()
        elif self._r is None:
            r = self.merit.rows(self.Xc, self.hard, self._values, jacobians=False)[0]
            self._r = np.concatenate([r, self._contact()[0]])
        return self._r

    def _form(self) -> None:
        if self._dense is not None:
            (self._J, self._reg), self._dense = self._dense(), None

    def normal(self):
        """Reduced Gauss-Newton matrix ``JᵀJ`` and gradient ``Jᵀr``."""
        self._form()
        if self._J is None:
            r, Jx, Jc, Jk = self._rows()
            H, g = self.merit.normal(r[: len(r) - len(Jk)], Jx, Jc, self.p)
            return H + Jk.T @ Jk, g + Jk.T @ r[len(r) - len(Jk) :]
        J = self._J
        H, g = J.T @ J, J.T @ self.r[: len(J)]
        if self._reg is not None:
            _, Hr, gr = self._reg
            k = len(gr)
            H[:k, :k] += Hr
            g[:k] += gr
        return H, g

    def jacobian(self) -> np.ndarray:
        """Dense ``∂r/∂p``."""
        self._form()
        if self._J is None:
            _, Jx, Jc, Jk = self._rows()
            self._J = np.vstack([self.merit.reduced_jacobian(Jx, Jc, self.p), Jk])
        if self._reg is None:
            return self._J
        t = self.merit._tiles
        assert t is not None, "a regulariser comes only with the tile-shape rows"
        Jr = self.merit.w * t.regularizer_jacobian(self._reg[0])
        return np.vstack(
            [self._J, np.hstack([Jr, np.zeros((len(Jr), self._J.shape[1] - Jr.shape[1]))])]
        )


def reduced_normal(J: sparse.csr_matrix, D: np.ndarray, r: np.ndarray, dense_jd: float):
    """Reduced Gauss-Newton matrix ``Dᵀ JᵀJ D`` and gradient ``Dᵀ Jᵀ r``: through a dense ``J D`` when it has
    at most ``dense_jd`` entries, else through the sparse ``JᵀJ``."""
    if J.shape[0] * D.shape[1] <= dense_jd:
        JD = J @ D
        return JD.T @ JD, JD.T @ r
    H = (J.T @ J).tocsr()
    return D.T @ (H @ D), D.T @ (J.T @ r)


class KeptGridBlock:
    """The regulariser rows' grid block ``Zᵀ (JᵀJ) Z`` of one LM run (a stage) on the block path, formed at the
    run's first point and kept for its later points, a quasi-Newton block: on the largest lattices forming it is
    most of a step's cost, and over one stage the tile shapes move little. The gradient and the block of the
    active convexity rows (few) are each point's own, so the run descends the same merit by the same rules;
    ``steps.stage`` gives each stage its own."""

    def __init__(self, merit: _Merit, n_blocks: int):
        self.merit = merit
        self.n_blocks = n_blocks  # the grid rows' first blocks: the regulariser's
        self.H: np.ndarray | None = None

    def block(self, f, x: np.ndarray, scale: float):
        """``f.block(x, scale)`` (residuals, Jacobian block) of a regulariser on the grid; once this block is
        formed, where ``f`` gives ``Jᵀ y`` without its stencil (``meta["lean"]``), the residuals with a
        ``TransposedBlock``: the gradient is all a later point asks of those rows."""
        if self.H is None or "lean" not in f.meta:
            return f.block(x, scale)
        r, transposed = f.meta["lean"](x)
        return r, TransposedBlock(transposed, scale, len(r), f.nv)

    def normal(self, Jc, rc: np.ndarray):
        """``(H, g)`` of ``merit``'s grid rows ``Jc`` (a ``StackedJacobian``), as ``merit._grid_normal``'s but
        with the regulariser's block kept."""
        merit, n = self.merit, self.n_blocks
        reg, act = (type(Jc)(bs, Jc.shape[1]) for bs in (Jc.blocks[:n], Jc.blocks[n:]))
        if self.H is None:
            self.H = merit._grid_normal(reg, rc[: reg.shape[0]])[0]
        core = merit.fam.core
        grad = _transposed_product(Jc, rc)  # Jcᵀ rc by grid vertex and coordinate
        g = [core.ZcT @ (core.ET @ grad[:, d]) for d in (0, 1)]
        H = self.H
        if act.shape[0]:
            JC = merit._grid_to_p(act)
            H = H + JC.T @ JC
        return H, np.concatenate([*g, [0.0]])


class TransposedBlock:
    """``scale ·`` the Jacobian ``J`` of ``m`` rows over ``nv`` nodes as a block of a ``StackedJacobian`` that
    gives only ``Jᵀ y`` (``transposed``, a family's ``meta["lean"]``, no stencil formed): a kept grid block's
    later points."""

    def __init__(self, transposed, scale: float, m: int, nv: int):
        self._transposed, self.scale = transposed, scale
        self.shape = (m, 2 * nv)

    def transposed(self, y: np.ndarray) -> np.ndarray:
        """``Jᵀ y`` as ``(nv, 2)`` (node, coordinate)."""
        return self._transposed(self.scale * y)


def _transposed_product(J: StackedJacobian, r: np.ndarray) -> np.ndarray:
    """``Jᵀ r`` as ``(n, 2)`` (node, coordinate), a stencil block's summed from its gradients by node."""
    n = J.shape[1] // 2
    out = np.zeros((n, 2))
    o = 0
    for b in J.blocks:
        if isinstance(b, TransposedBlock):
            m = b.shape[0]
            out += b.transposed(r[o : o + m])
        elif isinstance(b, StencilBlock):
            m, k = b.nodes.shape
            w = (
                np.asarray(b.grads, dtype=float).reshape(m, k, 2)
                * (b.scale * r[o : o + m])[:, None, None]
            )
            for d in (0, 1):
                out[:, d] += np.bincount(b.nodes.reshape(-1), w[..., d].reshape(-1), minlength=n)
        else:
            m = b.shape[0]
            out += (b.T @ r[o : o + m]).reshape(n, 2)
        o += m
    return out
