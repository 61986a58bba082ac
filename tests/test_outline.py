"""Closed-state outlines in the rigid family (design/outline.py): exact square, size-free circle."""

from __future__ import annotations

import numpy as np
import pytest

from fabkiri.design import outline
from fabkiri.design import targets as T
from fabkiri.design.constraints import ClosedGrid, Stencils
from fabkiri.design.solve import DesignRequest, design
from fabkiri.pattern.io import read_pattern


def _ring(M: int, N: int) -> np.ndarray:
    idx = np.arange((M + 1) * (N + 1)).reshape(M + 1, N + 1)
    return np.concatenate([idx[0, :-1], idx[:-1, -1], idx[-1, :0:-1], idx[:0:-1, 0]])


def _outline(pattern, state: int) -> np.ndarray:
    """Boundary vertices of a closed state, from the contracted tiles the CLI wrote (CCW)."""
    st = Stencils.from_pattern(pattern)
    g = ClosedGrid.build(st, state, 0)
    pos = np.zeros((g.n_vertices, 2))
    cnt = np.zeros(g.n_vertices)
    np.add.at(pos, g.vertex.ravel(), np.asarray(pattern.contracted[state]).reshape(-1, 2))
    np.add.at(cnt, g.vertex.ravel(), 1.0)
    return (pos / cnt[:, None])[_ring(st.rows, st.cols)]


def _lsq_circle(p: np.ndarray):
    """Geometric least-squares circle (Gauss-Newton from the algebraic one): centre, radius, rms."""
    sol = np.linalg.lstsq(np.c_[2 * p, np.ones(len(p))], (p * p).sum(1), rcond=None)[0]
    c = sol[:2]
    for _ in range(100):
        d = np.linalg.norm(p - c, axis=1)
        J = -(p - c) / d[:, None]
        step = np.linalg.lstsq(J - J.mean(0), -(d - d.mean()), rcond=None)[0]
        c = c + step
        if np.abs(step).max() < 1e-14 * d.mean():
            break
    d = np.linalg.norm(p - c, axis=1)
    return c, d.mean(), float(np.sqrt(np.mean((d - d.mean()) ** 2)))


@pytest.mark.parametrize("n", [5, 7])
def test_square_to_circle_exact_square_and_least_squares_circle(run_cli, tmp_path, n):
    out = tmp_path / "p.json"
    code, _, err = run_cli("design", "--tiles", f"{n}x{n}", "--rigid", "--contracted-target", "1:square",
                           "--contracted-target", "2:circle", "-o", out)
    assert code == 0, err
    pat = read_pattern(out)
    rep = pat.design["report"]
    assert rep["solver"].startswith("closed-form rigid family, closed-state outlines")
    assert rep["max_equality_residual"] <= 1e-10
    assert all(rep["checks"][k] == 0 for k in ("overlaps_deployed", "overlaps_state_1", "overlaps_state_2"))
    # state 1: a square of the target's side (100 mm), to rounding
    p1 = _outline(pat, 1)
    corners = p1[[0, n, 2 * n, 3 * n]]
    side = 100.0
    assert np.abs(np.linalg.norm(np.roll(corners, -1, 0) - corners, axis=1) - side).max() <= 1e-9 * side
    worst = 0.0  # every boundary vertex on the line through its side's two corners (the file's frame is rotated)
    for k in range(4):
        a, b = corners[k], corners[(k + 1) % 4]
        t = (b - a) / np.linalg.norm(b - a)
        q = p1[np.arange(k * n, (k + 1) * n + 1) % (4 * n)] - a
        worst = max(worst, float(np.abs(q[:, 0] * t[1] - q[:, 1] * t[0]).max()))
    assert worst <= 1e-9 * side
    # state 2: the stored circle target is the least-squares circle of the outline (size-free), up to the
    # rigid motion between the solver's grid and the contracted tiles
    p2 = _outline(pat, 2)
    c, R, rms = _lsq_circle(p2)
    fit = rep["closed_outline_fit"]["2"]
    assert fit["rms_mm"] == pytest.approx(rms, rel=1e-6)
    assert 0.5 * pat.design["contracted_targets"]["2"]["size_mm"] == pytest.approx(R, rel=1e-6)
    assert abs(R - 50.0) > 1e-3  # not the 100 mm circle it was given: the size is free


def test_applies_only_to_square_and_circle_rigid_outlines():
    sq, ci, he = T.load_target("square"), T.load_target("circle"), T.load_target("heart")
    assert outline.applies(DesignRequest(5, 5, None, rigid=True, contracted={1: sq, 2: ci}))
    assert not outline.applies(DesignRequest(5, 5, None, rigid=False, contracted={1: sq, 2: ci}))
    assert not outline.applies(DesignRequest(5, 5, None, rigid=True, contracted={1: sq, 2: he}))
    assert not outline.applies(DesignRequest(5, 5, ci, rigid=True, contracted={1: sq}))


def test_inconsistent_squares_fall_back_to_the_full_solver():
    sq = T.load_target("square")
    res = design(DesignRequest(4, 4, None, rigid=True, contracted={1: sq, 2: sq}))
    assert res.report["solver"].startswith("sparse")
    assert res.converged
