"""The solver core's assembly: stencil Jacobians on a fixed CSR pattern, rows without Jacobians."""

from __future__ import annotations

import numpy as np
from fabkiri.design.core.stencils import Family, StackedJacobian, StencilPattern, jac
from fabkiri.design.quad import constraints as C
from fabkiri.design.quad.objective import regularizer
from fabkiri.design.quad.solve import DesignRequest
from fabkiri.design.targets import lookup as T
from fabkiri.pattern import standard_pattern
from scipy import sparse

from ..rigid_merit import rigid_merit


def _coo(m, nv, nodes, grads):
    """The reference: every stencil entry summed by scipy's COO conversion."""
    k = nodes.shape[1]
    rows = np.repeat(np.arange(m), 2 * k)
    cols = (2 * nodes[:, :, None] + np.arange(2)).reshape(-1)
    return sparse.coo_matrix((grads.reshape(-1), (rows, cols)), shape=(m, 2 * nv)).toarray()


def test_stencil_jacobian_sums_repeated_nodes_like_the_coo_matrix():
    rng = np.random.default_rng(0)
    m, k, nv = 50, 5, 12
    nodes = rng.integers(0, nv, size=(m, k))  # repeats within a row are common
    grads = rng.normal(size=(m, k, 2))
    J = jac(m, nv, nodes, grads)
    assert J.has_canonical_format and J.shape == (m, 2 * nv)
    assert np.abs(J.toarray() - _coo(m, nv, nodes, grads)).max() <= 1e-14
    # one entry per distinct node coordinate of a row, sorted
    for i in range(m):
        cols = J.indices[J.indptr[i] : J.indptr[i + 1]]
        assert np.array_equal(cols, np.unique(2 * nodes[i, :, None] + np.arange(2)))


def test_a_family_with_no_rows_has_an_empty_jacobian():
    # a small cut kagome lattice can leave a row family empty (the 3x5 heart cut to 6 tiles at 60 mm)
    J = jac(0, 7, np.zeros((0, 3), dtype=int), np.zeros((0, 3, 2)))
    assert J.shape == (0, 14) and J.nnz == 0 and list(J.indptr) == [0]


def test_merged_entries_are_numpys_reduceat_sums_to_the_bit():
    # a repeated node's entries are summed by gathers (``stencils._Runs``), not by reduceat over every entry:
    # the same bits, signed zeros included, for runs of 2 to 7 entries; a run of 8 or more keeps reduceat
    rng = np.random.default_rng(2)
    for m, k, nv in ((400, 6, 40), (200, 4, 3), (60, 12, 2), (50, 3, 1000)):
        nodes = rng.integers(0, nv, size=(m, k))
        grads = rng.normal(size=(m, k, 2)) * 10.0 ** rng.integers(-8, 8, size=(m, k, 1))
        grads[rng.random((m, k, 2)) < 0.2] = 0.0
        grads[rng.random((m, k, 2)) < 0.1] = -0.0
        pat = StencilPattern(m, nv, nodes)
        ref = np.add.reduceat(grads.reshape(-1)[pat.order], pat.starts)
        got = pat.matrix(grads).data
        assert np.array_equal(got.view(np.int64), ref.view(np.int64))
    assert not StencilPattern(60, 2, rng.integers(0, 2, size=(60, 12)))._runs.short  # 12 entries


def _same_bits(a: sparse.csr_matrix, b: sparse.csr_matrix) -> bool:
    return (
        a.shape == b.shape
        and np.array_equal(a.data.view(np.int64), b.data.view(np.int64))
        and np.array_equal(a.indices, b.indices)
        and np.array_equal(a.indptr, b.indptr)
    )


