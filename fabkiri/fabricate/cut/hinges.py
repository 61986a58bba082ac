"""Hinge kinds: from a closed state to cut geometry (docs/fabrication.md#hinge-kinds).

* ``tape`` — tiles cut in place; every shared cut line is cut once
  (:func:`tape_linework`); tape joins the tiles, one hinge of every coincident
  pair on the top face and the other on the bottom (:func:`assign_faces`).
* ``ligament`` — one sheet: tiles shrunk by gap/2 (mitre) and joined by strips
  sized by the strain rule ε ≈ w·Δθ/(2L) (:func:`ligament_strips`).
* ``separate`` — loose tiles, each offset outward by kerf/2 (mitre).

All offsets are GEOS buffers through shapely. Coordinates are millimetres.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import shapely
from scipy import sparse
from scipy.sparse import csgraph

from ...errors import FabricationError
from ...kdtree import KDTree
from ...pattern import thinness as fab
from ...pattern.kinds.tessellation import tessellation
from ...pattern.model import Pattern

GRID = 1e-6  # mm: every coordinate written is snapped to this grid
MITRE_LIMIT = 10.0  # exact kerf offsets down to 11.5° corners (shapely default 5: 23°)
FACES = ("T", "B")


def hinge_points(pattern: Pattern, corners: np.ndarray) -> np.ndarray:
    """Position of every hinge in a placed state: tile A's corner at the hinge node."""
    top = pattern.topology
    return corners[top.hinge_tiles[:, 0], top.hinge_corner[:, 0]]


def coincident_pairs(points: np.ndarray, eps: float) -> np.ndarray:
    """Index pairs ``(i, j)``, ``i < j``, of points closer than ``eps``."""
    if len(points) < 2:
        return np.zeros((0, 2), dtype=np.int64)
    return KDTree(points).query_pairs(eps, output_type="ndarray").astype(np.int64)


@dataclass(frozen=True)
class FaceAssignment:
    """Tape face of every hinge: 0 = top (T), 1 = bottom (B).

    Hinges that coincide in a closed state must go on opposite faces, or the
    tape of one would glue the other pair of tiles together. ``conflicts``
    counts coincident pairs that still share a face (an odd cycle of
    coincidences; 0 for every pattern seen so far).
    """

    face: np.ndarray
    pairs: np.ndarray
    conflicts: int

    def letters(self) -> list[str]:
        return [FACES[int(f)] for f in self.face]


def assign_faces(
    pattern: Pattern, states: dict[int, np.ndarray], apart: np.ndarray | None = None
) -> FaceAssignment:
    """Two-colour the graph "hinges coincide in some closed state" by BFS depth; where that graph has
    odd cycles (three kagome hinges at a point), with the fewest conflicts local flips reach, also
    keeping the hinge pairs ``apart`` (printed strips too close for one face) on opposite faces
    where the flips can (they weigh as a lone coincident pair; not counted as conflicts)."""
    H = pattern.topology.n_hinges
    eps = 1e-6 * pattern.tile_size
    per_state = [coincident_pairs(hinge_points(pattern, c), eps) for c in states.values()]
    pairs = np.unique(
        np.concatenate(per_state) if per_state else np.zeros((0, 2), np.int64), axis=0
    )
    face = np.zeros(H, dtype=np.int64)
    if len(pairs) and H:
        g = sparse.coo_matrix(
            (np.ones(len(pairs)), (pairs[:, 0], pairs[:, 1])), shape=(H, H)
        ).tocsr()
        n, comp = csgraph.connected_components(g, directed=False)
        for c in range(n):
            members = np.flatnonzero(comp == c)
            if len(members) < 2:
                continue
            root = int(members.min())  # lowest hinge of the group gets the top face
            order, pred = csgraph.breadth_first_order(
                g, root, directed=False, return_predecessors=True
            )
            for node in order[1:]:
                face[node] = 1 - face[pred[node]]
    conflicts = int((face[pairs[:, 0]] == face[pairs[:, 1]]).sum()) if len(pairs) else 0
    if conflicts:  # an odd cycle: BFS depth need not give the fewest conflicts
        face = _fewer_conflicts(face, per_state + ([] if apart is None else [apart]), H)
        conflicts = int((face[pairs[:, 0]] == face[pairs[:, 1]]).sum())
    return FaceAssignment(face=face, pairs=pairs, conflicts=conflicts)


