"""The kagome fit's solver: Levenberg-Marquardt on the soft rows, moving along the family.

The iterate stays on the family (every equality at rounding). Each step solves the soft rows'
least-squares problem linearised at ``x`` in the family's tangent space,

    min ‖S d + s‖² + λ ‖D d‖²   subject to   A d = 0,

``s, S`` the soft rows (fit, violated inequalities) and ``A`` the equalities' Jacobian (closure in both
states, symmetry), through the sparse KKT system; then the point ``x + d`` is pulled back onto the family
by minimum-norm Newton steps (the same KKT matrix with the identity for ``SᵀS``). A step is accepted when
the soft cost ``½‖s‖²`` falls and the pull-back converged; λ grows on a rejection, shrinks on an
acceptance. Staying on the family avoids a merit function: an exact penalty on the equalities rejects
the good steps whose only fault is the second-order growth of the equalities (the Maratos effect, which
stalled a first version at |c| ~ 1e-4).

``A`` is rank deficient (one dependent edge pair per hole, more on wide lattices); a tiny negative (2,2)
block keeps the KKT matrix regular, and a right-hand side in the range of ``A`` (it is, near the family)
is met all the same.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
from scipy import sparse
from scipy.optimize import least_squares
from scipy.sparse.linalg import LinearOperator, splu

from ..core.stencils import Family
from .constraints import stacked


def compiled_matvec() -> dict | None:
    """The compiled kernels behind scipy's sparse matrix-vector product (``Jacobian``, below), by format,
    when they take the arguments ``_product`` gives them and give a small product right; None otherwise
    (a private module: another SciPy may move or change them, and the public product is used)."""
    try:
        from scipy.sparse import _sparsetools

        kernels = {"csr": _sparsetools.csr_matvec, "csc": _sparsetools.csc_matvec}
        probe = sparse.csr_matrix(np.array([[1.0, 2.0], [0.0, 3.0]]))
        for fmt, kernel in kernels.items():
            m, out = probe.asformat(fmt), np.zeros(2)
            kernel(2, 2, m.indptr, m.indices, m.data, np.array([1.0, 1.0]), out)
            if not np.array_equal(out, [3.0, 3.0]):
                return None
    except (ImportError, AttributeError, TypeError, ValueError):
        return None
    return kernels


_MATVEC = compiled_matvec()

KKT_REG = 1e-12  # the (2,2) block: regularises the dependent equality rows
ON_FAMILY = 1e-12  # the pull-back's tolerance on max |equality|
LAMBDA0 = 1e-3
LAND_WEIGHT = 30.0  # the equalities' weight while landing on the family
LAND_INEQ_WEIGHT = 10.0  # and the inequalities' (heavier ones hold the equalities off: 6x10 heart)
LAND_NFEV = 100
# the steps along the family stop when their last 10 accepted ones lowered the soft cost by < 0.1 %
LM_STALL = (10, 1e-3)
# a warm landing (a Lawson step's) stops when its last 40 evaluations lowered the penalty cost by < 0.01 %
# (shorter or looser windows cost the 6x10 heart's convex-hole claim: docs/kagome.md)
LAND_STALL = (40, 1e-4)
LAMBDA_MIN, LAMBDA_MAX = 1e-9, 1e8


@dataclass(frozen=True)
class Rows:
    """The rows of one fit: equalities, soft rows (with their per-family weights) and inequalities."""

    eq: list[Family]
    fit: list[Family]
    ineq: list[Family]
    weights: dict  # family name -> per-row weights (or a scalar)
    ineq_weight: float

    def soft(self, x: np.ndarray, jac: bool = True):
        """Weighted soft rows (fit, then inequalities) and their Jacobian."""
        rs, Js = [], []
        for f in self.fit + self.ineq:
            w = self.weights.get(f.name, 1.0) if f.kind == "fit" else self.ineq_weight
            if jac:
                r, J = f(x)
                Js.append(row_scaled(J, np.broadcast_to(w, r.shape).astype(float)))
            else:
                r = f.residual(x)
            rs.append(w * r)
        r = np.concatenate(rs)
        return (r, sparse.vstack(Js).tocsr()) if jac else r

    def equalities(self, x: np.ndarray):
        return stacked(self.eq, x)

    def equality_residuals(self, x: np.ndarray) -> np.ndarray:
        """The equalities' residuals alone (the same values as :meth:`equalities`, no Jacobian)."""
        return residuals(self.eq, x)


