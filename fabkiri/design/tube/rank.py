"""Local dimension of the reconfigurable tube family, with and without rigid deployability.

At a sheet ``x`` that satisfies the equalities, the null space of their Jacobian is the family's
tangent space. Two families of the ``rows x (cols + 1)`` seam-copy sheet (docs/tubes.md) are measured:

* **tube**: edge pairs and rings of both closed states, the deployed seam as a *free* rigid map
  ``x_copy = R(β) x_first + τ`` (3 extra unknowns: β, τ), and a pure translation seam in both closed
  states (:func:`fabkiri.design.tube.periodic.closed_seam`);
* **rigid tube**: the same plus the hinge sums (docs/algorithm.md#rigid-deployability).

Hinge sums imply the rings, so the rigid family lies inside the tube family; if adding them does not
raise the rank, both have the same tangent space and, where the rigid family is a manifold of that
dimension, the tubes near ``x`` *are* rigid-deployable. The planar sheet (no seam rows) is measured the
same way as a control: there the hinge sums do cut dimensions (the table in
docs/algorithm.md#reconfigurability).

Dimensions are raw null-space dimensions: they include the 4 similarities of the plane (translations,
rotation, scale), which every family here keeps.
"""

from __future__ import annotations

import numpy as np
from scipy import sparse
from scipy.sparse.linalg import lsqr

from ...pattern.kinds.periodic.sheet import Seam, seam_map
from ..core.lm import halving_gauss_newton
from ..quad import constraints as C
from . import periodic as P

RCOND = 1e-9  # singular values below this share of the largest count as zero


def free_seam_rows(seam: Seam, st: C.Stencils, x: np.ndarray) -> sparse.csr_matrix:
    """Linearised ``x_copy - R(β) x_first - τ = 0`` at β = the current seam rotation, over ``(x, β, τ)``.

    Rows ``2i + d`` per identified node pair; the last three columns are dβ, dτ_x, dτ_y.
    """
    pairs = seam.node_pairs(st.tiles)
    a = x[pairs[:, 0]]
    beta = seam_map(x[st.tiles], seam).rotation  # the current deployed seam rotation
    cb, sb = np.cos(beta), np.sin(beta)
    R = np.array([[cb, -sb], [sb, cb]])
    dR = np.array([[-sb, -cb], [cb, -sb]])
    n2, m = x.size, len(pairs)
    i = np.repeat(np.arange(2 * m), 6)
    d = np.tile(np.arange(2), m)
    p = np.repeat(pairs, 2, axis=0)
    cols = np.stack(
        [
            2 * p[:, 1] + d,
            2 * p[:, 0],
            2 * p[:, 0] + 1,
            np.full(2 * m, n2),
            np.full(2 * m, n2 + 1) + d,
            np.full(2 * m, n2 + 1) + (1 - d),
        ],
        -1,
    ).ravel()
    dbeta = (a @ dR.T).ravel()
    vals = np.stack(
        [np.ones(2 * m), -R[d, 0], -R[d, 1], -dbeta, -np.ones(2 * m), np.zeros(2 * m)], -1
    ).ravel()
    return sparse.csr_matrix((vals, (i, cols)), shape=(2 * m, n2 + 3))


def _pad(J: sparse.spmatrix, extra: int) -> sparse.csr_matrix:
    return sparse.hstack([J, sparse.csr_matrix((J.shape[0], extra))]).tocsr()


def _rank(J: sparse.spmatrix) -> tuple[int, float]:
    """Numerical rank and the gap ``σ_rank / σ_(rank+1)`` (inf when full) of a Jacobian."""
    s = np.linalg.svd(J.toarray(), compute_uv=False)
    r = int((s > RCOND * s[0]).sum())
    gap = float(s[r - 1] / s[r]) if r < len(s) and s[r] > 0 else float("inf")
    return r, gap


