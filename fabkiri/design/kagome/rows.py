"""Rows of the kagome fit beyond the closure equalities: sides, non-overlap, symmetry.

* **Sides.** The standard R x C kagome's boundary tips lie on four sides, as a quad lattice's do: the
  bottom row's down apexes (B), the right ends of the rows (R), the top row's up apexes (T) and the left
  ends (L). :func:`tip_sides` names each tip's side; the fit asks a tip to lie on its own arc of the
  target (``shape_match``), so tips cannot slide round a corner and bunch.
* **Non-overlap** as inequalities ``g(x) >= floor`` (rows ``min(g - floor, 0)``): both gaps at every
  hinge (the tiles beside a hinge do not overlap), and every tile's shape quality
  ``4√3 A / Σℓ²`` (1 for the equilateral triangle, 0 when it degenerates, negative when it folds
  over). The quality is scale free, so the tiles may grow and shrink.
* **Mirror symmetry** as equality rows ``x_m(i) = M x_i``. The standard lattice is mirror symmetric
  about its vertical axis when C is odd (the mirror keeps up tiles up, reverses every tile's corner
  order and so swaps the two hole pairings: state 1 of the mirror image is state 2 of the design), and
  about its horizontal axis when R is even (up tiles become down tiles; each state's pairing is kept).
  Both states are imposed, so either mirror maps the reconfigurable family onto itself and its fixed
  points are a subfamily (:func:`mirror_map` checks the pairing on the topology).
"""

from __future__ import annotations

import numpy as np
from scipy import sparse
from scipy.spatial import cKDTree

from ...pattern import conformance as pc
from ...pattern.geometry import cross2
from ...pattern.model import Pattern
from ..core.stencils import TWO_PI, Family
from .constraints import fold_gap_angles

SIDE_B, SIDE_R, SIDE_T, SIDE_L = range(4)
GAP_WRAP = np.pi / 3  # gap angles are read in [-60°, 300°): a gap closing past zero stays negative


def tip_order(pattern: Pattern) -> np.ndarray:
    """Boundary tips in counter-clockwise order."""
    top = pattern.topology
    return pc.boundary_tip_order(top.tiles, top.hole_nodes, top.hole_tiles, top.free_nodes)


def tip_sides(standard: Pattern, tips: np.ndarray) -> np.ndarray:
    """Side (0 B, 1 R, 2 T, 3 L) of each tip of a standard kagome, from the lattice's indexing: the
    left corner of a row's first tile is L, the right corner of its last tile R, any other tip is an
    apex of the bottom row (B) or of the top row (T). A lattice cut to an outline (``trimmed_from``) has
    no such rows: its tips take the side of the box they face, from the centre (:func:`facing_sides`)."""
    if "keep" in (standard.lattice or {}):
        return facing_sides(standard.nodes[tips])
    tiles = standard.topology.tiles
    cols = int((standard.lattice or {})["cols"])
    tile_of = np.full(standard.topology.n_nodes, -1)
    corner_of = np.full(standard.topology.n_nodes, -1)
    t, k = np.divmod(np.arange(tiles.size), 3)
    tile_of[tiles.ravel()], corner_of[tiles.ravel()] = t, k  # a tip has one tile
    t, k = tile_of[tips], corner_of[tips]
    r, c = np.divmod(t, cols)
    up = (r + c) % 2 == 0
    right_corner = np.where(up, 1, 2)  # CCW: up (left, right, apex), down (left, apex, right)
    side = np.where(r == 0, SIDE_B, SIDE_T)
    side = np.where((c == 0) & (k == 0), SIDE_L, side)
    side = np.where((c == cols - 1) & (k == right_corner), SIDE_R, side)
    return side.astype(np.int64)


def facing_sides(x: np.ndarray) -> np.ndarray:
    """Side (0 B, 1 R, 2 T, 3 L) of each point by the box side it faces from the box's centre: the
    diagonals of the bounding box split the points into four runs, in order round a star-shaped outline."""
    lo, hi = x.min(0), x.max(0)
    p = (x - 0.5 * (lo + hi)) / np.maximum(0.5 * (hi - lo), 1e-300)
    vertical = np.abs(p[:, 1]) >= np.abs(p[:, 0])
    side = np.where(
        vertical, np.where(p[:, 1] < 0, SIDE_B, SIDE_T), np.where(p[:, 0] > 0, SIDE_R, SIDE_L)
    )
    return side.astype(np.int64)


