"""The smooth-shape-change regulariser (algorithm spec §3) as least-squares residuals.

    E_reg(x) = (1/|Π|) Σ_{(T,U)∈Π} Σ_k [(ℓ_T,k - ℓ_U,k)² + (θ_T,k - θ_U,k)²]

over pairs of same-parity tiles two apart in a row or a column. It is written
as ``E_reg = |r|²`` with ``r`` the stacked differences divided by ``√|Π|``, so
the solver can treat it with Gauss-Newton like every other family. Lengths are
in normalised units (initial tile edge 1).
"""

from __future__ import annotations

import numpy as np

from ..pattern.geometry import wrap_angle
from .constraints import Family, Stencils, corner_angle, regularizer_pairs


def regularizer(st: Stencils, nv: int) -> Family:
    pairs = regularizer_pairs(st)
    P = len(pairs)
    tl = st.tiles
    T, U = pairs[:, 0], pairs[:, 1]
    k = np.arange(4)
    tT = np.repeat(T, 4)
    tU = np.repeat(U, 4)
    kk = np.tile(k, P)
    w = 1.0 / np.sqrt(max(P, 1))

    # edge k: corner k -> k+1, in tile T (1) and tile U (2) of every pair
    a1, b1 = tl[tT, kk], tl[tT, (kk + 1) % 4]
    a2, b2 = tl[tU, kk], tl[tU, (kk + 1) % 4]
    m = len(kk)
    t_both, k_both = np.concatenate([tT, tU]), np.concatenate([kk, kk])
    # one stencil of 6 nodes a row: a length row uses 4 (the other two repeat a node with zero gradient)
    len_nodes = np.stack([a1, b1, a2, b2, a1, a1], -1)

    def fn(x):
        E1, E2 = x[b1] - x[a1], x[b2] - x[a2]
        l1, l2 = np.linalg.norm(E1, axis=1), np.linalg.norm(E2, axis=1)
        e1, e2 = E1 / l1[:, None], E2 / l2[:, None]
        th, n, g = corner_angle(x, tl, t_both, k_both)
        zero = np.zeros_like(e1)
        nodes = np.concatenate([len_nodes, np.concatenate([n[:m], n[m:]], 1)])
        grads = w * np.concatenate([np.stack([-e1, e1, e2, -e2, zero, zero], 1), np.concatenate([g[:m], -g[m:]], 1)])
        return w * np.concatenate([l1 - l2, wrap_angle(th[:m] - th[m:])]), (nodes, grads)

    return Family("regularizer", "reg", fn, 0, nv=nv)


def energy(fam: Family, x: np.ndarray) -> float:
    r = fam.residual(x)
    return float(r @ r)
