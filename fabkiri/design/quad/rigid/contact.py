"""Tiles of a closed state kept apart: inequality rows of the rigid-family solver (``reduced.py``).

The solver's own inequalities are local (hinge gaps, convex tiles), so nothing stopped two boundary tiles
far apart in the lattice from meeting in a closed state: from 48x48 tiles on, the heart's notch closed
over itself in state 2 (48x48: 10 overlapping pairs, 64x64: 45, all in the top row either side of the
cusp), and the design failed the CLI's overlap check. In the rigid family both closed states are linear
in the seeds, with no ψ: state 1 is the grid ``c = Z S``, state 2 is ``J (Y S)`` (``family.py``; a quarter
turn, which keeps every distance and orientation), so the rows are evaluated on ``Z S`` and ``Y S``.

Rows: for every pair of tiles of the lattice's outer ``RING`` rows and columns that are not lattice neighbours (Chebyshev
distance ≥ 2) and whose circumscribed circles come within ``REACH`` median edges in that state (``_near_pairs``: a
large tile reaches as far as its own size), each corner of one tile
against the other (counter-clockwise, convex): ``g = max_e`` of the corner's outward distance from edge
``e``, ``g ≥ CONTACT_MARGIN`` (tile units). The pairs are found again at every evaluation (a KD-tree over
the ring's centres); a pair enters far from contact, so the penalty stays continuous. Only the rows below
their margin get a Jacobian, ``∂g/∂p`` through ``Z`` or ``Y`` (the stencil's three nodes: the corner and
the edge's ends). The CLI's exact check (penetration depth) still judges the result.
"""

from __future__ import annotations

import numpy as np

from ....kdtree import KDTree
from ...core.stencils import Stencils
from .family import RigidFamily

CONTACT_MARGIN = 0.01  # outward distance of a corner from a non-neighbouring tile, tile units
REACH = 3.0  # tile pairs whose circumscribed circles come closer than this many median edges are checked
# the rows and columns along the lattice's edge that are checked: the symmetric 64x64 heart's state-1 notch
# overlapped between the top row and the one below it (91 pairs, first tiles (62, 19) and (63, 41))
RING = 2
NAMES = ("closed_contact_1", "closed_contact_2")


