"""The least tile-edge rows (``constraints.least_edges``): a needle tile violates them, a sane one leaves them
inactive, and the solver's problem carries them in tile units (their Jacobian is checked in test_design.py), in a
minimax finish's steps only."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from fabkiri import limits
from fabkiri.design.quad import constraints as C
from fabkiri.design.quad.problem import LEAST_EDGE_FLOORS, LEAST_EDGE_SHARE
from fabkiri.design.quad.solve import DesignProblem, DesignRequest
from fabkiri.design.targets import lookup as T
from fabkiri.exchange.pattern_json import read_pattern
from fabkiri.pattern import standard_pattern

DATA = Path(__file__).resolve().parents[1] / "data"


def test_a_needle_tile_violates_only_its_short_edges_row():
    std = standard_pattern(4, 4, tile_size=1.0)
    st = C.Stencils.from_pattern(std)
    fam = C.least_edges(st, len(std.nodes), 0.01)
    X = std.nodes.copy()
    assert fam.residual(X).min() > fam.meta["margin"]  # unit squares: far above the floor
    t = 5
    a, b = st.tiles[t, 0], st.tiles[t, 1]
    # corner 1 of tile t moved onto corner 0 but for 0.1 % of the edge: edge 0 collapses, the others stay
    X[b] = X[a] + 1e-3 * (X[b] - X[a])
    g = fam.residual(X)
    assert g[4 * t] == pytest.approx(0.1**2 - 1.0)  # 0.001 against a floor of 0.01
    assert (np.delete(g, 4 * t) > 0).all()
    # every unit edge scaled to just above and just below the floor
    assert (fam.residual(0.0105 * std.nodes) > 0).all()
    assert fam.residual(0.0095 * std.nodes).max() < 0


@pytest.mark.parametrize("name", ["heart-16x16-rigid.json", "star-16x16-nonrigid.json"])
def test_the_rows_are_inactive_on_sane_designs(name):
    """Designs with no sliver are left alone: every row above its margin at the floor in mm."""
    pat = read_pattern(DATA / name)
    st = C.Stencils.from_pattern(pat)
    fam = C.least_edges(st, len(pat.nodes), LEAST_EDGE_FLOORS * limits.MIN_LENGTH_MM)
    assert fam.residual(np.asarray(pat.nodes, float)).min() > fam.meta["margin"]


@pytest.mark.parametrize("size", [1.0, 100.0])
def test_the_floor_is_in_mm_on_tiles_of_a_sane_size(size):
    prob = DesignProblem(
        DesignRequest(
            rows=4, cols=4, target=T.circle().transformed(size), rigid=True, least_edge=True
        )
    )
    fam = next(f for f in prob.families if f.name == "least_edges")
    assert fam.kind == "ineq" and prob.margin["least_edges"] == fam.meta["margin"]
    assert fam.meta["floor"] * prob.L0 == pytest.approx(LEAST_EDGE_FLOORS * limits.MIN_LENGTH_MM)


def test_on_tiny_tiles_the_floor_is_a_share_of_the_tile_unit():
    prob = DesignProblem(
        DesignRequest(
            rows=4, cols=4, target=T.circle().transformed(0.01), rigid=True, least_edge=True
        )
    )
    fam = next(f for f in prob.families if f.name == "least_edges")
    assert prob.L0 < LEAST_EDGE_FLOORS * limits.MIN_LENGTH_MM / LEAST_EDGE_SHARE
    assert fam.meta["floor"] == LEAST_EDGE_SHARE


def test_the_rows_are_in_the_minimax_finish_steps_only(monkeypatch):
    """Always on, the rows moved cells whose designs never come near the floor (the solvers' trial steps pass
    edges through zero on the way): a design's problem has none, a finish step's has them."""
    from fabkiri.api import design_minimax as dm

    req = DesignRequest(rows=4, cols=4, target=T.circle().transformed(100.0), rigid=True)
    assert not any(f.name == "least_edges" for f in DesignProblem(req).families)
    asked: list = []

    def refine(step, start, **kw):
        asked.append(step.least_edge)
        return None, [], 0.0

    monkeypatch.setattr(dm, "refine_minimax", refine)
    start = type("A", (), {"pattern": type("P", (), {"nodes": None})()})()
    dm._steps(req, start, lambda r: r)
    assert asked == [True] and not req.least_edge
