"""The rigid family's dense node bases ``Zn`` and ``Y`` are made on first use, and the rows of a few nodes
without them: the same numbers, bit for bit, as the whole arrays built eagerly (#36)."""

from __future__ import annotations

import numpy as np
import pytest
from fabkiri.design.quad import constraints as C
from fabkiri.design.quad.rigid.contact import ClosedContact
from fabkiri.design.quad.rigid.family import RigidFamily
from fabkiri.design.quad.rigid.mirror import centred
from fabkiri.pattern import standard_pattern


def _built(rows, cols):
    std = standard_pattern(rows, cols, tile_size=1.0)
    st = C.Stencils.from_pattern(std)
    return RigidFamily.build(st, std.topology.spanning_tree(0)), st, std


def _eager(fam):
    """``Zn`` and ``Y`` as ``build`` made them before (whole, at once)."""
    tau, use_t, sigma = fam.parts
    Zn = fam.Z[fam.node_vertex]
    return Zn, np.ascontiguousarray(tau[use_t] - sigma * Zn)


@pytest.mark.parametrize("rows,cols", [(3, 4), (8, 8), (13, 9)])
def test_rows_and_the_whole_bases_are_the_eager_ones(rows, cols):
    rng = np.random.default_rng(rows * cols)
    fam, _, _ = _built(rows, cols)
    Zn, Y = _eager(fam)
    V = len(fam.node_vertex)
    nodes = [rng.choice(V, 7, replace=False), rng.integers(0, V, (5, 3)), np.arange(V)]
    for n in nodes:
        zr, yr = fam.rows(n)
        assert np.array_equal(zr, Zn[n]) and np.array_equal(yr, Y[n])
    assert fam._zn is None and fam._y is None  # the rows made neither
    assert np.array_equal(fam.Y, Y) and fam.Y.flags.c_contiguous
    assert fam._zn is None  # Y alone did not keep Zn
    assert np.array_equal(fam.Zn, Zn)
    for n in nodes:  # and the same once both are made
        zr, yr = fam.rows(n)
        assert np.array_equal(zr, Zn[n]) and np.array_equal(yr, Y[n])
    moved = centred(fam)
    assert np.array_equal(moved.Y, Y - Y.mean(0)) and np.array_equal(
        moved.rows(nodes[0])[1], moved.Y[nodes[0]]
    )


@pytest.mark.parametrize("zn_first", [False, True])
def test_y_by_blocks_of_nodes_is_the_whole_formula_to_the_bit(monkeypatch, zn_first):
    # ``Y`` subtracts σ Zn block by block (no second (V, nf) array): blocks of 5 nodes, with and without ``Zn``
    # made first, give the eager formula's bits
    from fabkiri.design.quad.rigid import family

    monkeypatch.setattr(family, "Y_BLOCK", 5)
    fam, _, _ = _built(8, 6)
    _, Y = _eager(fam)
    if zn_first:
        assert fam.Zn.shape == Y.shape  # made and kept before Y
    assert np.array_equal(fam.Y.view(np.int64), Y.view(np.int64))


def test_a_jacobian_at_a_few_nodes_makes_no_whole_basis():
    fam, st, std = _built(10, 12)
    S = np.random.default_rng(3).normal(size=(fam.n_seeds, 2))
    nodes = np.array([0, 5, 17, 40])
    D = fam.jacobian_at(S, 0.6, nodes)
    assert fam._zn is None and fam._y is None
    assert np.array_equal(D, fam.jacobian_at(S, 0.6)[nodes])  # the whole one makes both
    assert fam._zn is not None and fam._y is not None


def test_the_contact_rows_read_the_bases_rows():
    fam, st, std = _built(8, 12)
    cc = ClosedContact(fam, st)
    S, _ = RigidFamily.fit(_built(8, 12)[0], std.nodes, np.pi / 4)
    xs = cc.configs(S)
    fresh, _, _ = _built(8, 12)
    lazy = ClosedContact(fresh, st)
    r, J = cc.active(xs, 1e6, 1.0)  # every row active
    r2, J2 = lazy.active(xs, 1e6, 1.0)
    assert len(r) and np.array_equal(r, r2) and np.array_equal(J, J2)
    assert fresh._y is None


def test_the_fit_is_the_block_matrix_least_squares():
    """``fit`` fills its matrix in place: the seeds are those of ``lstsq`` over the ``np.block`` matrix, bit for bit."""
    fam, st, std = _built(9, 7)
    X = std.nodes + np.random.default_rng(5).normal(scale=0.01, size=std.nodes.shape)
    psi = 0.7
    c, s = np.cos(psi), np.sin(psi)
    K = np.block([[c * fam.Zn, -s * fam.Y], [s * fam.Y, c * fam.Zn]])
    sol = np.linalg.lstsq(K, np.concatenate([X[:, 0], X[:, 1]]), rcond=None)[0]
    S, gap = fam.fit(X, psi)
    assert np.array_equal(S, np.stack([sol[: fam.n_seeds], sol[fam.n_seeds :]], -1)) and gap > 0
