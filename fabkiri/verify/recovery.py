"""Tile recovery: from the cut linework to one polygon per tile, per hinge kind.

``tape``: the noded linework polygonized; ``separate``: each closed outline shrunk by the kerf
offset; ``ligament``: the material minus the hinge strips, grown by the tile shrink. See
:mod:`.quads` for reducing each polygon to its four corners.
"""

from __future__ import annotations

import numpy as np
import shapely
from scipy.sparse import csgraph

from ..errors import VerifyError
from ..exchange.linework import JOIN_MM, SNAP_MM, Linework
from ..kdtree import KDTree
from .hingeread import PLAIN, HingeReading, reading, register_reading
from .manifest import Allowances
from .matching import match_by_shape
from .quads import (
    _declared_strips_moved,
    _feature_geometry,
    _hairline_free,
    _nested,
    _on_cut_edges,
    _open_ligaments,
    quads_of,
)

# ------------------------------------------------------------------ recovery


def _drop_reference(lw: Linework, corners: np.ndarray | None, tol: float = 1e-3) -> int:
    """Remove the closed polyline whose corners are the reference square's; where the sheet was moved
    (none there), the one closed polyline that is a square of the declared side within ``tol`` (the
    square is uncompensated: drawn at its side, unlike the kerf-offset or shrunk tiles). Several such
    squares (tiles of the square's size) are left for :func:`.quads._set_reference_aside`."""
    if corners is None:
        return 0
    at = [
        i
        for i, (pts, cl) in enumerate(zip(lw.polylines, lw.closed))
        if cl
        and len(pts) == len(corners)
        and np.linalg.norm(pts[:, None] - corners[None], axis=-1).min(axis=1).max() <= 1e-3
    ]
    if not at:
        side = float(np.linalg.norm(np.roll(corners, -1, 0) - corners, axis=1).mean())
        at = [
            i
            for i, (pts, cl) in enumerate(zip(lw.polylines, lw.closed))
            if cl and len(pts) == len(corners) and _is_square(pts, side, tol)
        ]
        if len(at) != 1:
            return 0
    keep = [i for i in range(len(lw.polylines)) if i != at[0]]
    lw.polylines = [lw.polylines[i] for i in keep]
    lw.closed = [lw.closed[i] for i in keep]
    return 1


def _is_square(pts: np.ndarray, side: float, tol: float) -> bool:
    """Whether the four points ``pts`` are a square of ``side`` within ``tol``."""
    if len(pts) != 4:
        return False
    e = np.linalg.norm(np.roll(pts, -1, 0) - pts, axis=1)
    d = np.linalg.norm(pts[2:] - pts[:2], axis=1)
    return bool(np.abs(e - side).max() <= tol and abs(d[0] - d[1]) <= tol)


def _snapped_segments(lw: Linework, eps: float = SNAP_MM) -> np.ndarray:
    """All segments ``(n, 2, 2)`` with endpoints closer than ``eps`` merged."""
    if not lw.polylines:
        return np.zeros((0, 2, 2))
    pts = np.concatenate(lw.polylines)
    n = np.array([len(q) for q in lw.polylines])
    start = np.concatenate([[0], np.cumsum(n)[:-1]])
    owner = np.repeat(np.arange(len(n)), n)
    local = np.arange(len(pts)) - start[owner]
    nxt = start[owner] + (local + 1) % n[owner]
    # every vertex starts a segment, except the last one of an open polyline
    use = (local < n[owner] - 1) | np.asarray(lw.closed)[owner]
    segs = np.stack([pts[use], pts[nxt[use]]], 1)
    pts = segs.reshape(-1, 2)
    pairs = KDTree(pts).query_pairs(eps, output_type="ndarray")
    if len(pairs):
        from scipy import sparse

        n_pts = len(pts)
        g = sparse.coo_matrix(
            (np.ones(len(pairs)), (pairs[:, 0], pairs[:, 1])), shape=(n_pts, n_pts)
        )
        _, label = csgraph.connected_components(g, directed=False)
        first = np.full(label.max() + 1, -1)
        first[label[::-1]] = np.arange(n_pts)[::-1]
        pts = pts[first[label]]
    segs = pts.reshape(-1, 2, 2)
    return segs[np.linalg.norm(segs[:, 1] - segs[:, 0], axis=1) > 0]


def _node(segs: np.ndarray, eps: float = JOIN_MM) -> shapely.Geometry:
    """Segments ``(n, 2, 2)`` noded: ends within ``eps`` of another line are put on it (T-junctions
    rounded off their edge), then every crossing and touch is a node. Returns the union."""
    lines = shapely.linestrings(segs)
    ends = shapely.points(np.unique(segs.reshape(-1, 2), axis=0))
    # each line snapped to the ends within eps of it only: the same snap as one
    # multiline to all ends (farther ends never move a vertex), without its n x m cost
    li, ei = shapely.STRtree(ends).query(lines, predicate="dwithin", distance=eps)
    order = np.lexsort((ei, li))
    has, rank = np.unique(li[order], return_inverse=True)
    near = shapely.multipoints(
        ends[ei[order]], indices=rank
    )  # one multipoint per line with ends near it
    lines[has] = shapely.snap(lines[has], near, eps)
    return shapely.unary_union(lines)


