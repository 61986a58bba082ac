"""The polyline foot (issue #36: its nine candidate feet evaluated in one batch) against the nearest point of
every segment, found by brute force."""

from __future__ import annotations

import numpy as np
import pytest
import shapely
from fabkiri.design.targets.lookup import load_target


def _nearest_on_segments(pts: np.ndarray, p: np.ndarray) -> np.ndarray:
    # 64 points at a time: the heart's 2048 segments against all points at once are arrays of a
    # hundred MB, several times slower than the same arithmetic in blocks that stay in the cache
    a, b = pts, np.roll(pts, -1, 0)
    ab = b - a
    out = []
    for q in np.split(p, range(64, len(p), 64)):
        w = np.clip(((q[:, None] - a) * ab).sum(-1) / (ab * ab).sum(-1), 0.0, 1.0)
        out.append(np.linalg.norm(a + w[..., None] * ab - q[:, None], axis=-1).min(1))
    return np.concatenate(out)


@pytest.mark.parametrize("name", ["heart", "star", "hexagon"])
def test_polyline_foot_is_the_nearest_point_of_the_curve(name):
    tgt = load_target(name)
    rng = np.random.default_rng(5)
    # points near the curve (a tenth of its size off, either side), on it, and at its vertices
    u = rng.random(300)
    n = np.stack([tgt.tangent(u)[:, 1], -tgt.tangent(u)[:, 0]], -1)
    off = 0.1 * tgt.size * (rng.random(300) - 0.5)
    p = np.vstack([tgt.point(u) + off[:, None] * n, tgt.point(u), tgt.points])
    uf, foot, d, grad = tgt.project(p)
    best = _nearest_on_segments(tgt.points, p)
    assert np.abs(np.abs(d) - best).max() <= 1e-9 * tgt.size
    assert np.abs(np.linalg.norm(p - foot, axis=1) - best).max() <= 1e-9 * tgt.size
    assert (
        np.abs(tgt.point(uf) - foot).max() <= 1e-9 * tgt.size
    )  # the foot is the curve at its parameter
    # outside positive: the sign agrees with the curve's own inside test
    poly = shapely.Polygon(tgt.points)
    far = np.abs(d) > 1e-6 * tgt.size
    inside = shapely.contains_xy(poly, p[:, 0], p[:, 1])
    assert (np.sign(d[far]) == np.where(inside[far], -1.0, 1.0)).all()


def test_arc_feet_stay_on_their_arc():
    tgt = load_target("heart")
    rng = np.random.default_rng(6)
    p = tgt.sample(200) + rng.standard_normal((200, 2))
    side = rng.integers(0, 4, 200)
    u, _, _, _ = tgt.project(p, side)
    for s in range(4):
        lo, hi = tgt.arc_range(s)
        pad = 0.1 * (hi - lo)
        us = u[side == s]
        us = np.mod(us - (lo - pad), 1.0) + (lo - pad)  # into the arc's period
        assert ((us >= lo - pad - 1e-12) & (us <= hi + pad + 1e-12)).all()
