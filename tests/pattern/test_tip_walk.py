"""The boundary tip walk (``conformance._walk_tips``) with its edge sets in numpy gives the loop's answers (#36)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from fabkiri.exchange.pattern_json import read_pattern
from fabkiri.pattern import conformance
from fabkiri.pattern.kinds.kagome.lattice import standard_kagome
from fabkiri.pattern.kinds.quad.lattice import standard_pattern

DATA = Path(__file__).parents[1] / "data"


def _loop_walk(tiles, hole_nodes, hole_tiles, free_nodes):
    """The walk as it was: its hole set and half-edge map built by a Python loop over every tile edge."""
    T, n = tiles.shape
    a = tiles.reshape(-1)
    b = np.roll(tiles, -1, axis=1).reshape(-1)
    t = np.repeat(np.arange(T), n)
    hole = set()
    if len(hole_nodes):
        n0, n1 = hole_nodes, np.roll(hole_nodes, -1, axis=1)
        for tt, x, y in zip(hole_tiles.ravel().tolist(), n0.ravel().tolist(), n1.ravel().tolist()):
            hole.add((tt, min(x, y), max(x, y)))
    nxt = {}
    users: dict = {}
    for tt, x, y in zip(t.tolist(), a.tolist(), b.tolist()):
        users.setdefault(x, []).append(tt)
        if (tt, min(x, y), max(x, y)) not in hole:
            nxt[(tt, x)] = y
    free = set(free_nodes.tolist())
    if not free:
        return np.zeros(0, dtype=np.int64)
    start = int(free_nodes[0])
    order = []
    key = (users[start][0], start)
    for _ in range(len(nxt) + 1):
        if key[1] in free:
            order.append(key[1])
        y = nxt.get(key)
        if y is None or y == start:
            break
        key = (next((u for u in users[y] if u != key[0]), key[0]), y)
    if len(order) != len(free):
        return np.asarray(free_nodes)
    return np.asarray(order, dtype=np.int64)


def _relabelled(top, rng):
    """The topology's arrays with the nodes renumbered and the tiles (and hole tile numbers) permuted."""
    nodes = rng.permutation(int(top.tiles.max()) + 1)
    tiles = rng.permutation(len(top.tiles))
    new_tile = np.argsort(tiles)
    return (
        nodes[top.tiles[tiles]],
        nodes[top.hole_nodes],
        new_tile[top.hole_tiles],
        nodes[rng.permutation(top.free_nodes)],
    )


PATTERNS = {
    "quad 5x7": lambda: standard_pattern(5, 7, tile_size=1.0),
    "quad 16x16": lambda: standard_pattern(16, 16, tile_size=1.0),
    "kagome 4x6": lambda: standard_kagome(4, 6),
    "heart design": lambda: read_pattern(DATA / "heart-16x16-rigid.json"),
    "kagome design": lambda: read_pattern(DATA / "kagome-heart-6x11.json"),
}


@pytest.mark.parametrize("name", PATTERNS)
def test_the_walk_gives_the_loops_order(name):
    top = PATTERNS[name]().topology
    rng = np.random.default_rng(36)
    cases = [(top.tiles, top.hole_nodes, top.hole_tiles, top.free_nodes)]
    cases += [_relabelled(top, rng) for _ in range(5)]
    # holes left out (more boundary, not one cycle) and free nodes dropped (fewer tips than the walk meets)
    keep = rng.random(len(top.hole_nodes)) < 0.8
    cases.append((top.tiles, top.hole_nodes[keep], top.hole_tiles[keep], top.free_nodes))
    cases.append((top.tiles, top.hole_nodes, top.hole_tiles, top.free_nodes[::2]))
    cases.append((top.tiles, top.hole_nodes[:0], top.hole_tiles[:0], top.free_nodes))
    for case in cases:
        want = _loop_walk(*case)
        got = conformance._walk_tips(*(np.asarray(x) for x in case))
        assert got.dtype == want.dtype and np.array_equal(got, want)


def test_random_tilings_walk_as_the_loop():
    rng = np.random.default_rng(7)
    for _ in range(200):
        T = int(rng.integers(1, 12))
        tiles = rng.integers(0, 3 * T + 2, (T, 4))
        holes = rng.integers(0, T, (int(rng.integers(0, 6)), 4))
        hole_nodes = tiles[holes, rng.integers(0, 4, holes.shape)]
        used = np.unique(tiles)
        free = rng.choice(used, size=min(int(rng.integers(0, 5)), len(used)), replace=False)
        want = _loop_walk(tiles, hole_nodes, holes, free)
        assert np.array_equal(conformance._walk_tips(tiles, hole_nodes, holes, free), want)
