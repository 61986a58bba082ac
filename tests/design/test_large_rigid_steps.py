"""The reduced solver's steps on the block path (large lattices, docs/speed.md "Fifth wave"): the
regulariser's grid block kept through an LM run."""

from __future__ import annotations

import numpy as np
from fabkiri.design.quad.rigid import reduced as R
from fabkiri.design.quad.solve import DesignProblem, DesignRequest
from fabkiri.design.targets import lookup as T

from ..rigid_merit import rigid_merit


def _block_merit(monkeypatch):
    """A merit on the block path whose convexity rows are active (a margin no tile meets), and two members."""
    prob = DesignProblem(DesignRequest(10, 12, T.load_target("heart", 100.0), rigid=True))
    monkeypatch.setattr(R, "DENSE_JD", 0)
    prob.margin["convexity"] = 1.0
    merit = rigid_merit(prob)
    S, _ = prob.rigid_family.fit(prob.X0, np.pi / 4)
    rng = np.random.default_rng(1)
    p1, p2 = (np.concatenate([*(S + 0.03 * rng.normal(size=S.shape)).T, [0.7]]) for _ in range(2))
    return merit, p1, p2


def _reg_block(merit, p):
    """The regulariser rows' grid block at ``p``, formed from scratch."""
    r, Jx, Jc = merit.rows(merit.state(p))
    n = 2 * len(merit.grid_regs[0].meta["rows"].first)
    return merit._grid_normal(Jc[:n], r[Jx.shape[0] :][:n])[0]


def test_a_stage_keeps_the_regularisers_grid_block_of_its_first_point(monkeypatch):
    merit, p1, p2 = _block_merit(monkeypatch)
    stage = merit.staged(1e2, "marquardt")
    H1, g1 = stage.evaluate(p1).normal()
    E1, e1 = merit.evaluate(p1).normal()  # formed at every point
    assert np.allclose(H1, E1, rtol=0, atol=1e-12 * np.abs(E1).max())
    assert np.allclose(g1, e1, rtol=0, atol=1e-12 * np.abs(e1).max())
    H2, g2 = stage.evaluate(p2).normal()
    E2, e2 = merit.evaluate(p2).normal()
    # the gradient and every other row's block are the point's own; the regulariser's block is p1's
    assert np.allclose(g2, e2, rtol=0, atol=1e-12 * np.abs(e2).max())
    kept = _reg_block(merit, p1)
    moved = kept - _reg_block(merit, p2)
    assert np.abs(moved).max() > 1e-2 * np.abs(kept).max()  # the members' tile shapes differ
    assert np.allclose(H2 - E2, moved, rtol=0, atol=1e-12 * np.abs(E2).max())
    # the next stage (another LM run) forms its own
    assert merit.staged(1e4, "marquardt")._kept is not stage._kept


def test_the_active_convexity_rows_are_in_the_kept_normal_matrix(monkeypatch):
    merit, p1, _ = _block_merit(monkeypatch)
    r, Jx, Jc = merit.rows(merit.state(p1))
    n = 2 * len(merit.grid_regs[0].meta["rows"].first)
    assert Jc.shape[0] - n > 10  # the margin makes convexity rows active
    H, g = merit.staged(1e2, "marquardt")._kept.normal(merit)(Jc, r[Jx.shape[0] :])
    E, e = merit._grid_normal(Jc, r[Jx.shape[0] :])
    assert np.allclose(H, E, rtol=0, atol=1e-12 * np.abs(E).max())
    assert np.allclose(g, e, rtol=0, atol=1e-12 * np.abs(e).max())


def test_the_dense_path_keeps_no_block():
    prob = DesignProblem(DesignRequest(6, 6, T.load_target("circle", 100.0), rigid=True))
    assert rigid_merit(prob).staged(1e2, "marquardt")._kept is None