def _noded(lw: Linework, eps: float = JOIN_MM) -> np.ndarray:
    """The CUT linework as noded line parts (shapely), endpoints within ``eps`` merged."""
    segs = _snapped_segments(lw, eps)
    if len(segs) == 0:
        return np.zeros(0, dtype=object)
    return shapely.get_parts(_node(segs, eps))


def join_pieces(lw: Linework, eps: float = JOIN_MM) -> Linework:
    """Open pieces and LINEs chained end to end into closed outlines where they close (within ``eps``).

    What stays open is a cut that ends in the material (see :func:`dangling_ends`).
    """
    if all(lw.closed):
        return lw
    merged = shapely.get_parts(shapely.line_merge(shapely.union_all(_noded(lw, eps))))
    out = Linework(lw.path, layer_found=lw.layer_found)
    for g in merged:
        pts = np.asarray(g.coords)
        out.add(pts, bool(g.is_ring))
    return out


def dangling_ends(lw: Linework, eps: float = JOIN_MM) -> np.ndarray:
    """Points ``(n, 2)`` where a cut line stops without meeting another cut (farther than ``eps``).

    Every line of a valid layout bounds a part: it ends where other lines meet it. An end in
    the material is a slit cut short (the tiles stay joined) or an extra cut into a part.
    """
    parts = _noded(lw, eps)
    if len(parts) == 0:
        return np.zeros((0, 2))
    ends = np.concatenate(
        [
            shapely.get_coordinates(shapely.get_point(parts, 0)),
            shapely.get_coordinates(shapely.get_point(parts, -1)),
        ]
    )
    owner = np.concatenate([np.arange(len(parts)), np.arange(len(parts))])
    tree = shapely.STRtree(parts)
    pi, gi = tree.query(shapely.points(ends), predicate="dwithin", distance=eps)
    other = np.zeros(len(ends), dtype=bool)
    other[pi[gi != owner[pi]]] = True
    # a closed part meets itself at its ends
    ring = shapely.is_closed(parts)[owner]
    return ends[~other & ~ring]


def recover_polygons(
    lw: Linework,
    al: Allowances,
    sheet: int = 1,
    frame_tiles: np.ndarray | None = None,
    arity: int = 4,
) -> tuple[np.ndarray, str]:
    """Tile regions (shapely polygons) from one file's CUT linework, and the method used: the hinge
    kind's reading (:mod:`.hingeread`) recovers them.

    ``frame_tiles``: the design tiles where the manifest puts them (its sheet frame), to find the
    declared ligaments on a sheet that was moved or turned since. ``arity``: corners per tile.
    """
    if not lw.polylines:  # e.g. a sheet that holds only the reference square
        return np.zeros(0, dtype=object), "nothing to recover"
    joined = None
    if (
        al.hinge == PLAIN
    ):  # no manifest: outlines that all close are separate tiles (or, nested, one
        # ligament sheet), else in-place linework
        joined = join_pieces(lw)
        rings = joined.subset(i for i, c in enumerate(joined.closed) if c)
        n_open = len(joined.closed) - len(rings.closed)
        # a sheet piece with holes stays one even with a few stray cuts across it (they are checked later)
        guess = (
            "ligament"
            if n_open < len(rings.closed) and _nested(rings)
            else "separate"
            if not n_open
            else "tape"
        )
        how = reading(guess)
    else:
        how = reading(al.hinge)
    if how is None:
        raise VerifyError(f"{lw.path}: no reading for hinge kind {al.hinge!r}")
    if (
        how.closed_only
    ):  # stray open cuts are left out here and reported as cut ends in the material
        joined = join_pieces(lw) if joined is None else joined
        lw = joined.subset(i for i, c in enumerate(joined.closed) if c)
    return how.recover(lw, al, sheet, frame_tiles, arity)


def _noded_faces(
    lw: Linework, al: Allowances, sheet: int, frame_tiles: np.ndarray | None, arity: int
) -> tuple[np.ndarray, str]:
    """Tape: the faces of the noded linework."""
    segs = _snapped_segments(lw, JOIN_MM)
    if len(segs) == 0:
        return np.zeros(0, dtype=object), "polygonize"
    noded = _node(segs)
    faces = shapely.get_parts(shapely.polygonize(shapely.get_parts(noded)))
    return faces, "polygonize of the noded linework"


def _closed_rings(lw: Linework, al: Allowances) -> np.ndarray:
    """The closed CUT outlines as valid polygons; every outline must be closed."""
    rings = [shapely.Polygon(p) for p, c in zip(lw.polylines, lw.closed) if c]
    if len(rings) != len(lw.polylines):
        raise VerifyError(
            f"{lw.path}: {len(lw.polylines) - len(rings)} open CUT polylines in a {al.hinge} "
            f"layout, where every outline must be closed"
        )
    return shapely.make_valid(np.array(rings, dtype=object))