def tube_jacobian(
    st: C.Stencils, seam: Seam, x: np.ndarray, closed: tuple[int, ...] = (1, 2), rigid: bool = False
) -> sparse.csr_matrix:
    """Jacobian over ``(x, β, τ)`` of reconfigurability, the free deployed seam, translation seams in the
    ``closed`` states and, if ``rigid``, the hinge sums. Column ``x.size`` is the deployed seam's turn β."""
    nv = st.n_nodes
    fams = [
        C.edge_pairs(st, 1, nv),
        C.edge_pairs(st, 2, nv),
        C.rings(st, 1, nv),
        C.rings(st, 2, nv),
    ]
    fams += [P.closed_seam(seam, st, s, nv) for s in closed]
    fams += [C.hinge_sums(st, nv)] if rigid else []
    return sparse.vstack(
        [_pad(sparse.vstack([f(x)[1] for f in fams]), 3), free_seam_rows(seam, st, x)]
    ).tocsr()


def family_dimensions(st: C.Stencils, seam: Seam, x: np.ndarray) -> dict:
    """Unknowns, equations, rank, null dimension and rank gap of each family at ``x``.

    ``x`` are the sheet's deployed nodes; keys ``planar`` (no seam rows), ``tube_closed1`` (a translation
    seam in closed state 1 only) and ``tube`` (in both), each also with ``_rigid`` (hinge sums added).
    """
    nv = st.n_nodes
    out = {}
    for rigid in (False, True):
        tag = "_rigid" if rigid else ""
        planar = [
            C.edge_pairs(st, 1, nv),
            C.edge_pairs(st, 2, nv),
            C.rings(st, 1, nv),
            C.rings(st, 2, nv),
        ]
        planar += [C.hinge_sums(st, nv)] if rigid else []
        Js = {
            "planar": sparse.vstack([f(x)[1] for f in planar]),
            "tube_closed1": tube_jacobian(st, seam, x, (1,), rigid),
            "tube": tube_jacobian(st, seam, x, (1, 2), rigid),
        }
        for name, J in Js.items():
            r, gap = _rank(J)
            out[name + tag] = {
                "unknowns": J.shape[1],
                "equations": J.shape[0],
                "rank": r,
                "dimension": J.shape[1] - r,
                "gap": gap,
            }
    return out


def _free_residual(
    fams: list, seam: Seam, st: C.Stencils, x: np.ndarray
) -> tuple[np.ndarray, float]:
    """Equality residuals with the deployed seam map fitted (Kabsch) to the sheet, and its turn β."""
    m = seam_map(x[st.tiles], seam)
    pairs = seam.node_pairs(st.tiles)
    c, s = np.cos(m.rotation), np.sin(m.rotation)
    seam_r = x[pairs[:, 1]] - x[pairs[:, 0]] @ np.array([[c, -s], [s, c]]).T - m.translation
    return np.concatenate([f(x)[0] for f in fams] + [seam_r.ravel()]), m.rotation


def project_free(st: C.Stencils, seam: Seam, x: np.ndarray, tol: float = 1e-12, max_iter: int = 80):
    """Gauss-Newton minimum-norm steps onto the tube family with the deployed seam map *free*.

    Unlike the design solver, which fixes the deployed seam by its target, this lets the projection pick
    any rigid seam map, a cone's rotation included; it answers where a sheet near ``x`` that is a tube in
    both closed states can be. Returns ``(x, max |r|, deployed seam turn β in rad, steps)``.
    """
    nv = st.n_nodes
    fams = [
        C.edge_pairs(st, 1, nv),
        C.edge_pairs(st, 2, nv),
        C.rings(st, 1, nv),
        C.rings(st, 2, nv),
        P.closed_seam(seam, st, 1, nv),
        P.closed_seam(seam, st, 2, nv),
    ]

    def step(
        y, state
    ):  # the minimum-norm step in the nodes (the seam map's last 3 unknowns are refitted)
        J = tube_jacobian(st, seam, y)
        return lsqr(J, -state[0], atol=1e-15, btol=1e-15, iter_lim=20 * J.shape[1])[0][:-3].reshape(
            -1, 2
        )

    # halved up to 14 times until the residual norm drops (β, τ are refitted to the new sheet)
    x, (r, beta), steps = halving_gauss_newton(
        x,
        _free_residual(fams, seam, st, x),
        step,
        lambda y: _free_residual(fams, seam, st, y),
        tol,
        max_iter,
        14,
    )
    return x, float(np.abs(r).max()), float(beta), steps