def reusing_structure(f: Family) -> Family:
    """``f`` giving the last call's stencil node array again whenever its nodes are the same: ``Family``
    keeps its Jacobian's sparsity by that array's identity, and a family that builds the array anew on
    every call (most do) would otherwise sort the same structure on every call. The last call's result is
    kept too and given again for the same ``x`` (bit for bit): the solver asks a family's residuals and
    then, at the same point, its Jacobian (the landing's function then its Jacobian, a step's cost then
    the accepted point's rows, the pull-back's test then its step), and the residual of a family without
    its own ``res`` is the whole evaluation."""
    last: list[np.ndarray] = []
    memo: list = []  # [x's bytes, r, J] of the last call

    def fn(x):
        key = (x.shape, x.tobytes())
        if memo and memo[0] == key:
            return memo[1].copy(), memo[2]
        r, J = f.fn(x)
        if isinstance(J, tuple):
            if last and last[0].shape == J[0].shape and np.array_equal(last[0], J[0]):
                J = (last[0], J[1])
            else:
                last[:] = [J[0]]
        memo[:] = [key, r, J]
        return r.copy(), J

    return replace(f, fn=fn, _pattern=None)


def residuals(fams: list[Family], x: np.ndarray) -> np.ndarray:
    """The residuals of ``fams`` at ``x``, as :func:`stacked` gives them, without their Jacobian."""
    return np.concatenate([f.residual(x) for f in fams])


def row_scaled(J: sparse.spmatrix, w: np.ndarray) -> sparse.csr_matrix:
    """``diags(w) @ J`` as scipy's sparse product gives it, entry for entry and in its order (the order
    the landing's matrix-vector products sum in), without the general product: the entries scaled,
    zeros dropped and each row's entries last first."""
    if not (sparse.isspmatrix_csr(J) and J.has_canonical_format):
        return sparse.diags(w) @ J
    counts = np.diff(J.indptr)
    v = np.repeat(w, counts) * J.data
    keep = v != 0
    row = np.repeat(np.arange(J.shape[0]), counts)[keep][::-1]
    order = np.argsort(row, kind="stable")
    indptr = np.concatenate([[0], np.cumsum(np.bincount(row, minlength=J.shape[0]))])
    return sparse.csr_matrix(
        (v[keep][::-1][order], J.indices[keep][::-1][order], indptr.astype(J.indptr.dtype)),
        shape=J.shape,
    )


@dataclass(frozen=True)
class Solve:
    x: np.ndarray
    iterations: int
    soft_cost: float  # ½‖s‖² at the end
    max_equality: float
    on_family: bool  # the start was pulled onto the family (else x is the start)


def solve(
    rows: Rows, x0: np.ndarray, max_iter: int = 60, tol: float = 1e-9, warm: bool = False
) -> Solve:
    """Levenberg-Marquardt along the family from ``x0`` (n, 2), landed and pulled onto it first; stops when
    a step lowers the soft cost by less than ``tol`` relative, when the last accepted steps have stalled
    (``LM_STALL``), or after ``max_iter`` steps.

    Every start is landed, a warm one (a Lawson step) too: measured on the 6x11 heart, pulling a warm start
    back directly left the Lawson steps at 10.4 -> 9.8 %, landing it again reached 7.4 % (the penalty
    solve moves the design further than the steps along the family, which stop in a nearer minimum).
    ``warm``: the start is a Lawson step's, whose landing stops when stalled (``LAND_STALL``)."""
    stall = LAND_STALL if warm else None
    x, ok, _ = pull_back(rows.eq, land(rows, np.asarray(x0, float), stall=stall), max_iter=40)
    if not ok:
        c = rows.equality_residuals(x)
        return Solve(np.asarray(x0, float), 0, np.inf, float(np.abs(c).max()), False)
    lam = LAMBDA0
    s, S = rows.soft(x)
    cost = 0.5 * s @ s
    it, costs = 0, [cost]
    A, normal = None, _normal(S, s)  # both change only with x: a rejected step keeps them
    while it < max_iter:
        it += 1
        if A is None:
            _, A = rows.equalities(x)
        d = _step(normal[0], normal[1], normal[2], A, lam).reshape(x.shape)
        xn, ok, _ = pull_back(rows.eq, x + d)
        sn = rows.soft(xn, jac=False) if ok else np.full(1, np.inf)
        cn = float(0.5 * sn @ sn)
        if np.isfinite(cn) and cn < cost:
            done = cost - cn <= tol * max(cost, 1e-300)
            x, cost = xn, cn
            s, S = rows.soft(x)
            A, normal = None, _normal(S, s)
            lam = max(lam / 3.0, LAMBDA_MIN)
            costs.append(cost)
            if done or stalled(costs, *LM_STALL):
                break
        else:
            lam *= 4.0
            if lam > LAMBDA_MAX:
                break
    c = rows.equality_residuals(x)
    return Solve(x, it, float(cost), float(np.abs(c).max(initial=0.0)), True)