def test_coordinate_columns_are_scipys_slices_and_transposes_to_the_bit():
    # the grid block's ``J[:, d::2]`` and their transposes straight from a stencil's gradients (``StackedJacobian``):
    # the same entries in the same order and the same bits as scipy's slicing and conversion of the stacked
    # CSR, with repeated nodes, signed zeros, an inequality block after the stencil, a run of 8 (the fallback)
    rng = np.random.default_rng(4)
    short = []
    for m, k, nv in ((400, 6, 40), (200, 4, 3), (60, 12, 2), (50, 3, 1000), (1, 1, 1)):
        nodes = rng.integers(0, nv, size=(m, k))
        grads = rng.normal(size=(m, k, 2)) * 10.0 ** rng.integers(-8, 8, size=(m, k, 1))
        grads[rng.random((m, k, 2)) < 0.2] = 0.0
        grads[rng.random((m, k, 2)) < 0.1] = -0.0
        fam = Family("rows", "reg", lambda x, n=nodes, g=grads: (np.zeros(len(n)), (n, g)), nv=nv)
        extra = 0.3 * jac(7, nv, rng.integers(0, nv, size=(7, 3)), rng.normal(size=(7, 3, 2)))
        w = float(rng.random())
        for after in ([], [extra]):
            _, block = fam.block(np.zeros((nv, 2)), w)
            got = StackedJacobian([block, *after], 2 * nv)
            J = sparse.vstack([w * jac(m, nv, nodes, grads), *after], format="csr")
            assert _same_bits(got.csr(), J)
            for Jd, Gd, Td in zip((J[:, 0::2], J[:, 1::2]), got.columns(), got.transposes()):
                assert _same_bits(Gd, Jd.tocsr()) and _same_bits(Td, Jd.T.tocsr())
        short.append(fam._columns[1].short)
    assert short == [True, True, False, True, True]  # 12 entries on two nodes: the fallback


def test_a_family_reuses_its_pattern_only_for_the_same_stencil():
    rng = np.random.default_rng(1)
    m, k, nv = 30, 4, 9
    fixed = rng.integers(0, nv, size=(m, k))
    g = {"grads": rng.normal(size=(m, k, 2)), "nodes": fixed}

    def fn(x):
        return np.zeros(m), (g["nodes"], g["grads"])

    fam = Family("rows", "reg", fn, nv=nv)
    fam(np.zeros((nv, 2)))
    pattern = fam._pattern
    g["grads"] = rng.normal(size=(m, k, 2))  # new values on the same stencil: the pattern is kept
    _, J = fam(np.zeros((nv, 2)))
    assert fam._pattern is pattern
    assert np.abs(J.toarray() - _coo(m, nv, fixed, g["grads"])).max() <= 1e-14
    g["nodes"] = rng.integers(0, nv, size=(m, k))  # another stencil: a new pattern
    _, J = fam(np.zeros((nv, 2)))
    assert fam._pattern is not pattern
    assert np.abs(J.toarray() - _coo(m, nv, g["nodes"], g["grads"])).max() <= 1e-14


def test_active_rows_jacobian_is_those_rows_of_the_full_one():
    std = standard_pattern(4, 5, tile_size=1.0)
    st = C.Stencils.from_pattern(std)
    X = std.nodes + 0.1 * np.random.default_rng(2).normal(size=std.nodes.shape)
    for f in (C.convexity(st, st.n_nodes), regularizer(st, st.n_nodes)):
        rows = np.array([0, 3, 7, 11])
        full = f(X)[1].toarray()
        assert np.array_equal(f.rows_jacobian(X, rows).toarray(), full[rows])
        assert np.array_equal(f.rows_jacobian(X, rows, len(f(X)[0])).toarray(), full[rows])
        # the residual-only path gives the rows of the Jacobian path
        assert np.array_equal(f.residual(X), f(X)[0])


def test_block_rows_come_without_jacobians_until_a_step_asks(monkeypatch):
    """A trial step of the block path (large lattices) reads only its rows; the Jacobians are assembled when
    its normal matrix is asked for, and the rows are those of the Jacobian path."""
    from fabkiri.design.quad.rigid import reduced as R
    from fabkiri.design.quad.solve import DesignProblem

    prob = DesignProblem(DesignRequest(6, 6, T.load_target("ellipse", 100.0), rigid=True))
    fam = prob.rigid_family
    monkeypatch.setattr(R, "DENSE_JD", 0)
    merit = rigid_merit(prob)
    assert merit._tiles is None
    S, _ = fam.fit(prob.X0, np.pi / 4)
    S = S + 0.2 * np.random.default_rng(3).normal(size=S.shape)  # some inequality rows active
    p = np.concatenate([S[:, 0], S[:, 1], [0.3]])
    calls = []
    call = Family.__call__
    monkeypatch.setattr(
        Family, "__call__", lambda self, x: calls.append(self.name) or call(self, x)
    )
    ev = merit.evaluate(p)
    r = ev.r
    assert calls == []
    H, g = ev.normal()
    assert calls
    r_full, Jx, Jc = merit.rows(merit.state(p))
    assert np.array_equal(r, r_full)
    assert len(r) > Jx.shape[0] and Jx.shape[0] + Jc.shape[0] == len(r)
    H2, g2 = merit.normal(r_full, Jx, Jc, p)
    assert np.array_equal(H, H2) and np.array_equal(g, g2)


