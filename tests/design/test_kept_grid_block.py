"""The regulariser's grid block kept through a stage (``merit.KeptGridBlock``, ``steps.stage``): the lattices
above ``routes.KEEP_BLOCK_TILES`` tiles only, forced onto a small lattice here."""

from __future__ import annotations

from dataclasses import replace
from types import SimpleNamespace

import numpy as np
import pytest
from fabkiri.design.quad import routes
from fabkiri.design.quad.rigid import merit as M
from fabkiri.design.quad.rigid import reduced as R
from fabkiri.design.quad.rigid import steps
from fabkiri.design.quad.solve import DesignProblem, DesignRequest, design
from fabkiri.design.targets import lookup as T

from ..rigid_merit import rigid_merit


def _block_merit(monkeypatch):
    """A 10x12 heart's merit on the block path (no dense ∂c/∂p, block normal matrix) and a member off its
    start with some convexity rows active."""
    prob = DesignProblem(DesignRequest(10, 12, T.load_target("heart", 100.0), rigid=True))
    monkeypatch.setattr(R, "DENSE_JD", 0)
    judge = rigid_merit(prob)
    assert judge._tiles is None and judge._C is None
    S, _ = prob.rigid_family.fit(prob.X0, np.pi / 4)
    S = S + 1.0 * np.random.default_rng(0).normal(size=S.shape)
    return judge, np.concatenate([S[:, 0], S[:, 1], [np.pi / 4]])


def _keeping(judge, keep: bool = True, tag: str = ""):
    how = R.ReducedSearch(1e-3, 1e-6, lambda X: 1.0, lambda s: None, keep_block=keep)
    return steps.stage(judge, 1e4, "marquardt", how, tag)


def test_transposed_product_is_the_stacked_csr_transpose_times_r(monkeypatch):
    judge, p = _block_merit(monkeypatch)
    r, Jx, Jc = judge.rows(judge.state(p))
    rc = r[Jx.shape[0] :]
    # active convexity rows (a CSR block) after the stencil
    assert len(Jc.blocks) > len(judge.grid_regs)
    want = (Jc.csr().T @ rc).reshape(-1, 2)
    got = M._transposed_product(Jc, rc)
    assert np.abs(got - want).max() <= 1e-13 * np.abs(want).max()


def test_the_regularisers_transposed_product_is_its_jacobians(monkeypatch):
    judge, p = _block_merit(monkeypatch)
    reg, c = judge.grid_regs[0], judge.state(p)[1]
    r, J = reg(c)
    y = np.random.default_rng(2).normal(size=len(r))
    want = (J.T @ y).reshape(-1, 2)
    lean, transposed = reg.meta["lean"](c)
    assert np.array_equal(lean, r)
    got = transposed(y)
    assert np.abs(got - want).max() <= 1e-13 * np.abs(want).max()
    # and against finite differences of the residuals along a direction: yᵀ J v
    v, h = np.random.default_rng(3).normal(size=c.shape), 1e-6
    fd = y @ (reg.residual(c + h * v) - reg.residual(c - h * v)) / (2 * h)
    assert abs(fd - float((got * v).sum())) <= 1e-6 * abs(fd)


def test_a_stage_keeps_the_regularisers_block_of_its_first_point_and_nothing_else(monkeypatch):
    judge, p = _block_merit(monkeypatch)
    every, kept = judge.staged(1e4, "marquardt"), _keeping(judge)
    assert every._kept is None and kept._kept is not None
    H0, g0 = every.evaluate(p).normal()
    K0, k0 = kept.evaluate(p).normal()
    assert np.abs(K0 - H0).max() <= 1e-12 * np.abs(H0).max()
    assert np.abs(k0 - g0).max() <= 1e-12 * np.abs(g0).max()
    # a second point: the gradient and the active rows' block are its own, the regulariser's block the first's
    rng = np.random.default_rng(1)
    q = p + 0.1 * rng.normal(size=p.shape) * np.r_[np.ones(len(p) - 1), 0.0]
    H1, g1 = every.evaluate(q).normal()
    K1, k1 = kept.evaluate(q).normal()
    # the block formed, a later point's regulariser rows come without their stencil
    assert isinstance(kept.rows(kept.state(q))[2].blocks[0], M.TransposedBlock)
    assert np.abs(k1 - g1).max() <= 1e-12 * np.abs(g1).max()
    n = len(judge.grid_regs)

    def reg_block(x):
        r, Jx, Jc = judge.rows(judge.state(x))
        reg = type(Jc)(Jc.blocks[:n], Jc.shape[1])
        return judge._grid_normal(reg, r[Jx.shape[0] : Jx.shape[0] + reg.shape[0]])[0]

    change = reg_block(p) - reg_block(q)
    assert np.abs(change).max() > 1e-6 * np.abs(H1).max()  # the kept block is not the point's own
    assert np.abs(K1 - (H1 + change)).max() <= 1e-10 * np.abs(H1).max()


def test_only_a_search_that_asks_keeps_a_block(monkeypatch):
    judge, _ = _block_merit(monkeypatch)
    assert _keeping(judge, keep=False)._kept is None
    assert _keeping(judge, tag="contact_")._kept is None  # a contact rerun forms it every step
    monkeypatch.setattr(R, "DENSE_JD", 4e6)
    small = rigid_merit(
        DesignProblem(DesignRequest(6, 6, T.load_target("circle", 100.0), rigid=True))
    )
    assert _keeping(small)._kept is None  # the dense path has no grid block to keep


def _asking(prob_req, level):
    return SimpleNamespace(req=prob_req, coarse=level)


TIPS = {"used": True, "fit": "tips", "hausdorff_rel": 0.002}


@pytest.mark.parametrize(
    "tiles,level,kept",
    [
        (97, TIPS, True),
        (96, TIPS, False),  # issue #37's table keeps forming it
        (97, None, False),  # no coarse level: a rescaled start, a warm-started finish step
        (97, {**TIPS, "used": False}, False),
        (97, {**TIPS, "fit": "outline"}, False),
        (97, {**TIPS, "rescaled_bottom": 32}, False),  # the finish follows whatever the miss
        (97, {**TIPS, "hausdorff_rel": 0.0026}, False),  # past the finish's floor (the star's 8 %)
    ],
)
def test_only_a_large_chain_from_a_close_tips_level_keeps_the_block(tiles, level, kept):
    req = DesignRequest(tiles, tiles, T.load_target("circle", 100.0), rigid=True)
    assert routes.keeps_block(_asking(req, level)) is kept
    # a coarse level of such a chain is judged by the chain's top
    sub = replace(req, rows=tiles // 2, cols=tiles // 2, chain_tiles=tiles * tiles)
    assert routes.keeps_block(_asking(sub, level)) is kept


def test_a_lattice_above_the_limit_keeps_it_where_its_level_fits(monkeypatch):
    asked: list[tuple[int, bool]] = []
    solve = routes.solve_reduced

    def spy(fam, st, X0, psi0, families, margin, how, **kw):
        asked.append((len(X0), how.keep_block))
        return solve(fam, st, X0, psi0, families, margin, how, **kw)

    monkeypatch.setattr(routes, "solve_reduced", spy)
    monkeypatch.setattr(routes, "KEEP_BLOCK_TILES", 8 * 8)
    monkeypatch.setattr(routes, "FINISH_FLOOR", 1.0)
    design(DesignRequest(10, 10, T.load_target("circle", 100.0), rigid=True, init="coarse"))
    # the 10x10 lattice from its 5x5 level keeps it; the 5x5 level, started from rescaled, does not
    assert sorted(set(asked)) == [(60, False), (220, True)]  # their nodes
