"""Non-overlap of kagome tiles that share no hinge: a corner of one tile stays outside the other.

The hinge-gap rows (:func:`fabkiri.design.kagome.rows.gap_family`) keep the two tiles at a hinge apart;
tiles that share no node can still overlap across a hole or a row-end notch (a tile crossing a non-convex
hole, or the end tiles of two rows folding onto each other when the gap floor is low). For every pair of
tiles near each other in the standard lattice and sharing no node, and every corner ``p`` of one, the row
asks ``p`` to be outside the other triangle by ``margin``:

    g(p) = max_k  -cross(a_{k+1} - a_k, p - a_k) / |a_{k+1} - a_k|  >= margin,

the largest signed distance of ``p`` beyond an edge line of the counter-clockwise triangle ``a`` (positive
outside, negative inside). A corner inside is pushed out across the nearest edge; two triangles can still
cross without a corner inside (a star), which the verifier's overlap check catches as before.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

from ...pattern.model import Pattern
from ..core.stencils import Family

NEAR = 3.5  # pairs whose standard centroids are this close (tile edges): across a hole, a notch or two rows


def near_pairs(standard: Pattern, near: float = NEAR) -> np.ndarray:
    """``(m, 2)`` tile pairs with centroids within ``near`` standard tile edges and no shared node."""
    top = standard.topology
    c = standard.nodes[top.tiles].mean(1) / standard.tile_size
    pairs = np.array(sorted(cKDTree(c).query_pairs(near)), dtype=np.int64).reshape(-1, 2)
    t = top.tiles
    share = (t[pairs[:, 0], :, None] == t[pairs[:, 1], None, :]).any((1, 2))
    return pairs[~share]


def corner_outside(x: np.ndarray, p: np.ndarray, tri: np.ndarray):
    """``g`` (above) of points ``x[p]`` against triangles ``x[tri]`` (m, 3), with its gradient on the
    nodes ``(p, a0, a1, a2)`` (the edge not chosen gets zero)."""
    P, A = x[p], x[tri]
    B = np.roll(A, -1, 1)
    U = B - A  # (m, 3, 2) edges
    W = P[:, None, :] - A
    L = np.linalg.norm(U, axis=2)
    c = U[..., 0] * W[..., 1] - U[..., 1] * W[..., 0]
    f = -c / L
    k = np.argmax(f, axis=1)
    i = np.arange(len(p))
    u, w, ln, ck = U[i, k], W[i, k], L[i, k], c[i, k]
    dp = np.stack([u[:, 1], -u[:, 0]], -1) / ln[:, None]
    du = -np.stack([w[:, 1], -w[:, 0]], -1) / ln[:, None] + (ck / ln**3)[:, None] * u
    g = np.zeros((len(p), 4, 2))
    g[:, 0] = dp
    g[i, 1 + k] += -dp - du  # the edge's start a_k
    g[i, 1 + (k + 1) % 3] += du  # and its end a_{k+1}
    return f[i, k], np.column_stack([p, tri]), g


def pair_family(standard: Pattern, margin: float, near: float = NEAR) -> Family:
    """Every corner of each near pair's tiles at least ``margin`` (tile edges) outside the other tile:
    rows ``min(g - margin, 0)``, six per pair."""
    top = standard.topology
    pairs = near_pairs(standard, near)
    a = np.repeat(pairs, 3, axis=0)
    k = np.tile(np.arange(3), len(pairs))
    # corners of the second tile against the first, then those of the first against the second
    p = np.r_[top.tiles[a[:, 1], k], top.tiles[a[:, 0], k]]
    tri = np.r_[top.tiles[a[:, 0]], top.tiles[a[:, 1]]]
    nodes = np.column_stack([p, tri])  # one array: the Jacobian's structure is built once

    def fn(x):
        g, _, grads = corner_outside(x, p, tri)
        act = g < margin
        return np.where(act, g - margin, 0.0), (nodes, grads * act[:, None, None])

    # not while landing: the start's tiles may cross anywhere, and the rows would pull against the landing
    return Family("tile_pairs", "ineq", fn, 1, meta={"land": False}, nv=top.n_nodes)
