"""2D plan of 3D-printed hinges on a closed state.

The rules: docs/fabrication.md#hinge-geometry and docs/fabrication.md#print-styles.

Everything here is planar (shapely/GEOS); :mod:`fabkiri.fabricate.print.mesh` turns
it into solids. Conventions:

* the closed state's tiles are shrunk by half the printer's gap (mitre joins),
  so neighbouring printed tiles stay ``gap`` apart;
* **coincident-hinge rule**: in a closed state the two hinges of an interior
  node sit at one point, so they go on opposite faces (top/bottom). The faces
  come from :func:`fabkiri.fabricate.cut.hinges.assign_faces`, shared with the
  laser-cut tape hinges: a two-colouring over *both* closed states (the lowest
  hinge of each group on top), so a printed piece also reconfigures into the
  other state without two strips or pin stacks meeting. A kind whose closed
  state joins more hinges at a point (kagome: three, ``hole_arity / 2``) cannot
  keep them all apart: the fewest pairs share a face, and their strips must
  keep the radial clearance like any two on one face;
* a **strip** (flexible hinge) of hinge ``h`` joining tiles A and B crosses the
  seam where A's and B's folded edges lie together: along the seam it spans
  ``strip_width`` from where the shrunk pair begins, across it reaches
  ``strip_reach`` into each tile; its pads follow the two tile corners.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
import shapely
from shapely.geometry import MultiPolygon, Polygon

from ...errors import CheckFailed, FabricationError
from ...kdtree import KDTree
from ...mechanics.contract import contract
from ...pattern.kinds.tessellation import tessellation
from ...pattern.model import Pattern
from .printers import Printer, min_pad_mm2

CLOSURE_TOL_REL = 1e-6  # loop closure accepted for printing, in tile sizes
COINCIDE_TOL_REL = 1e-6  # two hinge points closer than this (tile sizes) coincide
CIRCLE_SEGMENTS = 48
POCKET_OVERSHOOT_MM = 0.05
MITRE_LIMIT = (
    10.0  # as the laser-cut layer and the verifier: sharp tips shrink and grow back exactly
)
NOISE_MM = 1e-5  # outline vertices closer than this to their neighbours' line are dropped


def regular_polygon(
    centre, radius: float, circumscribed: bool, n: int = CIRCLE_SEGMENTS, phase: float = 0.0
) -> Polygon:
    """An n-gon approximating a circle: vertices on it (inscribed, for solid
    material) or edges tangent to it (circumscribed, for clearances), so that
    polygon approximation never eats into a clearance; turned by ``phase``
    (in vertex steps)."""
    r = radius / np.cos(np.pi / n) if circumscribed else radius
    a = 2 * np.pi * (np.arange(n) + phase) / n
    return Polygon(np.stack([centre[0] + r * np.cos(a), centre[1] + r * np.sin(a)], -1))


def closed_corners(pattern: Pattern, state: int) -> np.ndarray:
    """Per-tile corners ``(T, n, 2)`` (``n`` the tile arity) of closed state ``state`` (stored, or
    computed and checked)."""
    if state not in (1, 2):
        raise FabricationError(f"closed state must be 1 or 2, not {state!r}")
    if state in pattern.contracted:
        return np.asarray(pattern.contracted[state], dtype=float)
    c = contract(pattern, state)
    if c.max_closure > CLOSURE_TOL_REL * pattern.tile_size:
        raise CheckFailed(
            f"state {state} does not close (loop closure {c.max_closure:.3g} mm at hole {c.worst_hole}); "
            "nothing to print"
        )
    return c.corners


def _largest(geom) -> Polygon:
    if isinstance(geom, Polygon):
        return geom
    if isinstance(geom, MultiPolygon) and len(geom.geoms):
        return max(geom.geoms, key=lambda g: g.area)
    return Polygon()


@dataclass(frozen=True, eq=False)
class ClosedPlan:
    """The printed outline of every tile and the placement of every hinge."""

    state: int
    corners: np.ndarray  # (T, n, 2) closed-state corners, mm
    tiles: np.ndarray  # (T,) shapely Polygons, shrunk by gap/2
    hinge_tiles: np.ndarray  # (H, 2)
    hinge_xy: np.ndarray  # (H, 2) hinge point in the closed state
    seam_dir: np.ndarray  # (H, 2) unit vector along the folded seam, away from the hinge
    seam_end: np.ndarray  # (H, 2) far end of the folded seam
    partner: np.ndarray  # (H,) lowest other coincident hinge or -1 (coinciding() lists all)
    top: np.ndarray  # (H,) True: the hinge's strip goes on the top face
    shrink_mm: float
    other_state_closes: bool = True  # False: a pattern that closes in the printed state only
    shared_faces: int = 0  # coincident pairs on one face (two of three at a kagome merge corner)

    @property
    def n_hinges(self) -> int:
        return len(self.hinge_xy)

    @property
    def bounds(self) -> tuple[float, float, float, float]:
        return tuple(shapely.total_bounds(self.tiles).tolist())

    def face(self, h: int) -> str:
        return "top" if self.top[h] else "bottom"


def coincident_pairs(points: np.ndarray, tol: float, most: int = 2) -> np.ndarray:
    """Partner index of every point: the lowest other point within ``tol`` (``-1`` if alone);
    raises if more than ``most`` coincide (a closed state joins at most ``hole_arity / 2``
    hinges at a point: two for quads, three for kagome)."""
    partner = np.full(len(points), -1, dtype=np.int64)
    if len(points) < 2:
        return partner
    pairs = KDTree(points).query_pairs(tol, output_type="ndarray")
    if len(pairs):
        counts = np.bincount(pairs.ravel(), minlength=len(points))
        if counts.max() > most - 1:
            bad = int(np.argmax(counts))
            raise FabricationError(
                f"hinge {bad} coincides with {counts[bad]} other hinges in the closed state; "
                f"a closed state of this kind joins at most {most} at a point"
            )
        low = np.full(len(points), len(points), dtype=np.int64)
        np.minimum.at(low, pairs[:, 0], pairs[:, 1])
        np.minimum.at(low, pairs[:, 1], pairs[:, 0])
        partner = np.where(low < len(points), low, -1)
    return partner


def coinciding(partner: np.ndarray, h: int) -> list[int]:
    """The other hinges at hinge ``h``'s point (``partner`` as :func:`coincident_pairs` gives it:
    every member of a group points at its lowest member, which points at the next lowest)."""
    if partner[h] < 0:
        return []
    root = min(h, int(partner[h]))
    return [
        int(k)
        for k in np.flatnonzero(
            (np.minimum(np.arange(len(partner)), partner) == root) & (partner >= 0)
        )
        if k != h
    ]


def _fewest_shared(k: int) -> int:
    """Fewest pairs of ``k`` coincident hinges that two faces leave on one face (0 for a pair, 1 for three)."""
    a, b = (k + 1) // 2, k // 2
    return a * (a - 1) // 2 + b * (b - 1) // 2


def face_rule(
    pattern: Pattern, states: dict[int, np.ndarray], apart: np.ndarray | None = None
) -> tuple[np.ndarray, int]:
    """Top (True) or bottom face per hinge, opposite for hinges that coincide in a closed state, and
    how many coincident pairs share a face.

    Where more than two hinges meet at a point (kagome: three, an odd cycle) two of them must
    share a face; that fewest sharing is accepted, any more is refused. ``apart``: hinge pairs the
    colouring should also keep on opposite faces where it is free to (see :func:`closed_plan`)."""
    from ..cut.hinges import assign_faces

    faces = assign_faces(pattern, states, apart)
    if faces.conflicts:
        most = tessellation(pattern.kind).hole_arity // 2
        tol = COINCIDE_TOL_REL * pattern.tile_size
        groups = [
            (_group_sizes(coincident_pairs(_hinge_xy(pattern, c), tol, most)))
            for c in states.values()
        ]
        fewest = sum(_fewest_shared(int(k)) for g in groups for k in g)
        if faces.conflicts > fewest:
            i, j = next((int(a), int(b)) for a, b in faces.pairs if faces.face[a] == faces.face[b])
            raise FabricationError(
                f"hinges {i} and {j} coincide in a closed state but cannot take opposite faces "
                f"({faces.conflicts} conflicting pairs); no printed strip or pin layout exists"
            )
    return faces.face == 0, faces.conflicts


def _hinge_xy(pattern: Pattern, corners: np.ndarray) -> np.ndarray:
    """Every hinge's point in a placed state: the middle of its two tiles' corners there."""
    top_ = pattern.topology
    A, B = top_.hinge_tiles.T
    cA, cB = top_.hinge_corner.T
    return 0.5 * (corners[A, cA] + corners[B, cB])


def _group_sizes(partner: np.ndarray) -> np.ndarray:
    """Size of every group of coincident hinges (two or more), from :func:`coincident_pairs`."""
    roots = np.minimum(np.arange(len(partner)), partner)[partner >= 0]
    return np.bincount(roots)[np.unique(roots)]


def closed_plan(pattern: Pattern, state: int, printer: Printer) -> ClosedPlan:
    if pattern.topology.n_hinges == 0:
        raise FabricationError(
            "the pattern has a single tile and no hinges: there is nothing to hinge"
        )
    corners = closed_corners(pattern, state)
    top_ = pattern.topology
    fold = top_.fold(state)
    A, B = top_.hinge_tiles.T
    hxy = _hinge_xy(pattern, corners)
    far = 0.5 * (corners[A, fold.fold_corner_ends[:, 0]] + corners[B, fold.fold_corner_ends[:, 1]])
    seam = far - hxy
    seam /= np.linalg.norm(seam, axis=1, keepdims=True)
    partner = coincident_pairs(
        hxy, COINCIDE_TOL_REL * pattern.tile_size, tessellation(pattern.kind).hole_arity // 2
    )
    states = {state: corners}
    try:
        states[3 - state] = closed_corners(pattern, 3 - state)
    except CheckFailed:  # a pattern that closes one way only is still printable that way
        pass
    top, shared = face_rule(pattern, states)
    other_closes = len(states) == 2
    d = 0.5 * printer.gap_mm
    polys = shapely.polygons(corners)
    shrunk = shapely.buffer(polys, -d, join_style="mitre", mitre_limit=MITRE_LIMIT)
    empty = shapely.is_empty(shrunk) | (shapely.get_type_id(shrunk) != 3)
    if empty.any():
        bad = int(np.flatnonzero(empty)[0])
        raise FabricationError(
            f"tile {bad} vanishes or splits when shrunk by half the printer gap ({d:g} mm)"
        )
    plan = ClosedPlan(
        state=state,
        corners=corners,
        tiles=shrunk,
        hinge_tiles=top_.hinge_tiles.copy(),
        hinge_xy=hxy,
        seam_dir=seam,
        seam_end=far,
        partner=partner,
        top=top,
        shrink_mm=d,
        other_state_closes=other_closes,
        shared_faces=shared,
    )
    return _refaced(pattern, plan, states, printer) if shared else plan


def _refaced(
    pattern: Pattern, plan: ClosedPlan, states: dict[int, np.ndarray], printer: Printer
) -> ClosedPlan:
    """Where two of three coincident hinges must share a face, which two is free: choose so that
    strips closer than the radial clearance lie on opposite faces where the flips can (two strips
    at two corners of a small triangle). The plan as it was if no strip comes that close, or the
    strips cannot be drawn (``strip_outlines`` then refuses with the reason)."""
    try:
        outline = strip_outlines(plan, printer, check=False).outline
    except FabricationError:
        return plan
    close = _close_strips(outline, np.arange(plan.n_hinges), printer.radial_clearance_mm)
    clash = close[plan.top[close[:, 0]] == plan.top[close[:, 1]]]
    if not len(clash):
        return plan
    try:
        top, shared = face_rule(pattern, states, close)
    except (
        FabricationError
    ):  # the flips traded a coincident pair for strips: keep the fewest sharing
        return plan
    return replace(plan, top=top, shared_faces=shared)


def _close_strips(outline: np.ndarray, idx: np.ndarray, clearance: float) -> np.ndarray:
    """Pairs ``(h, k)``, ``h < k``, of hinges in ``idx`` whose strips are closer than ``clearance``."""
    if len(idx) < 2:
        return np.zeros((0, 2), np.int64)
    i, j = shapely.STRtree(outline[idx]).query(
        outline[idx], predicate="dwithin", distance=clearance - 1e-9
    )
    sel = i < j
    return np.stack([idx[i[sel]], idx[j[sel]]], 1).astype(np.int64)


@dataclass(frozen=True, eq=False)
class Strips:
    """One flexible strip outline per hinge, and its two pads."""

    outline: np.ndarray  # (H,) Polygons
    pads: np.ndarray  # (H, 2) Polygons on tile A and on tile B
    top: np.ndarray  # (H,) face
    pocket: np.ndarray  # (H,) what is cut from the tiles: the strip, reaching past the tile edges


def _pair_regions(a: np.ndarray, b: np.ndarray, d: float, eps: float) -> np.ndarray:
    """Tiles a and b merged along their closed seam (each grown by ``eps`` so they
    overlap), then shrunk like the tiles by ``d``.

    Where the two tiles' far corners nearly meet, the union keeps a notch ``eps``
    wide; shrinking it with mitres can make GEOS return a self-touching hole (a
    closed state-2 ellipse 16x16 raised a TopologyException in the seam
    intersection). The notch is simplified away first, and a merged pair, which
    has no hole by construction, keeps only its largest polygon's outline.
    """
    grow = dict(join_style="mitre", mitre_limit=MITRE_LIMIT)
    union = shapely.simplify(
        shapely.union(shapely.buffer(a, eps, **grow), shapely.buffer(b, eps, **grow)), 2 * eps
    )
    pair = shapely.buffer(union, -(d + eps), **grow)
    bad = np.flatnonzero(~shapely.is_valid(pair) | (shapely.get_num_interior_rings(pair) > 0))
    for k in bad:
        parts = shapely.get_parts(shapely.make_valid(pair[k]))
        parts = parts[shapely.get_type_id(parts) == 3]
        pair[k] = (
            shapely.Polygon(parts[np.argmax(shapely.area(parts))].exterior)
            if len(parts)
            else Polygon()
        )
    return pair


def strip_outlines(plan: ClosedPlan, printer: Printer, check: bool = True) -> Strips:
    """Strip outlines for every hinge (see the module docstring), checked:
    each strip crosses its seam, has a pad on both tiles, and (unless ``check`` is False: the
    outlines only, to choose faces by) keeps the radial clearance from every other strip on
    the same face and from other tiles."""
    d = plan.shrink_mm
    w, reach = printer.strip_width_mm, printer.strip_reach_mm
    eps = 1e-6 * max(1.0, float(np.abs(plan.corners).max()))
    A, B = plan.hinge_tiles.T
    raw = shapely.polygons(plan.corners)
    # the pair region: A and B merged along their closed seam, shrunk like the tiles
    pair = _pair_regions(raw[A], raw[B], d, eps)
    p, e = plan.hinge_xy, plan.seam_dir
    n = np.stack([-e[:, 1], e[:, 0]], -1)
    t0 = _seam_entry(plan, pair, w + reach + d)
    R = reach + d
    t1 = t0 + w
    band = np.stack(
        [
            p + t0[:, None] * e - R * n,
            p + t1[:, None] * e - R * n,
            p + t1[:, None] * e + R * n,
            p + t0[:, None] * e + R * n,
        ],
        1,
    )
    strips = shapely.intersection(shapely.polygons(band), pair)
    # the band's corners can land within micrometres of the pair's: drop such
    # near-duplicate vertices, which a float32 file would weld into degenerate faces
    outline = shapely.simplify(np.array([_largest(g) for g in strips], dtype=object), NOISE_MM)
    pads = np.stack(
        [
            shapely.intersection(outline, plan.tiles[A]),
            shapely.intersection(outline, plan.tiles[B]),
        ],
        -1,
    )
    min_pad = min_pad_mm2(printer)
    small = (shapely.area(pads) < min_pad).any(1)
    if small.any():
        h = int(np.flatnonzero(small)[0])
        raise FabricationError(
            f"hinge {h}: the strip pads on tiles {A[h]} and {B[h]} are too small "
            f"({shapely.area(pads[h]).min():.2f} mm² < {min_pad:.2f} mm²); the tile corners are too narrow "
            "for the strip width"
        )
    if check:
        _check_strip_clearance(plan, outline, printer)
    over = min(POCKET_OVERSHOOT_MM, 0.25 * printer.gap_mm)
    pocket = _pockets(pair, band_frame=(p, e, n), t=(t0, t1), R=R, over=over)
    return Strips(outline=outline, pads=pads, top=plan.top.copy(), pocket=pocket)


def _seam_entry(plan: ClosedPlan, pair: np.ndarray, span: float) -> np.ndarray:
    """Per hinge, where its seam line enters the pair region (``t0``, mm along ``seam_dir`` from the hinge);
    ``span``: strip width + reach + shrink, how far the line is followed. FabricationError if a seam misses."""
    H = plan.n_hinges
    A, B = plan.hinge_tiles.T
    p, e, far_xy = plan.hinge_xy, plan.seam_dir, plan.seam_end
    # where the seam line enters the pair region (t0), measured along e from p
    L = 4.0 * span + 1.0
    seam_lines = shapely.linestrings(np.stack([p, p + L * e], 1))
    inside = shapely.intersection(seam_lines, pair)
    t0 = np.full(H, np.nan)
    for h in range(H):  # a few µs each; intersections are short segments
        g = inside[h]
        if not g.is_empty:
            xy = shapely.get_coordinates(g)
            t0[h] = float(((xy - p[h]) @ e[h]).min())
    if np.isnan(t0).any():
        bad = int(np.flatnonzero(np.isnan(t0))[0])
        seam_len = float(np.linalg.norm(far_xy[bad] - p[bad]))
        raise FabricationError(
            f"hinge {bad}: tiles {A[bad]} and {B[bad]} meet along a seam of only {seam_len:.2f} mm in state "
            f"{plan.state}, too short for a strip after the {plan.shrink_mm:g} mm shrink"
        )
    return t0


def _pockets(pair: np.ndarray, band_frame: tuple, t: tuple, R: float, over: float) -> np.ndarray:
    """The pockets the strips sit in: each strip's band (``t = (t0, t1)`` along the seam, ``R`` either side,
    in the frame ``(p, e, n)``) overshooting the tile edges by ``over``."""
    p, e, n = band_frame
    t0, t1 = t
    # the pocket overshoots the tile edges (into the gap, never near another
    # tile) so no micrometre sliver of tile survives where strip and tile edges
    # meet. It is the band cut by the pair region grown by the overshoot, so its
    # outline runs clear of every tile edge: a pocket corner lying on a tile edge
    # (as band ∩ pair has) leaves manifold3d two vertices a nanometre apart,
    # which a float32 STL merges into edges shared by four faces.
    grown = shapely.buffer(pair, over, join_style="mitre", mitre_limit=MITRE_LIMIT)
    # ... and begins the overshoot before the band, whose end may lie along a tile edge
    t0o = t0 - over
    pband = np.stack(
        [
            p + t0o[:, None] * e - R * n,
            p + t1[:, None] * e - R * n,
            p + t1[:, None] * e + R * n,
            p + t0o[:, None] * e + R * n,
        ],
        1,
    )
    return np.array(
        [_largest(g) for g in shapely.intersection(shapely.polygons(pband), grown)], dtype=object
    )


def _check_strip_clearance(plan: ClosedPlan, outline: np.ndarray, printer: Printer) -> None:
    c = printer.radial_clearance_mm
    tol = 1e-9
    A, B = plan.hinge_tiles.T
    for face in (True, False):
        close = _close_strips(outline, np.flatnonzero(plan.top == face), c)
        if len(close):
            h, k = close[0]
            dist = shapely.distance(outline[h], outline[k])
            raise FabricationError(
                f"strips of hinges {h} and {k} on the {'top' if face else 'bottom'} face are "
                f"{dist:.2f} mm apart (radial clearance {c:g} mm); use a smaller --strip-width or --strip-reach"
            )
    # a strip touches its own two tiles only
    tree = shapely.STRtree(plan.tiles)
    hi, ti = tree.query(outline, predicate="dwithin", distance=c - tol)
    foreign = (ti != A[hi]) & (ti != B[hi])
    if foreign.any():
        h, t = int(hi[foreign][0]), int(ti[foreign][0])
        raise FabricationError(
            f"the strip of hinge {h} comes within {c:g} mm of tile {t}, which it does not join"
        )


def grow_back(polys, shrink: float):
    """Printed outlines grown back to design size (mitre, as the shrink)."""
    return shapely.buffer(polys, shrink, join_style="mitre", mitre_limit=MITRE_LIMIT)
