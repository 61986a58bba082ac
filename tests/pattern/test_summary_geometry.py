"""The fabricability summary's shared and vectorised geometry equals the plain way, bit for bit (#36):
the tile scales of many widths and shrinks from one set of frames, the pads clipped only by the band
edges that cut them, the strip faces from one graph search, the hinge pairs made unique as integers."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from fabkiri.exchange.pattern_json import read_pattern
from fabkiri.pattern import geometry, thinness
from fabkiri.pattern.geometry import cross2, dot2

DATA = Path(__file__).parents[1] / "data"


def _plain_min_scale(corners, width, shrink, min_edge):
    """min_scale with every term computed for the one ask (the summary's way before the shared frames)."""
    E = np.roll(corners, -1, axis=-2) - corners
    L = np.linalg.norm(E, axis=-1)
    u = E / np.where(L > 0, L, 1.0)[..., None]
    n = np.stack([-u[..., 1], u[..., 0]], -1)
    a = dot2(corners[..., None, :, :] - corners[..., :, None, :], n[..., :, None, :])
    na = np.roll(n, 1, axis=-2)
    m = (na + n) / (1.0 + dot2(na, n))[..., None]
    b = (
        shrink * (1.0 - dot2(n[..., :, None, :], m[..., None, :, :]))
        if shrink
        else np.zeros_like(a)
    )
    with np.errstate(divide="ignore", invalid="ignore"):
        s_width = np.where(a > 0, (width + b) / a, np.inf).min(-1).max(-1)
        loss = -shrink * dot2(u, np.roll(m, -1, axis=-2) - m)
        s_edges = np.where(L > 0, (loss + max(min_edge, thinness.EDGE_EPS_MM)) / L, np.inf).max(-1)
    s = np.maximum(s_width, s_edges) if shrink else s_width
    t = int(np.argmax(s))
    return float(s[t]), t, "width" if s_width[t] >= (s_edges[t] if shrink else 0.0) else "edge"


def test_tile_scales_of_many_asks_are_each_asks_own():
    c = read_pattern(DATA / "heart-16x16-rigid.json").contracted[1]
    shared = thinness.TileScales(c)
    asks = [(0.5, 0.0, 0.0), (0.5, 0.25, 0.5), (0.5, 0.25, 9.0), (1e-6, 0.2, 1e-6), (0.5, 0.0, 0.0)]
    got = [shared(*ask) for ask in asks]
    assert got == [_plain_min_scale(c, *ask) for ask in asks]
    assert {g[2] for g in got} == {"width", "edge"}  # both limits met (a large shrink loses edges)
    assert thinness.TileScales(np.zeros((0, 4, 2)))(1.0) == (0.0, -1, "")


def _plain_clipped_areas(subject, clip):
    """Every polygon clipped by every clip edge (the pads' way before the edges that cut them only)."""
    orient = np.sign(geometry.signed_areas(clip))[:, None]
    P, live, k = np.asarray(subject, float), np.ones(len(subject), bool), clip.shape[1]
    for j in range(k):
        c, d = clip[:, j], clip[:, (j + 1) % k]
        f = orient * cross2((d - c)[:, None], P - c[:, None])
        fq = np.roll(f, -1, 1)
        crosses = (f >= 0) != (fq >= 0)
        cut = P + (np.roll(P, -1, 1) - P) * (f / np.where(crosses, f - fq, 1.0))[..., None]
        pts = np.stack([P, cut], 2).reshape(len(P), -1, 2)
        keep = np.stack([f >= 0, crosses], 2).reshape(len(P), -1)
        count = keep.sum(1)
        live &= count > 0
        order = np.argsort(~keep, axis=1, kind="stable")[:, : max(int(count.max(initial=0)), 1)]
        last = np.maximum(count - 1, 0)[:, None]
        order = np.take_along_axis(order, np.minimum(np.arange(order.shape[1]), last), 1)
        P = np.take_along_axis(pts, order[..., None], 1)
    return np.where(live, 0.5 * np.abs(cross2(P, np.roll(P, -1, 1)).sum(1)), 0.0)


def test_pads_clipped_only_where_cut_are_the_plain_clipping_bit_for_bit():
    rng = np.random.default_rng(7)
    ang = (
        rng.uniform(0, 2 * np.pi, (600, 1))
        + np.arange(4) * np.pi / 2
        + rng.uniform(-0.6, 0.6, (600, 4))
    )
    clip = np.stack([np.cos(ang), np.sin(ang)], -1) * rng.uniform(
        0.5, 2, (600, 1, 1)
    )  # round the origin
    clip[::2] = clip[::2, ::-1]  # either orientation
    subject = rng.normal(
        0, 1.0, (600, 4, 2)
    )  # some inside, some cut into 5-8 corners, some bow-ties
    subject[:100] *= 0.05  # inside every edge: left as they are while the others are clipped
    subject[100:150] += 10.0  # outside: no area
    assert geometry.strictly_convex(clip).all()
    plain = _plain_clipped_areas(subject, clip)
    got = geometry.clipped_areas(subject, clip)
    assert np.array_equal(got.view(np.int64), plain.view(np.int64))
    assert (plain[:100] > 0).all() and (plain[100:150] == 0).all()


def _plain_faces(pairs, n):
    """The strip faces by a breadth-first search in Python, neighbours in order (the way before)."""
    face, nbr = np.full(n, -1), [[] for _ in range(n)]
    for i, j in pairs.tolist():
        nbr[i].append(j)
        nbr[j].append(i)
    for root in range(n):
        if face[root] < 0:
            face[root], queue = 0, [root]
            for h in queue:
                for g in sorted(nbr[h]):
                    if face[g] < 0:
                        face[g] = 1 - face[h]
                        queue.append(g)
    return face


@pytest.mark.parametrize("seed", range(6))
def test_strip_faces_are_the_breadth_first_ones(seed):
    """Several groups, isolated hinges, odd cycles (three hinges at a point) and pairs in any order."""
    rng = np.random.default_rng(seed)
    n = int(rng.integers(5, 80))
    pairs = rng.integers(0, n, (int(rng.integers(1, 2 * n)), 2))
    pairs = pairs[pairs[:, 0] != pairs[:, 1]]
    pairs = np.concatenate([pairs, [[n - 1, n - 2], [n - 2, n - 3], [n - 3, n - 1]]])  # a triangle
    assert np.array_equal(thinness.strip_faces(pairs, n), _plain_faces(pairs, n))
    assert np.array_equal(thinness.strip_faces(np.zeros((0, 2)), 4), np.zeros(4))


def test_strip_faces_put_the_lowest_of_a_chain_on_top():
    """A chain given from its middle: faces alternate from the lowest hinge, not the first pair's."""
    assert thinness.strip_faces(np.array([[3, 4], [2, 3], [4, 5]]), 7).tolist() == [
        0,
        0,
        0,
        1,
        0,
        1,
        0,
    ]


def test_unique_pairs_are_numpys_unique_rows():
    rng = np.random.default_rng(3)
    pairs = rng.integers(0, 40, (500, 2))
    want = np.unique(pairs, axis=0)
    got = thinness.unique_pairs(pairs, 40)
    assert got.dtype == np.int64 and np.array_equal(got, want)
    assert thinness.unique_pairs(np.zeros((0, 2), np.int64), 5).shape == (0, 2)


@pytest.mark.parametrize("shrink", [0.0, 0.05, 0.4])
def test_shrunk_tiles_are_the_shrunk_quads_and_edges(shrink):
    c = read_pattern(DATA / "heart-16x16-rigid.json").contracted[1]
    quads, edges = thinness.shrunk_tiles(c, shrink)
    assert np.array_equal(quads, thinness.shrunk_quads(c, shrink))
    assert np.array_equal(edges, thinness.shrunk_edges(c, shrink))
    assert shrink < 0.4 or (edges <= 0).any()  # the largest loses an edge somewhere
