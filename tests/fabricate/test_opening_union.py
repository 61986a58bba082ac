"""The closed states' outline area of the opening figures: a coverage union of snapped quads where the
tiles meet edge to edge (the fast path), the general GEOS union elsewhere."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import shapely
from fabkiri.exchange.pattern_json import read_pattern
from fabkiri.pattern import opening as op

DATA = Path(__file__).parents[1] / "data"


def _general(c: np.ndarray) -> float:
    """The area by the general union on the 1e-7 grid (what every closed state took before)."""
    pts = c.reshape(-1, 2)
    grid = 1e-7 * float((pts.max(0) - pts.min(0)).max())
    u = shapely.union_all(shapely.make_valid(shapely.polygons(c)), grid_size=grid)
    pieces = [u] if u.geom_type == "Polygon" else list(u.geoms)
    return float(sum(shapely.Polygon(g.exterior).area for g in pieces))


def _no_general_union(monkeypatch) -> None:
    def refuse(*a, **k):
        raise AssertionError("the general union was taken")

    monkeypatch.setattr(op.shapely, "union_all", refuse)


@pytest.mark.parametrize("name", ["circle-16x16-rigid.json", "heart-8x8.json"])
def test_closed_quads_take_the_coverage_union_and_give_the_general_unions_area(name, monkeypatch):
    p = read_pattern(DATA / name)
    closed = {s: np.asarray(c, float) for s, c in p.contracted.items()}
    want = {s: _general(c) for s, c in closed.items()}
    _no_general_union(monkeypatch)
    for s, c in closed.items():
        assert op._closed_area(c) == pytest.approx(want[s], rel=1e-14, abs=0)


def test_the_standard_closed_square_is_its_area_exactly(monkeypatch):
    # corners on integers: snapped like GEOS's integral scale, the outline is the 4 x 4 square exactly
    i, j = np.meshgrid(np.arange(4.0), np.arange(4.0))
    base = np.stack([i.ravel(), j.ravel()], -1)[:, None, :]
    quads = base + np.array([[0, 0], [1, 0], [1, 1], [0, 1]], float)
    _no_general_union(monkeypatch)
    assert op._closed_area(quads) == 16.0


def test_overlapping_or_gapped_quads_keep_the_general_union():
    overlapping = np.array(
        [[[0, 0], [2, 0], [2, 2], [0, 2]], [[1, 1], [3, 1], [3, 3], [1, 3]]], float
    )
    assert op._coverage_area(overlapping, 1e-7) is None
    assert op._closed_area(overlapping) == _general(overlapping) == pytest.approx(7.0, rel=1e-6)
    # a ring of four quads round a hole: a coverage; the hole is inside the outline
    ring = np.array(
        [
            [[0, 0], [3, 0], [3, 1], [0, 1]],
            [[2, 1], [3, 1], [3, 3], [2, 3]],
            [[0, 2], [2, 2], [2, 3], [0, 3]],
            [[0, 1], [1, 1], [1, 2], [0, 2]],
        ],
        float,
    )
    assert op._closed_area(ring) == pytest.approx(9.0, rel=1e-12)
    assert op._closed_area(ring) == pytest.approx(_general(ring), rel=1e-14)


def test_triangles_keep_the_general_union(monkeypatch):
    p = read_pattern(DATA / "kagome-heart-6x11.json")
    from fabkiri.fabricate.print.geometry import closed_corners

    c = np.asarray(closed_corners(p, 1), float)
    assert op._coverage_area(c, 1e-7 * float(np.ptp(c.reshape(-1, 2), 0).max())) is None
    assert op._closed_area(c) == _general(c)


def _cell_edge(x: float, grid: float) -> float:
    """Where GEOS's ``grid`` rounding of x-coordinates near ``x`` turns from one cell to the next."""

    def snapped(v: float) -> float:
        return shapely.get_x(shapely.set_precision(shapely.Point(v, 0.0), grid))

    lo, hi = x - 0.25 * grid, x + 0.25 * grid
    assert snapped(lo) != snapped(hi)
    for _ in range(60):
        m = 0.5 * (lo + hi)
        lo, hi = (m, hi) if snapped(m) == snapped(lo) else (lo, m)
    return 0.5 * (lo + hi)


def test_a_shared_corner_split_by_a_grid_cell_edge_takes_the_coverage_half_a_cell_on(monkeypatch):
    # a 2 x 2 block whose centre corner sits on the edge of a 1e-7-of-the-extent cell, one of its four copies
    # round-off apart on the other side: snapped, that tile's edges do not match its neighbours', so no
    # coverage; half a cell further on they round together (the 128x128 rigid circle's closed state 1 had one)
    grid = 1e-7 * 2.0
    mid = _cell_edge(1.0 + 0.5 * grid, grid)
    quads = np.array(
        [
            [[0, 0], [mid, 0], [mid - 1e-13, 1], [0, 1]],
            [[mid, 0], [2, 0], [2, 1], [mid + 1e-13, 1]],
            [[0, 1], [mid - 1e-13, 1], [mid, 2], [0, 2]],
            [[mid - 1e-13, 1], [2, 1], [2, 2], [mid, 2]],
        ],
        float,
    )
    snapped = shapely.set_precision(shapely.polygons(quads), grid, mode="pointwise")
    assert not shapely.coverage_is_valid(snapped)
    want = _general(quads)
    _no_general_union(monkeypatch)
    assert op._closed_area(quads) == pytest.approx(want, rel=1e-12)
    assert want == pytest.approx(4.0, rel=1e-12)
