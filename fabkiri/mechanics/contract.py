"""The two closed states of a pattern by breadth-first rigid placement.

The method: docs/algorithm.md#contraction.

Every tile is moved by a proper rigid motion ``Y = Rot(φ_T) x + t_T``. Going from
a placed tile A to its neighbour B through hinge h, B turns about h until the
edge bounding the gap that folds in this state lies on A's matching edge:

    φ_B = φ_A + δ_h,   δ_h = signed angle from (x_b - x_h) to (x_a - x_h),

where a and b are the far ends of the two edges bounding the folded gap. Only
directions are matched, so parallelogram holes (unequal fold edges, straight
slits with T-junctions) contract the same way. Conflicting placements are never
averaged: each hole's loop of four tiles is composed locally and its mismatch is
the **loop-closure error** of that hole.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..pattern import geometry
from ..pattern.model import Pattern


@dataclass(frozen=True, eq=False)
class Contraction:
    """One closed state computed from the deployed state.

    ``corners`` are the per-tile placed corners (mm), normalised so the tile
    centres best match the deployed tile centres (proper rotation, same
    centroid). ``hole_closure`` is each hole's loop-closure error (mm).
    """

    state: int
    corners: np.ndarray
    hole_closure: np.ndarray
    root: int

    @property
    def max_closure(self) -> float:
        return float(self.hole_closure.max(initial=0.0))

    @property
    def worst_hole(self) -> int | None:
        return int(np.argmax(self.hole_closure)) if len(self.hole_closure) else None


def hinge_turns(pattern: Pattern, state: int) -> np.ndarray:
    """δ_h for every hinge: the turn of tile B relative to tile A in ``state``."""
    top = pattern.topology
    fold = top.fold(state)
    x = pattern.nodes
    h = x[top.hinge_node]
    va = x[fold.fold_ends[:, 0]] - h
    vb = x[fold.fold_ends[:, 1]] - h
    return geometry.signed_angle(vb, va)


def _step(phi_a, t_a, delta, hinge_xy):
    """Pose of the next tile through a hinge, vectorised."""
    phi_b = phi_a + delta
    t_b = geometry.rotate(hinge_xy, phi_a) + t_a - geometry.rotate(hinge_xy, phi_b)
    return phi_b, t_b


def hole_closure(pattern: Pattern, state: int, delta: np.ndarray | None = None) -> np.ndarray:
    """Loop-closure error (mm) of every hole in ``state``.

    Starting from the tile owning the hole's first edge, the four tiles around
    the hole are placed through its four corner hinges; the error is the largest
    corner displacement of the first tile after the full loop.
    """
    top = pattern.topology
    K = top.n_holes
    if K == 0:
        return np.zeros(0)
    if delta is None:
        delta = hinge_turns(pattern, state)
    x = pattern.nodes
    tiles_around = top.hole_tiles  # tile owning edge c -> c+1
    m = top.hole_hinges.shape[1]  # corners per hole (the tessellation's hole arity)
    phi = np.zeros(K)
    t = np.zeros((K, 2))
    for c in range(m):
        # corner c+1 joins tile owning edge c with tile owning edge c+1
        hinge = top.hole_hinges[:, (c + 1) % m]
        frm = tiles_around[:, c]
        sign = np.where(top.hinge_tiles[hinge, 0] == frm, 1.0, -1.0)
        phi, t = _step(phi, t, sign * delta[hinge], x[top.hinge_node[hinge]])
    first = x[top.tiles[tiles_around[:, 0]]]  # (K, n, 2)
    moved = geometry.rotate(first, phi[:, None]) + t[:, None, :]
    return np.linalg.norm(moved - first, axis=-1).max(axis=1)


def contract(pattern: Pattern, state: int) -> Contraction:
    """Closed state ``state`` (1 or 2) by breadth-first rigid placement."""
    top = pattern.topology
    top.fold(state)  # ValueError naming the kind's states
    centres = pattern.nodes[top.tiles].mean(axis=1)
    root = int(np.argmin(np.linalg.norm(centres - centres.mean(0), axis=1)))
    x = pattern.nodes - centres[root]  # local frame keeps rounding small far from the origin
    corners = x[top.tiles]
    delta = hinge_turns(pattern, state)

    T = top.n_tiles
    phi = np.zeros(T)
    t = np.zeros((T, 2))
    tree = top.spanning_tree(root)
    sign = np.where(tree.parent_is_a, 1.0, -1.0)
    hxy = x[top.hinge_node[tree.hinges]]
    for sel in tree.levels():
        p, c = tree.parents[sel], tree.children[sel]
        phi[c], t[c] = _step(phi[p], t[p], sign[sel] * delta[tree.hinges[sel]], hxy[sel])
    placed = geometry.rotate(corners, phi[:, None]) + t[:, None, :]
    theta, shift = geometry.kabsch(placed.mean(axis=1), centres)  # back to the mm frame
    placed = geometry.rotate(placed, theta) + shift
    return Contraction(
        state=state, corners=placed, hole_closure=hole_closure(pattern, state, delta), root=root
    )


def placed_through_hinge(
    pattern: Pattern, state: int, hinges: np.ndarray, frm: np.ndarray
) -> np.ndarray:
    """The corners (mm) of the tile across each hinge of ``hinges`` from the tile ``frm``, in closed state ``state``
    with ``frm`` left where it is deployed: one hinge turn, the pair's own relative pose. ``contract`` places a
    tile through the spanning tree's path from its root, so two neighbours on different branches differ by the
    loop closures of every hole between the branches as well (the rigid 128x128 bean: neighbours' shared corners
    apart by 1.1e-9 tile sizes, each hole closing within 1e-11)."""
    top = pattern.topology
    a, b = top.hinge_tiles[hinges].T
    other = np.where(a == frm, b, a)
    sign = np.where(a == frm, 1.0, -1.0)
    h = pattern.nodes[top.hinge_node[hinges]][:, None, :]
    phi = (sign * hinge_turns(pattern, state)[hinges])[:, None]
    return geometry.rotate(pattern.nodes[top.tiles[other]] - h, phi) + h


def contract_both(pattern: Pattern) -> dict[int, Contraction]:
    return {s: contract(pattern, s) for s in pattern.topology.states}


def with_contracted_states(pattern: Pattern) -> Pattern:
    """The pattern with both closed states computed and stored."""
    both = contract_both(pattern)
    return pattern.with_contracted({s: c.corners for s, c in both.items()})


def adopt_state_labels(pattern: Pattern) -> Pattern:
    """Choose the fold parity so computed state 1 is the supplied state 1.

    Which closed state is called "1" is a convention; when a pattern arrives
    with its closed states (e.g. OBJ files from another tool), theirs wins.
    Only the stored state 1 (or, alone, state 2) is consulted.
    """
    if not pattern.contracted:
        return pattern
    label = min(pattern.contracted)
    supplied = pattern.contracted[label]
    other = 3 - label
    keep = geometry.aligned_distance(contract(pattern, label).corners, supplied)
    swap = geometry.aligned_distance(contract(pattern, other).corners, supplied)
    return pattern.with_parity(1 - pattern.parity) if swap < keep else pattern