def test_standard_rigid_family_is_built_once_per_lattice_and_equals_build():
    from fabkiri.design.quad.rigid.family import RigidFamily

    def stencils(rows, cols):
        std = standard_pattern(rows, cols, tile_size=1.0)
        return std, C.Stencils.from_pattern(std)

    std, st = stencils(4, 6)
    built = []

    def tree():
        built.append(1)
        return std.topology.spanning_tree(0)

    a = RigidFamily.of_standard(st, tree)
    assert RigidFamily.of_standard(st, tree) is a and built == [1]
    ref = RigidFamily.build(st, std.topology.spanning_tree(0))
    for name in ("node_vertex", "midpoint", "seeds", "Z", "Zn", "Y"):
        assert np.array_equal(getattr(a, name), getattr(ref, name)), name
    for rows, cols in ((3, 3), (5, 4)):  # two other lattices: the first one is dropped
        s2, st2 = stencils(rows, cols)
        RigidFamily.of_standard(st2, lambda s2=s2: s2.topology.spanning_tree(0))
    assert RigidFamily.of_standard(st, tree) is not a and built == [1, 1]


def test_pattern_rows_are_written_one_encode_per_row_as_before():
    from fabkiri.exchange import pattern_json as io

    def per_row(arr, indent):
        rows = arr.tolist()
        if not rows:
            return "[]"
        inner = f",\n{indent}  ".join(io._ROW.encode(r) for r in rows)
        return f"[\n{indent}  {inner}\n{indent}]"

    rng = np.random.default_rng(5)
    cases = [
        rng.normal(size=(7, 2)) * 1e3,
        rng.integers(0, 99, size=(5, 4)),
        rng.normal(size=(3, 4, 2)),
        np.array([[np.nan, -0.0], [np.inf, 1e-300]]),
        np.zeros((0, 2)),
        np.zeros((3, 0)),
        np.zeros((2, 0, 2)),
    ]
    for arr in cases:
        for indent in ("  ", "    "):
            assert io._rows(arr, indent) == per_row(arr, indent), arr.shape


def test_dense_rows_come_only_when_asked_and_a_violating_trial_needs_none(monkeypatch):
    """The dense path (small lattices) judges a trial step by its inequality values alone: its fit rows (the
    target projections) are formed when ``r`` is first asked for, once, and are the rows of a fresh
    evaluation; its normal matrix is the one formed from them."""
    from fabkiri.design.quad.solve import DesignProblem

    prob = DesignProblem(DesignRequest(6, 6, T.load_target("ellipse", 100.0), rigid=True))
    fam = prob.rigid_family
    merit = rigid_merit(prob)
    assert merit._tiles is not None
    S, _ = fam.fit(prob.X0, np.pi / 4)
    p = np.concatenate([S[:, 0], S[:, 1], [0.3]])
    fits = []
    for f in merit.fits:
        monkeypatch.setattr(f, "fn", lambda x, fn=f.fn, n=f.name: fits.append(n) or fn(x))
    ev = merit.evaluate(p)
    assert fits == [] and ev.gviol >= 0.0
    r = ev.r
    assert len(fits) == len(merit.fits)
    assert ev.r is r and len(fits) == len(merit.fits)  # once
    again = merit.evaluate(p)
    H, g = ev.normal()
    H2, g2 = again.normal()
    assert np.array_equal(r, again.r) and np.array_equal(H, H2) and np.array_equal(g, g2)
