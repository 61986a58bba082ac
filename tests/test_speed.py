"""Issue #18 (solver speed and start-up): the fast paths give the answers of the slow ones they replace
(timings live in bench/solve.py, not here)."""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st


@settings(max_examples=40, deadline=None)
@given(st.integers(2, 200), st.integers(0, 2 ** 32 - 1))
def test_closest_pair_equals_the_pairwise_minimum(n, seed):
    from fabkiri.fabricate.fabricability import closest_pair

    p = np.random.default_rng(seed).normal(size=(n, 2)) * 30.0
    dd = np.linalg.norm(p[:, None] - p[None], axis=-1)
    np.fill_diagonal(dd, np.inf)
    assert abs(closest_pair(p) - dd.min()) <= 1e-13 * dd.min()
