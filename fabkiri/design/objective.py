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
from .constraints import Family, Stencils, corner_angle, jac, regularizer_pairs


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

    def fn(x):
        m = 4 * P
        # edge k: corner k -> k+1
        a1, b1 = tl[tT, kk], tl[tT, (kk + 1) % 4]
        a2, b2 = tl[tU, kk], tl[tU, (kk + 1) % 4]
        E1, E2 = x[b1] - x[a1], x[b2] - x[a2]
        l1, l2 = np.linalg.norm(E1, axis=1), np.linalg.norm(E2, axis=1)
        e1, e2 = E1 / l1[:, None], E2 / l2[:, None]
        rl = w * (l1 - l2)
        Jl = jac(m, nv, np.stack([a1, b1, a2, b2], -1), w * np.stack([-e1, e1, e2, -e2], 1))
        th1, n1, g1 = corner_angle(x, tl, tT, kk)
        th2, n2, g2 = corner_angle(x, tl, tU, kk)
        ra = w * wrap_angle(th1 - th2)
        Ja = jac(m, nv, np.concatenate([n1, n2], 1), w * np.concatenate([g1, -g2], 1))
        from scipy import sparse

        return np.concatenate([rl, ra]), sparse.vstack([Jl, Ja]).tocsr()

    return Family("regularizer", "reg", fn, 0)


def energy(fam: Family, x: np.ndarray) -> float:
    r, _ = fam(x)
    return float(r @ r)
