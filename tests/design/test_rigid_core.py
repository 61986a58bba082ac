"""The rigid family's grid basis through its sparse factor ``Z = E Z[core]`` (design/quad/rigid/core.py) and the
grid block of the reduced normal matrix formed through it (``reduced._Merit._grid_normal``)."""

from __future__ import annotations

import numpy as np
import pytest
from fabkiri.design.quad import constraints as C
from fabkiri.design.quad.rigid import reduced as R
from fabkiri.design.quad.rigid.core import GridCore, grid_core
from fabkiri.design.quad.rigid.family import RigidFamily
from fabkiri.design.quad.solve import DesignProblem, DesignRequest
from fabkiri.design.targets import lookup as T
from fabkiri.pattern import standard_pattern

from ..rigid_merit import rigid_merit


def _family(rows, cols):
    std = standard_pattern(rows, cols, tile_size=1.0)
    st = C.Stencils.from_pattern(std)
    return RigidFamily.build(st, std.topology.spanning_tree(0))


@pytest.mark.parametrize("rows,cols", [(2, 2), (2, 5), (5, 7), (8, 6), (16, 16), (24, 19)])
def test_the_core_factors_the_grid_basis(rows, cols):
    fam = _family(rows, cols)
    core = grid_core(fam.midpoint, fam.Z)
    G = fam.Z.shape[0]
    assert np.abs(core.E @ core.Zc - fam.Z).max() <= 1e-12
    assert np.array_equal(core.Zc, fam.Z[core.core]) and np.array_equal(core.ZcT, core.Zc.T)
    assert np.isin(fam.seeds, core.core).all()  # the seeds are kept: nothing can eliminate them
    # a kept vertex is itself; every row is an average (a translation of the grid stays one)
    assert np.array_equal(core.E[core.core].toarray(), np.eye(len(core.core)))
    assert np.allclose(np.asarray(core.E.sum(1)).ravel(), 1.0, rtol=0, atol=1e-14)
    assert (core.ET != core.E.T).nnz == 0
    if min(rows, cols) >= 8:  # the point of it: the dense products run over a fraction of the grid
        assert len(core.core) <= 0.45 * G
        assert core.E.nnz <= 4 * G


def test_the_family_makes_its_core_once():
    fam = _family(6, 6)
    assert fam.core is fam.core
    assert np.abs(fam.core.E @ fam.core.Zc - fam.Z).max() <= 1e-12


@pytest.fixture
def block_merit(monkeypatch):
    """A 8x8 rigid merit on the block path (the grid block formed by coordinate blocks, not through a dense
    ``C``) at a member with some inequality rows active."""
    monkeypatch.setattr(R, "DENSE_JD", 0)
    prob = DesignProblem(DesignRequest(8, 8, T.load_target("ellipse", 100.0), rigid=True))
    fam = prob.rigid_family
    merit = rigid_merit(prob)
    assert merit._tiles is None and merit._C is None
    S, _ = fam.fit(prob.X0, np.pi / 4)
    S = S + 0.2 * np.random.default_rng(3).normal(size=S.shape)
    p = np.concatenate([S[:, 0], S[:, 1], [0.3]])
    return merit, p


def _grid_rows(merit, p):
    r, Jx, Jc = merit.rows(merit.state(p))
    return r[Jx.shape[0] :], Jc


def test_grid_block_through_the_core_is_the_dense_product(block_merit, monkeypatch):
    """``Cᵀ JcᵀJc C`` and ``Cᵀ Jcᵀ rc`` through the core equal the products through the dense ``C`` (the
    old assembly) to 1e-12, and the block path does go through the core."""
    merit, p = block_merit
    rc, Jc = _grid_rows(merit, p)
    Z, nf = merit.fam.Z, merit.nf
    C_dense = np.zeros((Z.shape[0], 2, 2 * nf + 1))
    C_dense[:, 0, :nf] = Z
    C_dense[:, 1, nf : 2 * nf] = Z
    JC = Jc @ C_dense.reshape(-1, 2 * nf + 1)
    H_ref, g_ref = JC.T @ JC, JC.T @ rc
    used = []
    quadratic = GridCore.quadratic
    monkeypatch.setattr(GridCore, "quadratic", lambda self, K: used.append(1) or quadratic(self, K))
    H, g = merit._grid_normal(Jc, rc)
    assert len(used) == 3  # xx, yy, xy
    assert np.abs(H - H_ref).max() <= 1e-12 * np.abs(H_ref).max()
    assert np.abs(g - g_ref).max() <= 1e-12 * np.abs(g_ref).max()


def test_grid_block_gradient_matches_finite_differences(block_merit):
    """``Cᵀ Jcᵀ rc`` is the gradient of ½‖rc(p)‖² (central differences), the Jacobian's rows through the
    core; the active inequality rows are held fixed by staying near ``p``."""
    merit, p = block_merit
    rc, Jc = _grid_rows(merit, p)
    _, g = merit._grid_normal(Jc, rc)

    def half_sq(q):
        r, _ = _grid_rows(merit, q)
        return 0.5 * float(r @ r) if len(r) == len(rc) else np.nan

    h = 1e-6
    rng = np.random.default_rng(5)
    for k in rng.choice(len(p) - 1, 12, replace=False):
        e = np.zeros(len(p))
        e[k] = h
        fd = (half_sq(p + e) - half_sq(p - e)) / (2 * h)
        assert abs(fd - g[k]) <= 1e-5 * np.abs(g).max(), k
    assert g[-1] == 0.0  # the grid rows do not see ψ


@pytest.mark.slow
def test_large_lattice_maps_go_through_the_core_and_the_tiles():
    """Above ``LARGE_GRID`` vertices ``grid`` is ``E (Z[core] S)`` and ``nodes`` takes ``Y S`` per tile: the
    maps ``Z S`` and ``x(S, ψ)`` of the basis to round-off; a family with another ``Y`` (the mirror's
    centred gauge) uses its own ``Y``."""
    from fabkiri.design.quad.rigid import family as rigid
    from fabkiri.design.quad.rigid.mirror import centred

    fam = _family(64, 64)
    assert len(fam.Z) > rigid.LARGE_GRID
    S = np.random.default_rng(7).normal(size=(fam.n_seeds, 2)) * 10.0
    psi = 0.4

    def reference(f):
        a, b = (f.Z @ S)[f.node_vertex], f.Y @ S
        c, s = np.cos(psi), np.sin(psi)
        return np.stack([c * a[:, 0] - s * b[:, 1], c * a[:, 1] + s * b[:, 0]], -1)

    scale = np.abs(fam.Z @ S).max()
    assert fam._core is None
    assert np.abs(fam.grid(S) - fam.Z @ S).max() <= 1e-13 * scale
    assert fam._core is not None  # the grid went through the core
    assert np.abs(fam.nodes(S, psi) - reference(fam)).max() <= 1e-13 * scale
    moved = centred(fam)
    assert moved.given_Y is not None  # its nodes take Y S, not the parts' τ S
    assert np.abs(moved.nodes(S, psi) - reference(moved)).max() <= 1e-13 * scale
    small = _family(8, 8)  # small lattices keep the plain products, bit for bit
    S8 = S[: small.n_seeds]
    assert np.array_equal(small.grid(S8), small.Z @ S8) and small._core is None