def gap_family(
    pattern: Pattern, floor: float, convex: float | None = None, hole_floor: float | None = None
) -> Family:
    """Both gaps at every hinge at least ``floor`` (rad): rows ``min(gap - floor, 0)``; ``hole_floor``
    (default ``floor``) instead for a gap that is a hole's corner; with ``convex``, every gap that is a
    hole's corner also at most ``π - convex`` (convex holes: a tile cannot cross a hole to overlap the
    tile opposite, which the gaps alone allow)."""
    top = pattern.topology
    nv = top.n_nodes
    H = np.arange(top.n_hinges)
    lo = floor if hole_floor is None else hole_floor
    floors = {s: np.where(top.gap_face[H, top.fold(s).fold_gap] >= 0, lo, floor) for s in (1, 2)}

    def fn(x):
        rs, nodes, grads = [], [], []
        for s in (1, 2):  # state s folds one of the hinge's two gaps: together they are both
            th, nd, g = fold_gap_angles(pattern, s, x)
            th = np.mod(th + GAP_WRAP, TWO_PI) - GAP_WRAP
            act = th < floors[s]
            rs.append(np.where(act, th - floors[s], 0.0))
            nodes.append(nd)
            grads.append(g * act[:, None, None])
            if convex is not None:
                hole = top.gap_face[H, top.fold(s).fold_gap] >= 0
                over = hole & (th > np.pi - convex)
                rs.append(np.where(over, np.pi - convex - th, 0.0))
                nodes.append(nd)
                grads.append(-g * over[:, None, None])
        return np.concatenate(rs), (np.concatenate(nodes), np.concatenate(grads))

    return Family("hinge_gaps", "ineq", fn, 0, nv=nv)


def tile_quality(x: np.ndarray, tiles: np.ndarray):
    """``4√3 A / Σℓ²`` of every triangle and its gradient (nodes = the tile's corners)."""
    p = x[tiles]  # (T, 3, 2)
    e = np.roll(p, -1, 1) - p  # edge k: corner k -> k + 1
    A = 0.5 * cross2(e[:, 0], -e[:, 2])
    S = (e * e).sum((1, 2))
    c = 4.0 * np.sqrt(3.0)
    q = c * A / S
    # dA/dp_k = ½ perp(p_{k+1} - p_{k-1}) rotated: ½ (y_{k+1} - y_{k-1}, x_{k-1} - x_{k+1})
    nxt, prv = np.roll(p, -1, 1), np.roll(p, 1, 1)
    dA = 0.5 * np.stack([nxt[..., 1] - prv[..., 1], prv[..., 0] - nxt[..., 0]], -1)
    dS = 2.0 * (e[:, [2, 0, 1]] - e)  # p_k enters edge k-1 with + and edge k with -
    g = c * (dA * S[:, None, None] - A[:, None, None] * dS) / S[:, None, None] ** 2
    return q, g


def quality_family(pattern: Pattern, floor: float) -> Family:
    """Every tile's shape quality at least ``floor``: rows ``min(q - floor, 0)``."""
    top = pattern.topology
    tiles = top.tiles

    def fn(x):
        q, g = tile_quality(x, tiles)
        act = q < floor
        return np.where(act, q - floor, 0.0), (tiles, g * act[:, None, None])

    return Family("tile_quality", "ineq", fn, 0, nv=top.n_nodes)


def mirror_map(standard: Pattern, axis: str) -> np.ndarray | None:
    """Node ``i`` -> its mirror image's node about the standard's vertical (``"y"``) or horizontal
    (``"x"``) centre line, or None when the lattice has no such symmetry: the image of every node is a
    node, every tile's image is a tile, and each state's folded gaps map onto folded gaps of one state."""
    x = standard.nodes - 0.5 * (standard.nodes.min(0) + standard.nodes.max(0))
    flip = np.array([-1.0, 1.0]) if axis == "y" else np.array([1.0, -1.0])
    d, m = cKDTree(x).query(x * flip)
    if d.max() > 1e-9 * standard.tile_size:
        return None
    top = standard.topology
    tiles = {tuple(sorted(t)) for t in top.tiles.tolist()}
    if any(tuple(sorted(m[t])) not in tiles for t in top.tiles.tolist()):
        return None
    return m if _maps_pairings(standard, m) else None


def _maps_pairings(standard: Pattern, m: np.ndarray) -> bool:
    """The mirror maps state 1's folded gaps (hinge node and the two edge ends) onto one state's."""
    top = standard.topology

    def gaps(s):
        f = top.fold(s)
        return {(h, *sorted(e)) for h, e in zip(top.hinge_node.tolist(), f.fold_ends.tolist())}

    g1 = gaps(1)
    image = {(int(m[h]), *sorted((int(m[a]), int(m[b])))) for h, a, b in g1}
    return image == g1 or image == gaps(2)