def _outlines_less_kerf(
    lw: Linework, al: Allowances, sheet: int, frame_tiles: np.ndarray | None, arity: int
) -> tuple[np.ndarray, str]:
    """Separate tiles: every closed outline less the kerf offset."""
    polys = _closed_rings(lw, al)
    out = (
        shapely.buffer(polys, -al.kerf_offset, join_style="mitre", mitre_limit=10.0)
        if al.kerf_offset
        else polys
    )
    return shapely.get_parts(out[~shapely.is_empty(out)]), "closed outlines minus the kerf offset"


def _material_less_ligaments(
    lw: Linework, al: Allowances, sheet: int, frame_tiles: np.ndarray | None, arity: int
) -> tuple[np.ndarray, str]:
    """A ligament sheet: the material minus the hinge strips, grown by the tile shrink."""
    material = _material(_closed_rings(lw, al), al.kerf_offset)
    feats = [
        _feature_geometry(f["polygon"])
        for f in al.hinge_features
        if f.get("polygon") and int(f.get("sheet", 1)) == sheet
    ]
    strips = shapely.unary_union(feats) if feats else None
    # a file rounded to 1 µm may keep a hairline of material beside a declared strip: an opening at the
    # join tolerance drops it (and leaves convex tiles exactly as they are)
    parts = (
        _hairline_free(material.difference(strips))
        if strips is not None
        else np.zeros(0, dtype=object)
    )

    # the declared strips (in the manifest's sheet frame) cut the piece into tiles where the sheet was not moved
    def cuts_tiles(parts: np.ndarray) -> bool:
        return (shapely.area(parts) > 1.0).sum() >= max(2, len(feats) // 4)

    if strips is not None and cuts_tiles(parts):
        parts = _on_cut_edges(parts, material, arity)
        how = "material minus the declared ligaments, corners on the cut edges"
    else:  # the ligaments are the strips an opening removes, wherever the sheet was moved
        parts = _on_cut_edges(_open_ligaments(material, al.ligament_width), material, arity)
        how = "material opened to drop the ligaments, corners on the cut edges"
        # the declared strips moved with the sheet (a tile narrower than a ligament the opening cuts short)
        moved = _declared_strips_moved(parts, strips, frame_tiles, al, material)
        if moved is not None:
            again = _hairline_free(material.difference(moved))
            if cuts_tiles(again):
                parts, how = (
                    _on_cut_edges(again, material, arity),
                    "material minus the declared ligaments, moved with the sheet",
                )
    # a file rounded to 1 µm leaves vertex pairs a fraction of a µm apart where it had one vertex: on a
    # tile narrower than its ligaments' roots they decide which corners the growth makes, so drop them
    parts = shapely.simplify(parts, JOIN_MM / 2, preserve_topology=True)
    if al.tile_shrink:
        parts = shapely.buffer(parts, al.tile_shrink, join_style="mitre", mitre_limit=10.0)
    return parts, how + ", grown by the tile shrink"


def _material(polys: np.ndarray, kerf_offset: float) -> shapely.Geometry:
    """A ligament sheet's material: outer loops minus the loops inside them, less the kerf offset."""
    tree = shapely.STRtree(polys)
    inside = np.zeros(len(polys), dtype=bool)
    a, b = tree.query(polys, predicate="contains_properly")
    inside[b[a != b]] = True
    material = shapely.difference(
        shapely.unary_union(polys[~inside]), shapely.unary_union(polys[inside])
    )
    if kerf_offset:
        material = material.buffer(-kerf_offset, join_style="mitre", mitre_limit=10.0)
    return material


def sheet_material(lw: Linework, kerf_offset: float) -> shapely.Geometry:
    """The material of a ligament sheet's CUT linework (its closed outlines)."""
    joined = join_pieces(lw)
    rings = [shapely.Polygon(p) for p, c in zip(joined.polylines, joined.closed) if c]
    return _material(shapely.make_valid(np.array(rings, dtype=object)), kerf_offset)


def _choose_cut(
    candidates: list[Linework], al: Allowances, sheet: int, D: np.ndarray, L: float, tol: float
) -> Linework:
    """The candidate linework (a colour class of a file without a CUT layer) that forms the most
    design tiles; with one candidate, that one."""
    if len(candidates) == 1:
        return candidates[0]
    best, score = candidates[0], None
    for lw in candidates:
        try:
            polys, _ = recover_polygons(lw, al, sheet, arity=D.shape[1])
        except VerifyError:
            continue
        quads, bad = quads_of(polys[shapely.area(polys) > tol**2], D.shape[1])
        _, res, _ = match_by_shape(D, quads, L)
        n = int(
            (res <= max(tol, 0.05 * L)).sum()
        )  # near a tile's shape (kerf offsets not yet undone)
        key = (n, -(len(quads) + bad - n))  # most tiles, then fewest other regions
        if score is None or key > score:
            best, score = lw, key
    return best


# the built-in hinge kinds' readings (the verify half of fabricate/hingekinds/)
register_reading(
    HingeReading("tape", _noded_faces, in_place=True, closed_only=False, tape_marks=True)
)
register_reading(HingeReading("separate", _outlines_less_kerf, in_place=False))
register_reading(
    HingeReading("ligament", _material_less_ligaments, in_place=True, declared_hinges=True)
)
