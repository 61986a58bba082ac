"""The symmetric reduced solver's normal matrix formed over half the seeds (``mirror.py``).

A symmetric member is ``p = P q`` with about half as many unknowns, but forming the whole ``H = JᵀJ``
over ``p`` and then ``Pᵀ H P`` costs what the unsymmetric solve costs per step: the symmetric 96x96 ellipse
spent about 40 % of its solve there (most of it in the grid block ``Zᵀ (JcᵀJc) Z``). Every product that
meets ``p``'s columns goes through ``P`` first here: ``J P`` (dense path), ``D P`` at the nodes, and on
the grid ``Z B_x`` and ``Z B_y`` (``B_d``: the rows of ``P`` of seed coordinate d, on the about nf/2 columns
of q they reach, against nf columns of p), so the dense products shrink about fourfold. The same matrix to
round-off (tests).
"""

from __future__ import annotations

from typing import Any

import numpy as np
from scipy import sparse

from .merit import reduced_normal


class HalfBlocks:
    """``P`` by seed coordinate: the columns of q that coordinate d reaches and ``P``'s dense block there
    (``nf × k_d``); ``Z B_d`` on the grid, formed on first use (the family's ``Z`` is fixed per solve)."""

    def __init__(self, P: sparse.csr_matrix, nf: int):
        self.nq, self.np = P.shape[1], P.shape[0]
        self.cols: list[np.ndarray] = []
        self.B: list[np.ndarray] = []
        for d in (0, 1):
            block = P[d * nf : (d + 1) * nf].tocsr()
            cols = np.unique(block.indices)
            self.cols.append(cols)
            self.B.append(block[:, cols].toarray())
        self._ZB: tuple[Any, list[np.ndarray]] | None = None

    def ZB(self, Z: np.ndarray) -> list[np.ndarray]:
        """``[Z B_x, Z B_y]`` (``G × k_d``)."""
        if self._ZB is None or self._ZB[0] is not Z:
            self._ZB = (Z, [Z @ B for B in self.B])
        return self._ZB[1]

    def grid_normal(self, Z: np.ndarray, Jc, rc: np.ndarray, dense_jd: float):
        """``(C P)ᵀ JcᵀJc (C P)`` and ``(C P)ᵀ Jcᵀ rc``, with ``C`` = ∂c/∂p (``Z`` per coordinate, no ψ), by
        the coordinate blocks of ``reduced._Merit._grid_normal``, each over the columns its coordinate reaches."""
        Zb = self.ZB(Z)
        Jd = list(Jc.columns())  # ``StackedJacobian``: J[:, 0::2] and J[:, 1::2]
        H, g = np.zeros((self.nq, self.nq)), np.zeros(self.nq)
        # the unsymmetric merit's choice (by p's width): by q's, the 48x48 grid's went dense, and slower
        if Jc.shape[0] * self.np <= dense_jd:
            A = [Jd[d] @ Zb[d] for d in (0, 1)]
            for a in (0, 1):
                g[self.cols[a]] = A[a].T @ rc
                for b in (0, 1):
                    H[np.ix_(self.cols[a], self.cols[b])] = A[a].T @ A[b]
            return H, g
        for a in (0, 1):
            g[self.cols[a]] = Zb[a].T @ (Jd[a].T @ rc)
            for b in range(a, 2):
                Hab = Zb[a].T @ ((Jd[a].T @ Jd[b]) @ Zb[b])
                H[np.ix_(self.cols[a], self.cols[b])] = Hab
                H[np.ix_(self.cols[b], self.cols[a])] = Hab.T
        return H, g


def _through(P: sparse.csr_matrix, J: np.ndarray) -> np.ndarray:
    """``J P`` (dense)."""
    return np.asarray((P.T @ J.T).T)


def half_normal(ev: Any, P: sparse.csr_matrix, halves: HalfBlocks):
    """``(J P)ᵀ (J P)`` and ``(J P)ᵀ r`` of a reduced evaluation (``merit._Evaluation``) at ``p = P q``:
    on the block path (large lattices) its node rows through ``D P``, its grid rows by ``HalfBlocks`` and the
    closed states' contact rows through ``P``; on the dense path ``Pᵀ (JᵀJ) P`` (a 32x32 J has 133 columns:
    as cheap either way)."""
    ev._form()
    if ev.merit._half is not None:  # the dense path formed over q (``mirror_dense``)
        return ev.normal()
    if ev._J is not None:  # a dense path over p
        H, g = ev.normal()
        return np.asarray(P.T @ np.asarray(P.T @ H).T), np.asarray(P.T @ g)
    r, Jx, Jc, Jk = ev._rows()
    merit, nx, nk = ev.merit, Jx.shape[0], len(Jk)
    Js, D = merit._touched(Jx, ev.p)
    Hx, gx = reduced_normal(Js, _through(P, D), r[:nx], merit.dense_jd())
    Hc, gc = halves.grid_normal(merit.fam.Z, Jc, r[nx : len(r) - nk], merit.dense_jd())
    JkP = _through(P, Jk)
    return Hx + Hc + JkP.T @ JkP, gx + gc + JkP.T @ r[len(r) - nk :]