def symmetry_family(m: np.ndarray, axis: str, nv: int) -> Family:
    """``x_m(i) = M x_i`` for the mirror ``M`` about the line x = 0 (``"y"``) or y = 0 (``"x"``):
    per pair of mirror nodes one row for each coordinate, per node on the axis one row (linear)."""
    i = np.arange(len(m))
    k = 0 if axis == "y" else 1  # the coordinate that changes sign
    pair = i < m
    on = i == m
    rows, cols, vals = [], [], []
    n_pair = int(pair.sum())
    a, b = i[pair], m[pair]
    for d in range(2):  # x_b,d ∓ x_a,d = 0
        r = d * n_pair + np.arange(n_pair)
        sgn = 1.0 if d == k else -1.0
        rows += [r, r]
        cols += [2 * b + d, 2 * a + d]
        vals += [np.ones(n_pair), np.full(n_pair, sgn)]
    c = i[on]
    rows.append(2 * n_pair + np.arange(len(c)))
    cols.append(2 * c + k)
    vals.append(np.ones(len(c)))
    J = sparse.csr_matrix(
        (np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
        shape=(2 * n_pair + len(c), 2 * nv),
    )

    def fn(x):
        return J @ x.ravel(), J

    return Family(f"mirror_{axis}", "eq", fn, 1, nv=nv)


def partial_fans(standard: Pattern) -> list[tuple[np.ndarray, np.ndarray]]:
    """The boundary fans of both closed states: ``(tiles, corners)`` of the tile corners that meet at one
    point of a closed state with less than a full turn between them. A full fan is a hole's ring (an
    equality); a partial one lies on the outline, where a row's end tile hangs on a single hinge, and its
    angles must leave room: their sum at most 2π, or the end tile overlaps the next row's in that state.
    Found on the standard lattice's closed states (ψ = 0° and 120°), where the meeting corners coincide."""
    from ...pattern.kinds.kagome.lattice import OPEN_DEG, kagome_corners

    lat = standard.lattice or {}
    rows, cols = (int(v) for v in lat.get("trimmed_from", (lat.get("rows"), lat.get("cols"))))
    keep = np.asarray(
        lat.get("keep", np.arange(rows * cols)), dtype=np.int64
    )  # a cut lattice's tiles
    out = []
    for psi in (0.0, 2.0 * OPEN_DEG):
        pts = kagome_corners(rows, cols, np.radians(psi))[keep].reshape(-1, 2)
        key = np.rint(pts * 1e6).astype(np.int64)
        _, inv, cnt = np.unique(key, axis=0, return_inverse=True, return_counts=True)
        inv = inv.ravel()
        for g in np.flatnonzero(cnt >= 3):  # three or more corners meet (a hinge alone is two)
            t, k = np.divmod(np.flatnonzero(inv == g), 3)
            if len(t) < 6:
                out.append((t, k))
    return out


def fan_family(standard: Pattern, floor: float) -> Family:
    """Every boundary fan's angle sum at most ``2π - floor``: rows ``min(2π - floor - Σθ, 0)``."""
    from ..core.stencils import corner_angle

    top = standard.topology
    fans = partial_fans(standard)
    t = np.concatenate([f[0] for f in fans]) if fans else np.zeros(0, np.int64)
    k = np.concatenate([f[1] for f in fans]) if fans else np.zeros(0, np.int64)
    fan = np.repeat(np.arange(len(fans)), [len(f[0]) for f in fans])
    width = max((len(f[0]) for f in fans), default=0)
    slot = np.arange(len(t)) - np.repeat(
        np.cumsum([0] + [len(f[0]) for f in fans])[:-1], [len(f[0]) for f in fans]
    )

    def fn(x):
        th, nodes, g = corner_angle(x, top.tiles, t, k)
        S = np.bincount(fan, th, minlength=len(fans))
        act = S > TWO_PI - floor
        nd = np.zeros((len(fans), 3 * width), np.int64)
        gr = np.zeros((len(fans), 3 * width, 2))
        for j in range(3):
            nd[fan, 3 * slot + j] = nodes[:, j]
            gr[fan, 3 * slot + j] = -g[:, j] * act[fan, None]
        return np.where(act, TWO_PI - floor - S, 0.0), (nd, gr)

    # not while landing on the family: the start may have a folded tile, whose angles wrap past 2π
    return Family("boundary_fans", "ineq", fn, 0, meta={"land": False}, nv=top.n_nodes)