class ClosedContact:
    """The closed-state contact rows of one lattice's rigid family (module docstring)."""

    def __init__(self, fam: RigidFamily, st: Stencils, barrier: bool = True):
        # barrier: the rows count as inequalities (no step may deepen a violation); else a penalty only
        self.barrier = barrier
        M, N = st.rows, st.cols
        r, c = np.divmod(np.arange(M * N), N)
        d = RING
        self.ring = np.flatnonzero((r < d) | (r >= M - d) | (c < d) | (c >= N - d))
        self.r, self.c = r[self.ring], c[self.ring]
        # (rows of the basis, tile corners as rows of the basis) per closed state; Y's rows made as asked
        self.fam = fam
        self.blocks = (
            (lambda n: fam.Z[n], fam.node_vertex[st.tiles]),
            (lambda n: fam.rows(n)[1], st.tiles),
        )
        self.nf = fam.n_seeds
        self._last: tuple | None = None

    def configs(self, S: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Closed state 1 (``Z S``) and closed state 2 turned back a quarter (``Y S``)."""
        return self.fam.Z @ S, self.fam.Y @ S

    def measure(self, x: np.ndarray, state: int, below: float | None = None):
        """``(g, nodes (m, 3), grads (m, 3, 2))`` of state ``state`` (1 or 2) on its configuration ``x``.

        ``below``: only the pairs that may have a row below it (``_may_touch``); the rows left out are all
        above it, and the rows kept are the same, in the same order."""
        tiles = self.blocks[state - 1][1][self.ring]
        q = x[tiles]  # (R, 4, 2)
        pairs = _near_pairs(q)
        far = np.maximum(
            np.abs(self.r[pairs[:, 0]] - self.r[pairs[:, 1]]),
            np.abs(self.c[pairs[:, 0]] - self.c[pairs[:, 1]]),
        )
        pairs = pairs[far >= 2]
        if below is not None:
            pairs = pairs[_may_touch(q, pairs, below)]
        # every corner of one tile against the other tile, both ways
        a = np.concatenate([pairs[:, 0], pairs[:, 1]]).repeat(4)  # the corner's tile
        b = np.concatenate([pairs[:, 1], pairs[:, 0]]).repeat(4)  # the tile it must stay out of
        k = np.tile(np.arange(4), 2 * len(pairs))
        v_node = tiles[a, k]
        ends = tiles[b]  # (m, 4)
        v = x[v_node][:, None, :]  # (m, 1, 2)
        p0, p1 = x[ends], x[np.roll(ends, -1, 1)]  # each edge's ends (m, 4, 2)
        e, w = p1 - p0, v - p0
        length = np.maximum(np.linalg.norm(e, axis=-1), 1e-300)
        cross = e[..., 0] * w[..., 1] - e[..., 1] * w[..., 0]
        out = -cross / length  # outward distance from each edge (counter-clockwise tiles)
        j = np.argmax(out, axis=1)
        row = np.arange(len(a))
        g = out[row, j]
        e, w, length, cross = e[row, j], w[row, j], length[row, j], cross[row, j]
        dv = np.stack([e[:, 1], -e[:, 0]], -1) / length[:, None]
        de = -np.stack([w[:, 1], -w[:, 0]], -1) / length[:, None] + (cross / length**3)[:, None] * e
        nodes = np.stack([v_node, ends[row, j], np.roll(ends, -1, 1)[row, j]], 1)
        grads = np.stack([dv, -dv - de, de], 1)
        return g, nodes, grads

    def _measured(self, xs, margin: float = CONTACT_MARGIN) -> list:
        """``measure`` of both states, kept for the same arrays (the merit asks for the values, then the rows):
        every row below ``margin``, and from the pairs that may hold one only while ``margin`` is at most
        ``CONTACT_MARGIN`` (the merit's rows and the sign of the smallest value need no more)."""
        below = CONTACT_MARGIN if margin <= CONTACT_MARGIN else None
        if (
            self._last is None
            or self._last[1] != below
            or any(a is not b for a, b in zip(self._last[0], xs))
        ):
            self._last = (
                tuple(xs),
                below,
                [self.measure(x, s + 1, below) for s, x in enumerate(xs)],
            )
        return self._last[2]

    def values(self, xs) -> dict:
        """The contact rows' values per state, on ``configs``' arrays: every row below ``CONTACT_MARGIN``
        (those above it bar nothing: only a negative value is a violation) and some of the others."""
        return {NAMES[s]: m[0] for s, m in enumerate(self._measured(xs))}

    def active(self, xs, margin_scale: float, scale: float) -> tuple[np.ndarray, np.ndarray]:
        """Rows below ``margin_scale · CONTACT_MARGIN``, times ``scale``: ``(r, ∂r/∂p)`` (dense, P columns)."""
        rs, Js = [np.zeros(0)], [np.zeros((0, 2 * self.nf + 1))]
        for s, (g, nodes, grads) in enumerate(self._measured(xs, margin_scale * CONTACT_MARGIN)):
            act = np.flatnonzero(g < margin_scale * CONTACT_MARGIN)
            if not len(act):
                continue
            n, gr = nodes[act], grads[act]
            B = self.blocks[s][0](n)
            J = np.zeros((len(act), 2 * self.nf + 1))
            J[:, : self.nf] = np.einsum("mk,mkf->mf", gr[..., 0], B)
            J[:, self.nf : 2 * self.nf] = np.einsum("mk,mkf->mf", gr[..., 1], B)
            rs.append(scale * (g[act] - margin_scale * CONTACT_MARGIN))
            Js.append(scale * J)
        return np.concatenate(rs), np.vstack(Js)


def _may_touch(q: np.ndarray, pairs: np.ndarray, below: float) -> np.ndarray:
    """Which ``pairs`` of tiles ``q`` may have a row (a corner of one against the other, ``measure``) below
    ``below``. A corner ``v`` of tile a lies within ``R_a`` (its farthest corner) of a's corner mean ``c_a``, so
    its outward distance from an edge of tile b (unit normal ``n``, through ``p``) is
    ``n·(v - p) >= n·(c_a - p) - R_a``; a row is the largest of these over b's edges. Exact for any
    quadrilateral (no convexity needed); a pair is left out only when both ways are clear of ``below`` by more
    than round-off."""
    cen = q.mean(1)
    rad = np.linalg.norm(q - cen[:, None], axis=-1).max(1)
    e = np.roll(q, -1, 1) - q
    n = (
        np.stack([e[..., 1], -e[..., 0]], -1)
        / np.maximum(np.linalg.norm(e, axis=-1), 1e-300)[..., None]
    )
    slack = below + 1e-9 * (1.0 + float(np.abs(q).max(initial=0.0)))
    keep = np.zeros(len(pairs), bool)
    for a, b in ((pairs[:, 0], pairs[:, 1]), (pairs[:, 1], pairs[:, 0])):
        # the least outward distance of any corner of a from b's edges, over its best edge
        off = np.einsum("mkd,mkd->mk", n[b], cen[a][:, None, :] - q[b]).max(1) - rad[a]
        keep |= off <= slack
    return keep


def _near_pairs(q: np.ndarray) -> np.ndarray:
    """Pairs ``(i, j)``, i < j, of tiles ``q`` (R, 4, 2) whose circumscribed circles (about the corners' mean)
    come within ``REACH`` median edges of each other. A tile's own size counts: a tile many edges long meets
    tiles whose centres are far from its own (the 64x64 drop's state-1 corner tile, 17.6 median edges long,
    lay over a top-row tile 13.6 median edges from its centre, a pair a reach between centres never saw)."""
    cen = q.mean(1)
    rad = np.linalg.norm(q - cen[:, None], axis=-1).max(1)
    edge = float(np.median(np.linalg.norm(q[:, 1] - q[:, 0], axis=1)))
    gap = REACH * max(edge, 1e-12)
    # a pair is found from its larger tile's ball: |ci - cj| <= ri + rj + gap <= 2 max(ri, rj) + gap; the pairs of
    # tiles up to 1.5 median radii in one query, each larger tile's (rare) from its own ball
    cut = min(float(rad.max()), 1.5 * float(np.median(rad)))
    tree = KDTree(cen)
    small = tree.query_pairs(2 * cut + gap, output_type="ndarray").astype(np.int64).reshape(-1, 2)
    large = np.flatnonzero(rad > cut)
    hits = tree.query_ball_point(cen[large], 2 * rad[large] + gap) if len(large) else []
    i = np.concatenate([small[:, 0], np.repeat(large, [len(h) for h in hits])])
    j = np.concatenate([small[:, 1]] + [np.asarray(h, dtype=np.int64) for h in hits])
    lo, hi = np.minimum(i, j), np.maximum(i, j)
    code = np.unique(lo[lo < hi] * len(q) + hi[lo < hi])
    a, b = np.divmod(code, len(q))
    near = np.linalg.norm(cen[a] - cen[b], axis=1) <= rad[a] + rad[b] + gap
    return np.stack([a[near], b[near]], 1).astype(np.int64)
