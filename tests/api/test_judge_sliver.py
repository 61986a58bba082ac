"""The design search judges a design with a tile squeezed to a sliver invalid, as an overlap
(``limits.sliver``): the 96x96 drop's Lawson steps squeezed the tile at its point to an edge under a micrometre,
which no file reader takes, so the finish keeps the last step without one and the guesses go on past it."""

from __future__ import annotations

import dataclasses
from collections import Counter

import numpy as np
from fabkiri.api.design import PatternRequest, _check
from fabkiri.design.core import conformance as conf
from fabkiri.design.core.request import DesignResult
from fabkiri.limits import MIN_LENGTH_MM
from fabkiri.pattern.kinds.quad.lattice import standard_pattern


def _judged(pattern):
    result = DesignResult(
        pattern, {"max_equality_residual": 0.0, "status": "converged", "time_s": 0.0}, True, {}, {}
    )
    return _check(
        result, {}, PatternRequest(tiles=(4, 4), size=100), None, conf.parse_shape_tol("2%")
    )


def _squeezed(edge_mm: float):
    """The 4x4 standard pattern (1 mm tiles) with a free corner of tile 0 (in no other tile, so both closed
    states still close) moved along its edge to within ``edge_mm`` of the next corner."""
    sp = standard_pattern(4, 4, tile_size=1.0)
    shared = Counter(int(n) for t in sp.tiles for n in t)
    t = [int(n) for n in sp.tiles[0]]
    a, b = next(
        (t[k], t[(k + 1) % 4]) for k in range(4) if shared[t[k]] == 1 < shared[t[(k + 1) % 4]]
    )
    nodes = np.array(sp.nodes, dtype=float)
    nodes[a] = nodes[b] + (nodes[a] - nodes[b]) * (edge_mm / np.linalg.norm(nodes[a] - nodes[b]))
    return dataclasses.replace(sp, nodes=nodes)


def test_a_design_with_a_sliver_is_invalid_and_says_which_tile():
    outcome = _judged(_squeezed(MIN_LENGTH_MM / 2))
    assert not outcome.valid
    assert outcome.problems == [
        f"tile 0 has an edge of {MIN_LENGTH_MM / 2:.3g} mm (at least {MIN_LENGTH_MM:g} mm)"
    ]
    assert outcome.report["status"] == "unconverged"


def test_a_short_edge_over_the_least_length_stays_valid():
    outcome = _judged(_squeezed(2 * MIN_LENGTH_MM))  # the squeeze alone: every other check passes
    assert outcome.valid and outcome.problems == []
