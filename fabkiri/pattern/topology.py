"""Topology of a kirigami pattern, derived once from its tiles.

Vocabulary (docs/algorithm.md#lattice):

* a **hinge** is a node shared by exactly two tiles ``A < B``;
* a **free corner** is a node used by one tile (it lies on the outer boundary);
* each hinge has two **gaps** between its tiles. With ``prev``/``next`` taken
  counter-clockwise inside each tile, gap 0 lies between ``A``'s edge to
  ``prev_A(h)`` and ``B``'s edge to ``next_B(h)``, gap 1 between ``B``'s edge to
  ``prev_B(h)`` and ``A``'s edge to ``next_A(h)``;
* a **hole** is a bounded face of the cut: tile edges of distinct tiles meeting at hinges, as many
  as the tessellation's ``hole_arity`` (four in a quad pattern);
* a closed **state** folds exactly one gap at every hinge; which one is the tessellation's fold rule
  (:mod:`fabkiri.pattern.kinds.tessellation`; the quad rule is in :mod:`fabkiri.pattern.kinds.quad.rules`). The tile adjacency
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
from .kinds.tessellation import DEFAULT_KIND, Tessellation, tessellation

STATES = (1, 2)


@dataclass(frozen=True, eq=False)
class FoldRule:
    """What closes in one closed state."""

    state: int
    fold_gap: np.ndarray  # (H,) which gap (0/1) folds at each hinge
    fold_ends: np.ndarray  # (H, 2) far node of A's and of B's edge bounding the folded gap
    fold_corner_ends: np.ndarray  # (H, 2) corner index of those nodes in A and in B
    hole_folds: np.ndarray  # (K, m) bool: the hole folds at that corner in this state
    rings: np.ndarray  # (K, m, 2) (tile, corner) of the m angles at the hole's m/2 merge corners

    def edge_pairs(self, hinge_node: np.ndarray) -> np.ndarray:
        """``(H, 2, 2)`` node pairs ``((h, a), (h, b))`` whose lengths must agree."""
        h = hinge_node
        return np.stack(
            [np.stack([h, self.fold_ends[:, 0]], -1), np.stack([h, self.fold_ends[:, 1]], -1)], 1
        )


@dataclass(frozen=True, eq=False)
class Topology:
    """Hinges, free corners, holes and fold rules of a set of CCW tiles (``n`` corners each)."""

    tiles: np.ndarray  # (T, n) node indices, CCW
    n_nodes: int
    hinge_node: np.ndarray  # (H,)
    hinge_tiles: np.ndarray  # (H, 2) tiles A < B
    hinge_corner: np.ndarray  # (H, 2) corner index of the hinge node in A, in B
    free_nodes: np.ndarray  # (F,)
    tile_color: np.ndarray  # (T,) bipartite colour, tile 0 has colour 0
    gap_face: np.ndarray  # (H, 2) hole index of each gap, -1 for the exterior
    hole_nodes: np.ndarray  # (K, m) hinge nodes, CCW around the hole
    hole_hinges: np.ndarray  # (K, m) hinge index of each hole corner
    hole_gap: np.ndarray  # (K, m) which gap of that hinge is this hole
    hole_tiles: np.ndarray  # (K, m) tile owning the hole edge from corner c to c+1
    parity: int = 0
    kind: str = DEFAULT_KIND  # the tessellation: arity, hole arity, fold rules

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

    def spanning_tree(self, root: int = 0) -> SpanningTree:
        """Breadth-first spanning tree of the tile graph from ``root``."""
        return _spanning_tree(self, root)

    def even_tiles(self) -> np.ndarray:
        return self.tile_color == self.parity

    @property
    def arity(self) -> int:
        """Corners per tile."""
        return int(self.tiles.shape[1])

    @property
    def states(self) -> tuple[int, ...]:
        return tessellation(self.kind).states

    def fold(self, state: int) -> FoldRule:
        return self._folds[tessellation(self.kind).check_state(state)]

    @cached_property
    def _folds(self) -> dict[int, FoldRule]:
        rule = tessellation(self.kind).fold_rule
        return {s: rule(self, s) for s in self.states}


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
    return SpanningTree(
        root, children, parents, hinges, depth[children], top.hinge_tiles[hinges, 0] == parents
    )


def derive_topology(
    tiles: np.ndarray, n_nodes: int, parity: int = 0, kind: str = DEFAULT_KIND
) -> Topology:
    """Derive hinges, holes and fold rules from CCW tiles of the tessellation ``kind``.

    Raises :class:`PatternError` naming the first inconsistency: a node used by
    three or more tiles, two tiles sharing an edge, a disconnected pattern, a
    tile graph that is not two-colourable, or a face that is not a hole of the kind.
    """
    tess = tessellation(kind)
    tiles, use = _checked_tiles(tiles, n_nodes, parity, tess)
    hinge_node, hinge_tiles, hinge_corner = _hinges(tiles, use)
    color = _two_colouring(hinge_tiles, len(tiles))
    holes = _holes(tiles, n_nodes, hinge_node, hinge_tiles, hinge_corner, kind, tess.hole_arity)
    return Topology(
        tiles=tiles,
        n_nodes=int(n_nodes),
        hinge_node=hinge_node,
        hinge_tiles=hinge_tiles,
        hinge_corner=hinge_corner,
        free_nodes=np.flatnonzero(use == 1),
        tile_color=color,
        parity=int(parity),
        kind=kind,
        **holes,
    )


def _checked_tiles(
    tiles: np.ndarray, n_nodes: int, parity: int, tess: Tessellation
) -> tuple[np.ndarray, np.ndarray]:
    """The tiles as an int array and how many tiles use each node, or :class:`PatternError` on the
    first malformed tile or node use."""
    n = tess.arity
    tiles = np.asarray(tiles, dtype=np.int64)
    if len(tiles) == 0:
        raise PatternError("the pattern has no tiles")
    if tiles.ndim != 2 or tiles.shape[1] != n:
        raise PatternError(
            f"tiles must be {tess.tile_noun}s ({n} node indices each), got shape {tiles.shape}"
        )
    if tiles.min() < 0 or tiles.max() >= n_nodes:
        bad = int(np.flatnonzero((tiles < 0).any(1) | (tiles >= n_nodes).any(1))[0])
        raise PatternError(
            f"tile {bad} references node {tiles[bad].tolist()} outside 0..{n_nodes - 1}"
        )
    srt = np.sort(tiles, axis=1)
    dup = (srt[:, 1:] == srt[:, :-1]).any(1)
    if dup.any():
        bad = int(np.flatnonzero(dup)[0])
        raise PatternError(f"tile {bad} uses the same node twice: {tiles[bad].tolist()}")
    if parity not in (0, 1):
        raise PatternError(f"parity must be 0 or 1, not {parity!r}")
    use = np.bincount(tiles.ravel(), minlength=n_nodes)
    if (use > 2).any():
        bad = int(np.flatnonzero(use > 2)[0])
        who = sorted({int(t) for t in np.flatnonzero((tiles == bad).any(1))})
        raise PatternError(
            f"node {bad} is shared by {use[bad]} tiles {who}; a hinge joins exactly two"
        )
    if (use == 0).any():
        raise PatternError(f"node {int(np.flatnonzero(use == 0)[0])} is not used by any tile")
    return tiles, use


def _hinges(tiles: np.ndarray, use: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Hinge nodes (used by two tiles), their tiles ``A < B`` and the hinge's corner in each."""
    T, n = tiles.shape
    flat = tiles.ravel()
    order = np.argsort(flat, kind="stable")
    first = np.searchsorted(flat[order], np.arange(len(use)))
    hinge_node = np.flatnonzero(use == 2)
    i0, i1 = order[first[hinge_node]], order[first[hinge_node] + 1]
    hinge_tiles = np.stack([i0 // n, i1 // n], -1)
    hinge_corner = np.stack([i0 % n, i1 % n], -1)
    swap = hinge_tiles[:, 0] > hinge_tiles[:, 1]
    hinge_tiles[swap] = hinge_tiles[swap][:, ::-1]
    hinge_corner[swap] = hinge_corner[swap][:, ::-1]
    # Two tiles may share one node only: a shared edge is not a kirigami cut.
    if len(hinge_node):
        key = hinge_tiles[:, 0] * T + hinge_tiles[:, 1]
        uniq, counts = np.unique(key, return_counts=True)
        if (counts > 1).any():
            k = uniq[counts > 1][0]
            raise PatternError(
                f"tiles {k // T} and {k % T} share more than one node (an uncut edge)"
            )
    return hinge_node, hinge_tiles, hinge_corner


def _two_colouring(hinge_tiles: np.ndarray, T: int) -> np.ndarray:
    """The tile graph's bipartite colouring (tile 0 has colour 0); it must be connected and bipartite."""
    H = len(hinge_tiles)
    adj = sparse.csr_matrix(
        (
            np.ones(2 * H),
            (
                np.r_[hinge_tiles[:, 0], hinge_tiles[:, 1]],
                np.r_[hinge_tiles[:, 1], hinge_tiles[:, 0]],
            ),
        ),
        shape=(T, T),
    )
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
            f"tiles {a} and {b} close an odd cycle of tiles: a kirigami tile graph is two-coloured"
        )
    return color


def _holes(tiles, n_nodes, hinge_node, hinge_tiles, hinge_corner, kind: str, m: int) -> dict:
    """The bounded faces of the cut (``hole_*`` arrays, ``m`` corners each) and each gap's hole.

    Faces are found by following tile edges backwards with the face on the left: half-edge
    ``n*t+k`` is the edge of tile ``t`` from corner ``k`` to ``k+1``, walked from ``k+1`` to ``k``;
    at a hinge the walk continues on the other tile, at a free corner on the same one.
    """
    T, n = tiles.shape
    H = len(hinge_node)
    he = np.arange(n * T)
    t_of, k_of = he // n, he % n
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
    nxt = n * other_t + (other_k + n - 1) % n
    perm = sparse.csr_matrix((np.ones(n * T), (he, nxt)), shape=(n * T, n * T))
    n_faces, face_of = csgraph.connected_components(perm, directed=True, connection="strong")
    face_size = np.bincount(face_of, minlength=n_faces)
    face_free = np.bincount(face_of, weights=(~is_h).astype(float), minlength=n_faces) > 0
    gap_idx = np.where(arrives_on_A, 1, 0)  # which gap of the hinge the half-edge's face fills

    bounded = np.flatnonzero(~face_free)
    bad = bounded[face_size[bounded] != m]
    if len(bad):
        raise PatternError(
            f"the cut has a hole with {face_size[bad[0]]} corners; {kind} kirigami holes have {m}"
        )
    # order holes by their smallest half-edge, walk m steps from it
    first_he = np.full(n_faces, n * T, dtype=np.int64)
    np.minimum.at(first_he, face_of, he)
    hole_faces = bounded[np.argsort(first_he[bounded], kind="stable")]
    K = len(hole_faces)
    hole_index = np.full(n_faces, -1, dtype=np.int64)
    hole_index[hole_faces] = np.arange(K)
    walk = np.empty((K, m), dtype=np.int64)
    if K:
        walk[:, 0] = first_he[hole_faces]
        for i in range(1, m):
            walk[:, i] = nxt[walk[:, i - 1]]
    # corner c of a hole is where the walk arrives at step c; the edge from
    # corner c to corner c+1 (CCW) is the one walked at step c+1.
    hole_tiles = t_of[np.roll(walk, -1, axis=1)]
    if K and (np.sort(hole_tiles, 1)[:, 1:] == np.sort(hole_tiles, 1)[:, :-1]).any():
        raise PatternError(
            f"a hole is bounded twice by the same tile; not a {kind} kirigami tessellation"
        )
    gap_face = np.full((H, 2), -1, dtype=np.int64)
    gap_face[h_at[is_h], gap_idx[is_h]] = hole_index[face_of[is_h]]
    return {
        "gap_face": gap_face,
        "hole_nodes": node_at[walk],
        "hole_hinges": h_at[walk],
        "hole_gap": gap_idx[walk],
        "hole_tiles": hole_tiles,
    }