class Jacobian(LinearOperator):
    """A sparse Jacobian as an operator with its own products, ``J @ x`` and ``Jᵀ @ x``: the same products
    the least-squares solver forms from the matrix itself, through fewer of scipy's operator layers
    (its inner LSMR takes a few hundred of them per step). A vector product goes straight to the compiled
    kernel scipy's own product calls (``csr_matvec`` for ``J``, ``csc_matvec`` for ``Jᵀ``, into zeros), so
    the sums are the same to the bit; anything but a float vector of the right length takes scipy's
    general path."""

    def __init__(self, J: sparse.csr_matrix):
        self.J, self.JT = J, J.T
        super().__init__(J.dtype, J.shape)
        self._kernels = [_kernel(M) for M in (self.J, self.JT)]

    def matvec(self, x):
        k = self._kernels[0]
        return _product(k, x) if k and _vector(k, x) else super().matvec(x)

    def rmatvec(self, x):
        k = self._kernels[1]
        return _product(k, x) if k and _vector(k, x) else super().rmatvec(x)

    def _matvec(self, x):
        return self.J @ x

    def _rmatvec(self, x):
        return self.JT @ x

    def _matmat(self, X):
        return self.J @ X

    def _rmatmat(self, X):
        return self.JT @ X


def _kernel(M) -> tuple | None:
    """``(kernel, rows, cols, indptr, indices, data)`` of scipy's compiled product for a float CSR or CSC
    matrix (None: another matrix, or no such kernel in this SciPy)."""
    if _MATVEC is None or M.format not in _MATVEC or M.dtype != np.float64:
        return None
    return (_MATVEC[M.format], M.shape[0], M.shape[1], M.indptr, M.indices, M.data)


def _vector(k: tuple, x) -> bool:
    """Whether ``x`` is a float vector of the kernel's matrix width."""
    return x.__class__ is np.ndarray and x.shape == (k[2],) and x.dtype == np.float64


def _product(k: tuple, x: np.ndarray) -> np.ndarray:
    """``M @ x`` as scipy's ``_matmul_vector`` forms it: zeros, then the format's compiled kernel."""
    kernel, m, n, indptr, indices, data = k
    out = np.zeros(m)
    kernel(m, n, indptr, indices, data, x, out)
    return out


class _Stalled(Exception):
    """Raised from the landing's function when its evaluations have stalled (``LAND_STALL``)."""


def land(
    rows: Rows, x0: np.ndarray, max_nfev: int = LAND_NFEV, stall: tuple[int, float] | None = None
) -> np.ndarray:
    """A point near the family from a start far from it: penalty least squares (the equalities weighted
    by ``LAND_WEIGHT`` beside the soft rows; scipy's trust-region reflective method), for the pull-back to
    finish. The pull-back alone diverges from the initial guess of a heart (|c| ~ 1 there). ``stall``
    (window, rel): stop once the last ``window`` evaluations lowered the lowest cost by < ``rel`` of it and
    return the lowest point evaluated (the trust region's iterate)."""
    rows = replace(
        rows,
        ineq_weight=min(rows.ineq_weight, LAND_INEQ_WEIGHT),
        ineq=[f for f in rows.ineq if f.meta.get("land", True)],
    )

    best: list = [np.inf, x0.ravel()]
    lows: list[float] = []

    def fun(v):
        x = v.reshape(x0.shape)
        f = np.concatenate([LAND_WEIGHT * rows.equality_residuals(x), rows.soft(x, jac=False)])
        if stall is not None:
            c = 0.5 * float(f @ f)
            if c < best[0]:
                best[0], best[1] = c, v.copy()
            lows.append(best[0])
            if stalled(lows, *stall):
                raise _Stalled
        return f

    def jac(v):
        x = v.reshape(x0.shape)
        return Jacobian(
            sparse.vstack([LAND_WEIGHT * rows.equalities(x)[1], rows.soft(x)[1]]).tocsr()
        )

    try:
        sol = least_squares(
            fun,
            x0.ravel(),
            jac=jac,
            method="trf",
            tr_solver="lsmr",
            max_nfev=max_nfev,
            xtol=1e-12,
            ftol=1e-12,
            gtol=1e-12,
        )
    except _Stalled:
        return best[1].reshape(x0.shape)
    return sol.x.reshape(x0.shape)


def stalled(costs: list[float], window: int, rel: float) -> bool:
    """Whether the last ``window`` entries of ``costs`` (the cost after each accepted step) lowered it by
    less than ``rel`` of it: the solve has stalled."""
    return len(costs) > window and costs[-1] > (1.0 - rel) * costs[-1 - window]