def _fewer_conflicts(face: np.ndarray, per_state: list[np.ndarray], H: int) -> np.ndarray:
    """Flip, in hinge order, every hinge whose same-face coincident hinges outweigh the others, until
    none does. A hinge of a point that carries only two (which opposite faces always separate) weighs
    3, more than a hinge can gain in a group of three (2), so those pairs are separated first. Each
    flip lowers the weighted conflicts, so this ends; deterministic, so the files are too."""
    rows, cols, weights = [], [], []
    for pr in per_state:
        deg = np.bincount(pr.ravel(), minlength=H)
        w = np.where((deg[pr[:, 0]] == 1) & (deg[pr[:, 1]] == 1), 3.0, 1.0)
        rows += [pr[:, 0], pr[:, 1]]
        cols += [pr[:, 1], pr[:, 0]]
        weights += [w, w]
    g = sparse.csr_matrix(
        (np.concatenate(weights), (np.concatenate(rows), np.concatenate(cols))), shape=(H, H)
    )
    face = face.copy()
    changed = True
    while changed:
        changed = False
        for h in range(H):
            nb, w = g.indices[g.indptr[h] : g.indptr[h + 1]], g.data[g.indptr[h] : g.indptr[h + 1]]
            same = float(w[face[nb] == face[h]].sum())
            if 2 * same > float(w.sum()):
                face[h] = 1 - face[h]
                changed = True
    return face


def closure_pairs(pattern: Pattern, state: int) -> np.ndarray:
    """Flat corner ids ``n t + k`` (``n`` the tile arity) that meet in a closed state by construction.

    The two corners of every hinge, and the far ends of the two edges that
    fold onto each other in ``state``.
    """
    top = pattern.topology
    A, B = top.hinge_tiles.T
    cA, cB = top.hinge_corner.T
    ends = top.fold(state).fold_corner_ends
    n = tessellation(pattern.kind).arity
    return np.concatenate(
        [
            np.stack([n * A + cA, n * B + cB], 1),
            np.stack([n * A + ends[:, 0], n * B + ends[:, 1]], 1),
        ]
    )


def snap_corners(corners: np.ndarray, eps: float, pairs: np.ndarray | None = None) -> np.ndarray:
    """Make nearly coincident tile corners exactly equal (lowest index wins).

    Closed states from a solver close to ~1e-9 of a tile (or worse); cut-once
    linework needs shared corners to be bit-identical before noding. With
    ``pairs`` (flat corner ids, see :func:`closure_pairs`) only those pairs
    are merged, so free corners that merely come close stay apart.
    """
    flat = corners.reshape(-1, 2)
    if pairs is None:
        pairs = coincident_pairs(flat, eps)
    else:
        pairs = pairs[np.linalg.norm(flat[pairs[:, 0]] - flat[pairs[:, 1]], axis=1) < eps]
    return _merged(flat, pairs).reshape(corners.shape)


def _merged(points: np.ndarray, pairs: np.ndarray) -> np.ndarray:
    """Points with every connected group of ``pairs`` replaced by its lowest-index member."""
    if len(pairs) == 0:
        return points.copy()
    n = len(points)
    g = sparse.coo_matrix((np.ones(len(pairs)), (pairs[:, 0], pairs[:, 1])), shape=(n, n))
    _, label = csgraph.connected_components(g, directed=False)
    rep = np.full(label.max() + 1, n, dtype=np.int64)
    np.minimum.at(rep, label, np.arange(n))
    return points[rep[label]]


