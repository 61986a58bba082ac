"""Topology of a quad kirigami pattern, derived once from its tiles.

Vocabulary (algorithm spec §1-§2):

* a **hinge** is a node shared by exactly two tiles ``A < B``;
* a **free corner** is a node used by one tile (it lies on the outer boundary);
* each hinge has two **gaps** between its tiles. With ``prev``/``next`` taken
  counter-clockwise inside each tile, gap 0 lies between ``A``'s edge to
  ``prev_A(h)`` and ``B``'s edge to ``next_B(h)``, gap 1 between ``B``'s edge to
  ``prev_B(h)`` and ``A``'s edge to ``next_A(h)``;
* a **hole** is a bounded face of the cut: four tile edges of four distinct
  tiles meeting at four hinges;
* a closed **state** folds exactly one gap at every hinge. The tile adjacency
  graph of a quad tessellation is bipartite; in state 1 every hinge folds the
  gap on the ``prev`` side of its *even* tile, in state 2 the other gap. With the
  lattice's corner order (BL, BR, TR, TL) this is the primal pattern (ψ = 0) for
  state 1 and the dual (ψ = π/2) for state 2. Which colour counts as even is the
  pattern's ``parity`` (0: tile 0 is even).

Everything here is combinatorial: geometry never decides topology, so a
self-intersecting tile or a pattern deployed at ψ = 0 still gets a topology.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np
from scipy import sparse
from scipy.sparse import csgraph

from ..errors import PatternError

STATES = (1, 2)


@dataclass(frozen=True, eq=False)
class FoldRule:
    """What closes in one closed state."""

    state: int
    fold_gap: np.ndarray  # (H,) which gap (0/1) folds at each hinge
    fold_ends: np.ndarray  # (H, 2) far node of A's and of B's edge bounding the folded gap
    fold_corner_ends: np.ndarray  # (H, 2) corner index of those nodes in A and in B
    hole_folds: np.ndarray  # (K, 4) bool: the hole folds at that corner in this state
    rings: np.ndarray  # (K, 4, 2) (tile, corner) of the four angles at the hole's two merge corners

    def edge_pairs(self, hinge_node: np.ndarray) -> np.ndarray:
        """``(H, 2, 2)`` node pairs ``((h, a), (h, b))`` whose lengths must agree."""
        h = hinge_node
        return np.stack(
            [np.stack([h, self.fold_ends[:, 0]], -1), np.stack([h, self.fold_ends[:, 1]], -1)], 1
        )


@dataclass(frozen=True, eq=False)
class Topology:
    """Hinges, free corners, holes and fold rules of a set of CCW quad tiles."""

    tiles: np.ndarray  # (T, 4) node indices, CCW
    n_nodes: int
    hinge_node: np.ndarray  # (H,)
    hinge_tiles: np.ndarray  # (H, 2) tiles A < B
    hinge_corner: np.ndarray  # (H, 2) corner index of the hinge node in A, in B
    free_nodes: np.ndarray  # (F,)
    tile_color: np.ndarray  # (T,) bipartite colour, tile 0 has colour 0
    gap_face: np.ndarray  # (H, 2) hole index of each gap, -1 for the exterior
    hole_nodes: np.ndarray  # (K, 4) hinge nodes, CCW around the hole
    hole_hinges: np.ndarray  # (K, 4) hinge index of each hole corner
    hole_gap: np.ndarray  # (K, 4) which gap of that hinge is this hole
    hole_tiles: np.ndarray  # (K, 4) tile owning the hole edge from corner c to c+1
    parity: int = 0

    @property
    def n_tiles(self) -> int:
        return len(self.tiles)

    @property
    def n_hinges(self) -> int:
        return len(self.hinge_node)

    @property
    def n_holes(self) -> int:
        return len(self.hole_nodes)

    @cached_property
    def node_hinge(self) -> np.ndarray:
        """Hinge index of every node, -1 for free corners."""
        out = np.full(self.n_nodes, -1, dtype=np.int64)
        out[self.hinge_node] = np.arange(self.n_hinges)
        return out

    @cached_property
    def tile_adjacency(self) -> sparse.csr_matrix:
        """Symmetric tile graph; the stored value is ``hinge index + 1``."""
        a, b = self.hinge_tiles.T
        h = np.arange(self.n_hinges) + 1
        T = self.n_tiles
        return sparse.csr_matrix(
            (np.concatenate([h, h]), (np.concatenate([a, b]), np.concatenate([b, a]))), shape=(T, T)
        )

    def spanning_tree(self, root: int = 0) -> "SpanningTree":
        """Breadth-first spanning tree of the tile graph from ``root``."""
        return _spanning_tree(self, root)

    def even_tiles(self) -> np.ndarray:
        return self.tile_color == self.parity

    def fold(self, state: int) -> FoldRule:
        if state not in STATES:
            raise ValueError(f"state must be 1 or 2, not {state!r}")
        return self._folds[state]

    @cached_property
    def _folds(self) -> dict[int, FoldRule]:
        return {s: _fold_rule(self, s) for s in STATES}


@dataclass(frozen=True, eq=False)
class SpanningTree:
    """A breadth-first tree of tiles: every non-root tile with its parent and hinge.

    Placing tiles rigidly along it (contraction, rigid paths, reassembly from
    cut shapes) is one vectorised step per BFS level: ``levels()`` yields the
    positions (into ``children``) of each level, parents always placed first.
    """

    root: int
    children: np.ndarray  # (T-1,) tiles in BFS order, root excluded
    parents: np.ndarray  # (T-1,) parent of each child
    hinges: np.ndarray  # (T-1,) hinge joining child and parent
    depth: np.ndarray  # (T-1,) BFS depth of each child (>= 1)
    parent_is_a: np.ndarray  # (T-1,) bool: the parent is the hinge's tile A

    def levels(self):
        for d in range(1, int(self.depth.max(initial=0)) + 1):
            yield np.flatnonzero(self.depth == d)


def _spanning_tree(top: Topology, root: int) -> SpanningTree:
    T = top.n_tiles
    if T == 1:
        empty = np.zeros(0, dtype=np.int64)
        return SpanningTree(root, empty, empty, empty, empty, np.zeros(0, dtype=bool))
    adj = top.tile_adjacency
    order, pred = csgraph.breadth_first_order(adj, root, directed=False, return_predecessors=True)
    depth = np.zeros(T, dtype=np.int64)
    for tile in order[1:]:  # BFS order: a parent's depth is known before its children's
        depth[tile] = depth[pred[tile]] + 1
    children = order[1:].astype(np.int64)
    parents = pred[children].astype(np.int64)
    hinges = np.asarray(adj[parents, children]).ravel().astype(np.int64) - 1
    return SpanningTree(root, children, parents, hinges, depth[children],
                        top.hinge_tiles[hinges, 0] == parents)


def _fold_rule(top: Topology, state: int) -> FoldRule:
    tiles = top.tiles
    A, B = top.hinge_tiles.T
    cA, cB = top.hinge_corner.T
    a_even = top.even_tiles()[A]
    fold_gap = np.where(a_even, 0, 1) if state == 1 else np.where(a_even, 1, 0)
    # gap 0: (prev_A, next_B); gap 1: (next_A, prev_B)
    end_cA = np.where(fold_gap == 0, (cA + 3) % 4, (cA + 1) % 4)
    end_cB = np.where(fold_gap == 0, (cB + 1) % 4, (cB + 3) % 4)
    fold_ends = np.stack([tiles[A, end_cA], tiles[B, end_cB]], -1)

    K = top.n_holes
    hole_folds = fold_gap[top.hole_hinges] == top.hole_gap if K else np.zeros((0, 4), bool)
    if K:
        alternating = (hole_folds == np.array([True, False, True, False])).all(1) | (
            hole_folds == np.array([False, True, False, True])
        ).all(1)
        if not alternating.all():
            bad = int(np.flatnonzero(~alternating)[0])
            raise PatternError(
                f"hole {bad} (nodes {top.hole_nodes[bad].tolist()}) does not fold at two opposite "
                f"corners in state {state}: not a rotating-squares quad tessellation"
            )
    # merge corners: the two corners where this hole does not fold
    merge = np.argsort(hole_folds, axis=1, kind="stable")[:, :2] if K else np.zeros((0, 2), int)
    mh = np.take_along_axis(top.hole_hinges, merge, 1) if K else np.zeros((0, 2), int)
    ring_tiles = top.hinge_tiles[mh].reshape(K, 4)
    ring_corners = top.hinge_corner[mh].reshape(K, 4)
    rings = np.stack([ring_tiles, ring_corners], -1)
    return FoldRule(
        state=state,
        fold_gap=fold_gap.astype(np.int64),
        fold_ends=fold_ends,
        fold_corner_ends=np.stack([end_cA, end_cB], -1),
        hole_folds=hole_folds,
        rings=rings,
    )


def derive_topology(tiles: np.ndarray, n_nodes: int, parity: int = 0) -> Topology:
    """Derive hinges, holes and fold rules from CCW quad tiles.

    Raises :class:`PatternError` naming the first inconsistency: a node used by
    three or more tiles, two tiles sharing an edge, a disconnected pattern, a
    tile graph that is not two-colourable, or a face that is not a quad hole.
    """
    tiles = np.asarray(tiles, dtype=np.int64)
    T = len(tiles)
    if T == 0:
        raise PatternError("the pattern has no tiles")
    if tiles.ndim != 2 or tiles.shape[1] != 4:
        raise PatternError(f"tiles must be quads (4 node indices each), got shape {tiles.shape}")
    if tiles.min() < 0 or tiles.max() >= n_nodes:
        bad = int(np.flatnonzero((tiles < 0).any(1) | (tiles >= n_nodes).any(1))[0])
        raise PatternError(f"tile {bad} references node {tiles[bad].tolist()} outside 0..{n_nodes - 1}")
    srt = np.sort(tiles, axis=1)
    dup = (srt[:, 1:] == srt[:, :-1]).any(1)
    if dup.any():
        bad = int(np.flatnonzero(dup)[0])
        raise PatternError(f"tile {bad} uses the same node twice: {tiles[bad].tolist()}")
    if parity not in (0, 1):
        raise PatternError(f"parity must be 0 or 1, not {parity!r}")

    flat = tiles.ravel()
    use = np.bincount(flat, minlength=n_nodes)
    if (use > 2).any():
        bad = int(np.flatnonzero(use > 2)[0])
        who = sorted({int(t) for t in np.flatnonzero((tiles == bad).any(1))})
        raise PatternError(f"node {bad} is shared by {use[bad]} tiles {who}; a hinge joins exactly two")
    if (use == 0).any():
        raise PatternError(f"node {int(np.flatnonzero(use == 0)[0])} is not used by any tile")

    order = np.argsort(flat, kind="stable")
    sorted_nodes = flat[order]
    first = np.searchsorted(sorted_nodes, np.arange(n_nodes))
    hinge_node = np.flatnonzero(use == 2)
    i0, i1 = order[first[hinge_node]], order[first[hinge_node] + 1]
    hinge_tiles = np.stack([i0 // 4, i1 // 4], -1)
    hinge_corner = np.stack([i0 % 4, i1 % 4], -1)
    swap = hinge_tiles[:, 0] > hinge_tiles[:, 1]
    hinge_tiles[swap] = hinge_tiles[swap][:, ::-1]
    hinge_corner[swap] = hinge_corner[swap][:, ::-1]
    free_nodes = np.flatnonzero(use == 1)
    H = len(hinge_node)

    # Two tiles may share one node only: a shared edge is not a kirigami cut.
    if H:
        key = hinge_tiles[:, 0] * T + hinge_tiles[:, 1]
        uniq, counts = np.unique(key, return_counts=True)
        if (counts > 1).any():
            k = uniq[counts > 1][0]
            raise PatternError(f"tiles {k // T} and {k % T} share more than one node (an uncut edge)")

    adj = sparse.csr_matrix((np.ones(2 * H), (np.r_[hinge_tiles[:, 0], hinge_tiles[:, 1]],
                                               np.r_[hinge_tiles[:, 1], hinge_tiles[:, 0]])), shape=(T, T))
    n_comp, _ = csgraph.connected_components(adj, directed=False)
    if n_comp > 1:
        raise PatternError(f"the tiles form {n_comp} disconnected pieces; a pattern is one piece")
    bfs, pred = csgraph.breadth_first_order(adj, 0, directed=False, return_predecessors=True)
    color = np.zeros(T, dtype=np.int64)
    for t in bfs[1:]:  # depth parity along the BFS tree
        color[t] = 1 - color[pred[t]]
    clash = color[hinge_tiles[:, 0]] == color[hinge_tiles[:, 1]]
    if clash.any():
        a, b = hinge_tiles[np.flatnonzero(clash)[0]]
        raise PatternError(
            f"tiles {a} and {b} close an odd cycle of tiles: a quad kirigami tile graph is a checkerboard"
        )

    # Faces of the cut: follow tile edges backwards with the face on the left.
    # Half-edge 4*t+k is the edge of tile t from corner k to k+1, walked from
    # k+1 to k. At a hinge the walk continues on the other tile, else on the same.
    he = np.arange(4 * T)
    t_of, k_of = he // 4, he % 4
    node_at = tiles[t_of, k_of]
    hinge_of_node = np.full(n_nodes, -1, dtype=np.int64)
    hinge_of_node[hinge_node] = np.arange(H)
    h_at = hinge_of_node[node_at]
    is_h = h_at >= 0
    # a dummy last row lets free corners (h_at == -1) index safely
    ht = np.vstack([hinge_tiles, [[-1, -1]]])
    hc = np.vstack([hinge_corner, [[-1, -1]]])
    arrives_on_A = ht[h_at, 0] == t_of
    other_t = np.where(is_h, np.where(arrives_on_A, ht[h_at, 1], ht[h_at, 0]), t_of)
    other_k = np.where(is_h, np.where(arrives_on_A, hc[h_at, 1], hc[h_at, 0]), k_of)
    nxt = 4 * other_t + (other_k + 3) % 4
    perm = sparse.csr_matrix((np.ones(4 * T), (he, nxt)), shape=(4 * T, 4 * T))
    n_faces, face_of = csgraph.connected_components(perm, directed=True, connection="strong")
    face_size = np.bincount(face_of, minlength=n_faces)
    face_free = np.bincount(face_of, weights=(~is_h).astype(float), minlength=n_faces) > 0

    # which gap of the hinge the half-edge's face fills (see module docstring)
    gap_idx = np.where(arrives_on_A, 1, 0)

    bounded = np.flatnonzero(~face_free)
    bad = bounded[face_size[bounded] != 4]
    if len(bad):
        raise PatternError(
            f"the cut has a hole with {face_size[bad[0]]} corners; quad kirigami holes have 4"
        )
    # order holes by their smallest half-edge, walk 4 steps from it
    first_he = np.full(n_faces, 4 * T, dtype=np.int64)
    np.minimum.at(first_he, face_of, he)
    hole_faces = bounded[np.argsort(first_he[bounded], kind="stable")]
    K = len(hole_faces)
    hole_index = np.full(n_faces, -1, dtype=np.int64)
    hole_index[hole_faces] = np.arange(K)
    walk = np.empty((K, 4), dtype=np.int64)
    if K:
        walk[:, 0] = first_he[hole_faces]
        for i in range(1, 4):
            walk[:, i] = nxt[walk[:, i - 1]]
    # corner c of a hole is where the walk arrives at step c; the edge from
    # corner c to corner c+1 (CCW) is the one walked at step c+1.
    hole_nodes = node_at[walk]
    hole_hinges = h_at[walk]
    hole_gap = gap_idx[walk]
    hole_tiles = t_of[np.roll(walk, -1, axis=1)]
    if K and (np.sort(hole_tiles, 1)[:, 1:] == np.sort(hole_tiles, 1)[:, :-1]).any():
        raise PatternError("a hole is bounded twice by the same tile; not a quad kirigami tessellation")

    gap_face = np.full((H, 2), -1, dtype=np.int64)
    sel = is_h
    gap_face[h_at[sel], gap_idx[sel]] = hole_index[face_of[sel]]

    return Topology(
        tiles=tiles,
        n_nodes=int(n_nodes),
        hinge_node=hinge_node,
        hinge_tiles=hinge_tiles,
        hinge_corner=hinge_corner,
        free_nodes=free_nodes,
        tile_color=color,
        gap_face=gap_face,
        hole_nodes=hole_nodes,
        hole_hinges=hole_hinges,
        hole_gap=hole_gap,
        hole_tiles=hole_tiles,
        parity=int(parity),
    )
