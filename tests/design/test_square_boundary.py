"""The inverse map's boundary on the unit square (``design/quad/inverse_map.square_boundary``): every boundary
node placed, a corner's node too where the curve's parameter wraps (an L-shaped outline's default split put one
on neither arc by round-off; its unset point reached the map's KD-tree as NaN, an internal error)."""

from pathlib import Path

import numpy as np
from fabkiri.design.quad.corner_split import _stencils
from fabkiri.design.quad.inverse_map import (
    SQUARE_CORNERS,
    TargetMesh,
    square_boundary,
    with_corners,
)
from fabkiri.design.targets.lookup import load_target

DATA = Path(__file__).resolve().parents[1] / "data"


def _boundary(name: str, rows: int, cols: int):
    target = load_target(str(DATA / name), 100)
    mesh = TargetMesh(target)
    tgt = with_corners(target, target.default_corner_split())
    base, st = _stencils(rows, cols)
    q = (base - base.min(0)) / (base.max(0) - base.min(0))
    return tgt, mesh, square_boundary(tgt, mesh.u, q[st.tip_nodes], st.tip_side)


def test_a_node_on_the_wrapping_corner_is_that_corner_of_the_square():
    tgt, mesh, (fixed, tip_u) = _boundary("ell2.csv", 11, 23)
    assert np.isfinite(fixed).all() and np.isfinite(tip_u).all()
    starts = np.array([tgt.arc_range(s)[0] for s in range(4)])
    on_arc = np.zeros(len(mesh.u), bool)
    for s in range(4):
        a, b = tgt.arc_range(s)
        uu = np.mod(mesh.u - a, 1.0) + a
        on_arc |= (uu >= a) & (uu < b)
    off = np.flatnonzero(~on_arc)
    assert len(off) == 1  # the case this test is for: round-off leaves it off both arcs
    k = np.abs(np.mod(mesh.u[off[0]] - starts + 0.5, 1.0) - 0.5).argmin()
    assert np.array_equal(fixed[off[0]], SQUARE_CORNERS[k])


def test_the_map_of_that_outline_is_finite():
    target = load_target(str(DATA / "ell2.csv"), 100)
    base, st = _stencils(11, 23)
    out = TargetMesh(target).place(base, st.tip_nodes, st.tip_side, target.default_corner_split())
    assert np.isfinite(out).all()