def snap_to_edges(corners: np.ndarray, eps: float) -> np.ndarray:
    """Move corners lying within ``eps`` of another tile's edge onto that edge.

    A solver's closed state may leave a corner a hair off the edge it should
    meet (a T-junction); cut once, that would enclose a sliver of scrap.
    """
    T = len(corners)
    flat = corners.reshape(-1, 2).copy()
    seg = np.stack([corners, np.roll(corners, -1, axis=1)], 2).reshape(-1, 2, 2)
    tree = shapely.STRtree(shapely.linestrings(seg))
    pi, ei = tree.query(shapely.points(flat), predicate="dwithin", distance=eps)
    n = corners.shape[1]  # the tile arity: flat point and edge ids are n t + k
    keep = (pi // n) != (ei // n)
    pi, ei = pi[keep], ei[keep]
    if len(pi) == 0 or T == 0:
        return corners.copy()
    a, b = seg[ei, 0], seg[ei, 1]
    d = b - a
    L2 = np.maximum((d * d).sum(1), 1e-300)
    t = ((flat[pi] - a) * d).sum(1) / L2
    foot = a + t[:, None] * d
    off = np.linalg.norm(flat[pi] - foot, axis=1)
    near_end = (
        np.minimum(np.linalg.norm(flat[pi] - a, axis=1), np.linalg.norm(flat[pi] - b, axis=1)) < eps
    )
    move = (t > 0) & (t < 1) & (off > 0) & ~near_end
    order = np.lexsort((ei[move], pi[move]))
    done = set()
    for i in np.flatnonzero(move)[order]:
        if pi[i] not in done:  # one edge per corner, the lowest-numbered
            flat[pi[i]] = foot[i]
            done.add(pi[i])
    return flat.reshape(corners.shape)


def _chain(segments: np.ndarray, straight_only: bool) -> list[tuple[np.ndarray, bool]]:
    """Chain 2-point segments into polylines.

    Segments continue through nodes of degree 2 and, where several lines
    cross, straight on (so a grid line is one polyline, not one per cell);
    with ``straight_only`` False (outlines) they pair up by angle instead.
    Returns ``(points, closed)`` pairs in a deterministic order.
    """
    if len(segments) == 0:
        return []
    pts = segments.reshape(-1, 2)
    keys, node = np.unique(np.round(pts / GRID).astype(np.int64), axis=0, return_inverse=True)
    node = node.reshape(-1, 2)
    xy = keys.astype(float) * GRID
    S = len(node)
    # half-edge 2*s leaves node[s,0], 2*s+1 leaves node[s,1]
    he_from = node.ravel()
    he_to = node[:, ::-1].ravel()
    d = xy[he_to] - xy[he_from]
    ang = np.arctan2(d[:, 1], d[:, 0])
    partner = _partners(he_from, ang, len(xy), straight_only)
    seen = np.zeros(S, dtype=bool)
    out = []

    def walk(h):  # follow half-edge h and its straight/degree-2 continuations
        nodes = [he_from[h], he_to[h]]
        seen[h // 2] = True
        while True:
            nxt = partner[h ^ 1]  # leaves the node h arrives at, along the next segment
            if nxt < 0 or seen[nxt // 2]:
                return nodes
            h = nxt
            seen[h // 2] = True
            nodes.append(he_to[h])

    for h in range(2 * S):  # open chains start at their ends
        if not seen[h // 2] and partner[h] < 0:
            out.append((xy[walk(h)], False))
    for s in range(S):  # what is left are loops
        if not seen[s]:
            nodes = walk(2 * s)
            closed = nodes[0] == nodes[-1]
            out.append((xy[nodes[:-1]] if closed else xy[nodes], closed))
    return out


def _partners(
    he_from: np.ndarray, ang: np.ndarray, n_nodes: int, straight_only: bool
) -> np.ndarray:
    """For each half-edge, the half-edge a chain arriving along it continues by (-1: the chain ends there)."""
    partner = np.full(
        len(he_from), -1, dtype=np.int64
    )  # half-edge arriving straight-through continues as partner
    order = np.argsort(he_from, kind="stable")
    starts = np.searchsorted(he_from[order], np.arange(n_nodes))
    ends = np.append(starts[1:], len(order))
    for v in range(n_nodes):
        hs = order[starts[v] : ends[v]]
        if len(hs) == 2:
            partner[hs[0]], partner[hs[1]] = hs[1], hs[0]
        elif (
            len(hs) > 2 and not straight_only
        ):  # an outline touching itself: pair neighbours by angle
            hs = hs[np.argsort(ang[hs], kind="stable")]
            for i in range(0, len(hs) - 1, 2):
                partner[hs[i]], partner[hs[i + 1]] = hs[i + 1], hs[i]
        elif len(hs) > 2:
            _pair_straight(hs, ang, partner)
    return partner


def _pair_straight(hs: np.ndarray, ang: np.ndarray, partner: np.ndarray) -> None:
    """Pair the half-edges ``hs`` leaving one node that continue each other straight on (a grid crossing)."""
    used: set[int] = set()  # hinge ends already paired
    for i in range(len(hs)):
        if hs[i] in used:
            continue
        for j in range(i + 1, len(hs)):
            if hs[j] in used:
                continue
            diff = abs(((ang[hs[i]] - ang[hs[j]]) % (2 * np.pi)) - np.pi)
            if diff < 1e-7:
                partner[hs[i]], partner[hs[j]] = hs[j], hs[i]
                used.update((hs[i], hs[j]))
                break


def _segments_of(geom: shapely.Geometry) -> np.ndarray:
    """All 2-point segments of a (multi)linestring, ``(n, 2, 2)``."""
    coords, idx = shapely.get_coordinates(shapely.get_parts(geom), return_index=True)
    same = idx[1:] == idx[:-1]
    return np.stack([coords[:-1][same], coords[1:][same]], 1)


WELD_GRIDS = 4  # noded points this many grid steps apart are one point


def _welded(segs: np.ndarray) -> np.ndarray:
    """Segments with their ends welded (within ``WELD_GRIDS`` grid steps, lowest index wins),
    zero-length and repeated segments dropped.

    Snap-rounding nodes a T-junction where a corner lies within 1e-7 mm of another tile's
    edge; the junction and the corner can round to neighbouring grid points, and the edge they
    share is then cut twice 1e-6 mm apart, enclosing a sliver piece (the additive-kirigami
    random triple at 10 mm tiles: 122 pieces for 121 tiles)."""
    pts = segs.reshape(-1, 2)
    pts = _merged(pts, coincident_pairs(pts, WELD_GRIDS * GRID))
    return _once(_split_at_near_points(pts.reshape(-1, 2, 2), WELD_GRIDS * GRID))


def _once(segs: np.ndarray) -> np.ndarray:
    """Each segment once, whichever way round it was given (first occurrence kept, in order)."""
    a, b = segs[:, 0], segs[:, 1]
    swap = (a[:, 0] > b[:, 0]) | ((a[:, 0] == b[:, 0]) & (a[:, 1] > b[:, 1]))
    key = np.concatenate([np.where(swap[:, None], b, a), np.where(swap[:, None], a, b)], 1)
    _, first = np.unique(key, axis=0, return_index=True)
    return segs[np.sort(first)]


def _split_at_near_points(segs: np.ndarray, w: float) -> np.ndarray:
    """Segments split at every segment end lying within ``w`` of their interior (a node the
    snap-rounding left a grid step off the segment it should split), zero-length ones dropped."""
    segs = segs[np.linalg.norm(segs[:, 1] - segs[:, 0], axis=1) > 0]
    pts = np.unique(segs.reshape(-1, 2), axis=0)
    si, pi = shapely.STRtree(shapely.linestrings(segs)).query(
        shapely.points(pts), predicate="dwithin", distance=w
    )[::-1]
    a, d = segs[si, 0], segs[si, 1] - segs[si, 0]
    t = np.einsum("ij,ij->i", pts[pi] - a, d) / np.einsum("ij,ij->i", d, d)
    inner = (np.linalg.norm(pts[pi] - segs[si, 0], axis=1) > w) & (
        np.linalg.norm(pts[pi] - segs[si, 1], axis=1) > w
    )
    si, pi, t = si[inner], pi[inner], t[inner]
    if not len(si):
        return segs
    out = [segs[np.setdiff1d(np.arange(len(segs)), si)]]
    for k in np.unique(si):
        mine = si == k
        chain = np.vstack([segs[k, :1], pts[pi[mine]][np.argsort(t[mine])], segs[k, 1:]])
        out.append(np.stack([chain[:-1], chain[1:]], 1))
    return np.concatenate(out)


def tape_linework(corners: np.ndarray) -> tuple[list[np.ndarray], list[np.ndarray]]:
    """Cut-once linework of tiles placed edge to edge.

    Returns ``(rings, lines)``: closed boundary loops of the union (cut last)
    and the open interior lines shared by two tiles, each cut once. Tile
    corners must already be snapped (:func:`snap_corners`); noding at
    T-junctions uses snap-rounding on the 1e-6 mm grid.
    """
    seg = np.stack([corners, np.roll(corners, -1, axis=1)], 2).reshape(-1, 2, 2)
    # an edge shared by two tiles is the same segment twice (corners are snapped): node it once
    lines = shapely.linestrings(_once(seg))
    noded = shapely.union_all(lines, grid_size=GRID)
    segs = _welded(_segments_of(noded))
    mids = shapely.points(segs.mean(axis=1))
    tree = shapely.STRtree(shapely.boundary(shapely.polygons(corners)))
    hit_seg, _ = tree.query(mids, predicate="dwithin", distance=10 * GRID)
    count = np.bincount(hit_seg, minlength=len(segs))
    boundary = segs[count == 1]
    interior = segs[count >= 2]
    rings = [p for p, closed in _chain(boundary, False) if closed]
    open_b = [p for p, closed in _chain(boundary, False) if not closed]
    if open_b:
        raise FabricationError(
            "the outline of the closed state is not a closed loop (tiles overlap or gap)"
        )
    chains = _chain(interior, True)
    inner = [p for p, closed in chains if not closed] + [
        np.vstack([p, p[:1]]) for p, closed in chains if closed
    ]
    return rings, inner


@dataclass(frozen=True)
class LigamentDesign:
    """Strips joining shrunk tiles: widths, free lengths and strains per hinge."""

    width_mm: float
    turn_rad: float
    lengths: np.ndarray  # (H,) free length L between the two apexes
    strains: np.ndarray  # (H,) ε = w Δθ / (2 L)
    apex: np.ndarray  # (H, 2, 2) apex of tile A and of tile B
    warnings: list[str]


def shrink_tiles(corners: np.ndarray, shrink: float) -> np.ndarray:
    """Tiles offset inward by ``shrink`` (mitre), returned as ``(T, 4, 2)`` in corner order.

    Exact for convex tiles: every edge moves inward by ``shrink`` and each corner along its mitre
    (:mod:`fabkiri.pattern.thinness`, the definition the web check and the minimum scale use; a GEOS
    buffer simplifies short edges away at 1 % of the distance). A tile that loses an edge is an error naming it.
    """
    corners = np.asarray(corners, dtype=float)
    edges = fab.shrunk_edges(corners, shrink)
    lost = np.flatnonzero((edges <= fab.EDGE_EPS_MM).any(-1))
    if len(lost):
        t = int(lost[0])
        raise FabricationError(
            f"tile {t} is not a quad once shrunk by {shrink:g} mm; use a smaller gap"
        )
    return fab.shrunk_quads(corners, shrink)


def ligament_design(
    pattern: Pattern,
    shrunk: np.ndarray,
    *,
    gap: float,
    width_max: float,
    min_web: float,
    kerf: float,
    strain_limit: float,
    turn_rad: float = np.pi,
    width: float | None = None,
) -> LigamentDesign:
    """Size the strips by the strain rule (docs/fabrication.md#strain-rule).

    The strip width is the widest that keeps ε = w·Δθ/(2L) within the strain
    limit at the shortest strip, capped by ``width_max`` and never below the
    minimum web (then a warning says the strain is exceeded). ``width``
    forces a value. The clear spacing 2d − w between the two strips at a
    node must stay ≥ min web + kerf.
    """
    top = pattern.topology
    A, B = top.hinge_tiles.T
    cA, cB = top.hinge_corner.T
    apex = np.stack([shrunk[A, cA], shrunk[B, cB]], 1)
    lengths = np.linalg.norm(apex[:, 1] - apex[:, 0], axis=1)
    warnings: list[str] = []
    if len(lengths) == 0:
        return LigamentDesign(0.0, turn_rad, lengths, lengths, apex, warnings)
    Lmin = float(lengths.min())
    if width is None:
        w = max(min_web, min(width_max, 2.0 * Lmin * strain_limit / turn_rad))
    else:
        w = float(width)
    if w < min_web - 1e-12:
        raise FabricationError(f"ligament width {w:g} mm is below the minimum web {min_web:g} mm")
    spacing = gap - w
    if spacing < min_web + kerf - 1e-9:
        raise FabricationError(
            f"ligaments {w:.3g} mm wide leave {spacing:.3g} mm between the two strips of a node, less than "
            f"min web + kerf = {min_web + kerf:.3g} mm; use a gap of at least {w + min_web + kerf:.3g} mm"
        )
    strains = w * turn_rad / (2.0 * lengths)
    worst = float(strains.max())
    if worst > strain_limit:
        h = int(np.argmax(strains))
        # the digits that tell the strain from the limit (not "0.3 exceeds 0.3")
        ws = next(
            (t for d in range(3, 13) if (t := f"{worst:.{d}g}") != f"{strain_limit:g}"), repr(worst)
        )
        warnings.append(
            f"ligament strain {ws} at hinge {h} exceeds the material's limit {strain_limit:g} "
            f"(w {w:.3g} mm, L {lengths[h]:.3g} mm, Δθ {np.degrees(turn_rad):.0f}°); use a larger gap"
        )
    return LigamentDesign(w, turn_rad, lengths, strains, apex, warnings)


def ligament_strips(apex: np.ndarray, width: float, embed: float) -> np.ndarray:
    """Strip polygons from apex A to apex B, reaching ``embed`` mm into each tile."""
    a, b = apex[:, 0], apex[:, 1]
    u = b - a
    n = np.linalg.norm(u, axis=1, keepdims=True)
    u = u / np.where(n > 0, n, 1.0)
    lines = shapely.linestrings(np.stack([a - embed * u, b + embed * u], 1))
    return shapely.buffer(lines, 0.5 * width, cap_style="flat", join_style="mitre")


def kerf_outset(
    polys: shapely.Geometry | np.ndarray, offset: float
) -> shapely.Geometry | np.ndarray:
    """Toolpath outside a part by ``offset`` = kerf/2 (holes shrink), mitre joins."""
    if offset == 0:
        return polys
    return shapely.buffer(polys, offset, join_style="mitre", mitre_limit=MITRE_LIMIT)


def rings_of(geom: shapely.Geometry) -> tuple[list[np.ndarray], list[np.ndarray]]:
    """(exteriors, interiors) of a (multi)polygon as open coordinate arrays, snapped to the grid."""
    ext: list[np.ndarray] = []
    inner: list[np.ndarray] = []
    for poly in shapely.get_parts(geom):
        if poly.is_empty:
            continue
        ext.append(np.asarray(poly.exterior.coords)[:-1])
        inner.extend(np.asarray(r.coords)[:-1] for r in poly.interiors)
    return ext, inner