def _kkt(H: sparse.spmatrix, A: sparse.spmatrix):
    return splu(kkt_matrix(H, A))


def kkt_matrix(H: sparse.spmatrix, A: sparse.spmatrix) -> sparse.csc_matrix:
    """``[[H, Aᵀ], [A, -KKT_REG I]]`` in canonical CSC, entry for entry as ``sparse.bmat`` builds it (the
    factorisation sees the same matrix), assembled from the columns directly: column ``j < N`` is ``H``'s
    column then ``A``'s, column ``N + i`` is ``A``'s row ``i`` then the regularisation."""
    H, Ac, Ar = H.tocsc(), A.tocsc(), A.tocsr()
    for M in (H, Ac, Ar):
        M.sum_duplicates()
    N, m = H.shape[0], A.shape[0]
    hc, ac, ar = np.diff(H.indptr), np.diff(Ac.indptr), np.diff(Ar.indptr)
    counts = np.concatenate([hc + ac, ar + 1])
    indptr = np.concatenate([[0], np.cumsum(counts)])
    # each entry's place: its column's start, then its rank among the column's entries
    h_at = np.repeat(indptr[:N], hc) + np.arange(H.nnz) - np.repeat(H.indptr[:-1], hc)
    a_at = np.repeat(indptr[:N] + hc, ac) + np.arange(Ac.nnz) - np.repeat(Ac.indptr[:-1], ac)
    t_at = np.repeat(indptr[N:-1], ar) + np.arange(Ar.nnz) - np.repeat(Ar.indptr[:-1], ar)
    d_at = indptr[N + 1 :] - 1
    data = np.empty(indptr[-1])
    rows = np.empty(indptr[-1], dtype=np.int32)
    for at, v, r in (
        (h_at, H.data, H.indices),
        (a_at, Ac.data, Ac.indices + N),
        (t_at, Ar.data, Ar.indices),
        (d_at, np.full(m, -KKT_REG), np.arange(N, N + m)),
    ):
        data[at], rows[at] = v, r
    K = sparse.csc_matrix((data, rows, indptr.astype(np.int32)), shape=(N + m, N + m))
    K.has_sorted_indices = True
    return K


def _normal(S: sparse.csr_matrix, s: np.ndarray):
    """``(SᵀS, -Sᵀs, diag(SᵀS))``: the soft rows' normal equations at the iterate."""
    H = (S.T @ S).tocsc()
    return H, -(S.T @ s), H.diagonal()


def _step(H: sparse.csc_matrix, g: np.ndarray, dg: np.ndarray, A: sparse.csr_matrix, lam: float):
    """The tangent step of the linearised problem (Marquardt's scaling: λ times diag(SᵀS), floored)."""
    D = sparse.diags(lam * np.maximum(dg, 1e-6 * max(dg.max(initial=0.0), 1.0)))
    rhs = np.concatenate([g, np.zeros(A.shape[0])])
    return _kkt(H + D, A).solve(rhs)[: H.shape[0]]


def pull_back(eq: list[Family], x: np.ndarray, tol: float = ON_FAMILY, max_iter: int = 8):
    """Minimum-norm Newton steps onto the equalities (sparse KKT): ``(x, converged, steps)``. When they do
    not converge, ``x`` is the point of smallest residual they reached (the start included): far from the
    family a full Newton step can raise the residual by orders (8x8 heart: 0.25 -> 3e11 in ten steps),
    and the last point of such a run is no design."""
    N = x.size
    nearest, least = x, np.inf
    for k in range(max_iter + 1):
        r = residuals(eq, x)  # the Jacobian only for a step
        worst = np.abs(r).max(initial=0.0)
        if worst <= tol:
            return x, True, min(k, max_iter)
        if not np.isfinite(r).all():
            break
        if worst < least:
            nearest, least = x, worst
        if k == max_iter:
            break
        r, J = stacked(eq, x)
        dx = _kkt(sparse.identity(N, format="csc"), J).solve(np.concatenate([np.zeros(N), -r]))[:N]
        x = x + dx.reshape(x.shape)
    return nearest, False, max_iter


def project(eq: list[Family], x: np.ndarray, tol: float = 1e-13, max_iter: int = 30):
    """Minimum-norm Newton steps onto the equalities to rounding: ``(x, converged, steps)``; the
    pull-back's steps with a tighter tolerance. (Dense least-squares steps took as many tries at the
    rounding floor, ~1e-13 on a 12x21 lattice, and each cost a dense SVD.)"""
    return pull_back(eq, x, tol, max_iter)
