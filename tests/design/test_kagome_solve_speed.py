"""The kagome solver's assembly shortcuts give the matrices the general scipy operations gave."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
from fabkiri.design.kagome import fit as KF
from fabkiri.design.kagome import solve as KS
from fabkiri.design.targets import lookup as TG
from fabkiri.pattern.kinds.kagome.lattice import standard_kagome
from scipy import sparse


def _rows():
    std = standard_kagome(4, 5, tile_size=12.0)
    rows, x0, _ = KF.fit_rows(std, TG.circle().scaled_to(60.0), pairs=True)
    return rows, x0 + 0.2 * np.random.default_rng(3).standard_normal(x0.shape)


def _same(A, B) -> bool:
    return (
        A.shape == B.shape
        and A.indptr.tolist() == B.indptr.tolist()
        and A.indices.tolist() == B.indices.tolist()
        and np.array_equal(A.data, B.data)
    )


def test_row_scaling_and_the_kkt_matrix_are_scipys_entry_for_entry():
    rows, x = _rows()
    w_rng = np.random.default_rng(4)
    for f in rows.eq + rows.fit + rows.ineq:
        r, J = f(x)
        assert np.array_equal(r, f.residual(x)), f.name
        w = w_rng.random(r.shape) * (w_rng.random(r.shape) > 0.3)
        assert _same(KS.row_scaled(J, w), sparse.diags(w) @ J), f.name
    s, S = rows.soft(x)
    _, A = rows.equalities(x)
    H = (S.T @ S).tocsc() + sparse.identity(S.shape[1])
    want = sparse.bmat([[H, A.T], [A, -KS.KKT_REG * sparse.identity(A.shape[0])]], format="csc")
    assert _same(KS.kkt_matrix(H, A), want)


def test_the_landing_operator_multiplies_as_its_matrix():
    rows, x = _rows()
    _, J = rows.equalities(x)
    op = KS.Jacobian(J)
    v, u = np.arange(J.shape[1], dtype=float), np.arange(J.shape[0], dtype=float)
    assert np.array_equal(op.matvec(v), J @ v) and np.array_equal(op.rmatvec(u), J.T @ u)
    X = np.stack([v, -v], 1)
    assert np.array_equal(op.matmat(X), J @ X)
    # the compiled kernels' products (random floats, so the order of the sums shows), and scipy's own
    # path for a column or an integer vector
    rng = np.random.default_rng(5)
    v, u = rng.standard_normal(J.shape[1]), rng.standard_normal(J.shape[0])
    assert np.array_equal(op.matvec(v), J @ v) and np.array_equal(op.rmatvec(u), J.T @ u)
    assert np.array_equal(op.matvec(v[:, None]), (J @ v)[:, None])
    n = np.arange(J.shape[1])
    assert np.array_equal(op.matvec(n), J @ n)


def test_a_family_is_evaluated_once_per_point_and_gives_the_same_rows():
    std = standard_kagome(4, 5, tile_size=12.0)
    rows, x0, _ = KF.fit_rows(std, TG.circle().scaled_to(60.0))
    calls = []
    f = rows.fit[0]
    counted = KS.reusing_structure(
        replace(f, fn=lambda x: (calls.append(1), f.fn(x))[1], _pattern=None)
    )
    r1, J1 = counted(x0)
    r2 = counted.residual(x0.copy())  # the same point, another array: no new evaluation
    r2[:] = np.nan  # a caller writing into its rows leaves the kept ones alone
    r3, J3 = counted(x0)
    assert len(calls) == 1 and np.array_equal(r1, r3) and _same(J1, J3)
    counted(x0 + 1e-9)
    assert len(calls) == 2
    assert np.array_equal(counted(x0)[0], f(x0)[0]) and len(calls) == 3


def test_a_scipy_whose_kernels_differ_gets_the_public_product(monkeypatch):
    """The compiled kernels are scipy's private module: this SciPy's pass the probe; one whose kernel takes
    other arguments (or gives another product) is not used, and the operator multiplies through scipy."""
    from scipy.sparse import _sparsetools

    assert KS.compiled_matvec() is not None  # the fast path is the one the suite runs
    with (
        monkeypatch.context() as m
    ):  # scipy's own product calls these too: patched for the probe only
        m.setattr(_sparsetools, "csc_matvec", lambda *a: None)  # writes nothing: a wrong product
        assert KS.compiled_matvec() is None
        m.setattr(_sparsetools, "csr_matvec", lambda n: None)  # another signature: TypeError
        assert KS.compiled_matvec() is None
    monkeypatch.setattr(KS, "_MATVEC", None)
    rows, x = _rows()
    _, J = rows.equalities(x)
    op = KS.Jacobian(J)
    v = np.random.default_rng(6).standard_normal(J.shape[1])
    assert op._kernels == [None, None] and np.array_equal(op.matvec(v), J @ v)
