"""2D plan of 3D-printed hinges on a closed state (fabrication.md §3.1, §3.4).

Everything here is planar (shapely/GEOS); :mod:`fabkiri.fabricate.mesh` turns
it into solids. Conventions:

* the closed state's tiles are shrunk by half the printer's gap (mitre joins),
  so neighbouring printed tiles stay ``gap`` apart;
* **coincident-hinge rule**: in a closed state the two hinges of an interior
  node sit at one point, so they go on opposite faces (top/bottom). The faces
  come from :func:`fabkiri.fabricate.hinges.assign_faces`, shared with the
  laser-cut tape hinges: a two-colouring over *both* closed states (the lowest
  hinge of each group on top), so a printed piece also reconfigures into the
  other state without two strips or pin stacks meeting;
* a **strip** (flexible hinge) of hinge ``h`` joining tiles A and B crosses the
  seam where A's and B's folded edges lie together: along the seam it spans
  ``strip_width`` from where the shrunk pair begins, across it reaches
  ``strip_reach`` into each tile; its pads follow the two tile corners.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import shapely
from scipy.spatial import cKDTree
from shapely.geometry import MultiPolygon, Polygon

from ..errors import CheckFailed, FabricationError
from ..mechanics.contract import contract
from ..pattern.model import Pattern
from .printers import Printer

CLOSURE_TOL_REL = 1e-6  # loop closure accepted for printing, in tile sizes
COINCIDE_TOL_REL = 1e-6  # two hinge points closer than this (tile sizes) coincide
CIRCLE_SEGMENTS = 48
POCKET_OVERSHOOT_MM = 0.05
MITRE_LIMIT = 10.0  # as the laser-cut layer and the verifier: sharp tips shrink and grow back exactly
NOISE_MM = 1e-5  # outline vertices closer than this to their neighbours' line are dropped
MASK_MARGIN_MM = 1e-3  # the tile check masks the pivot clearances with this margin


def regular_polygon(centre, radius: float, circumscribed: bool, n: int = CIRCLE_SEGMENTS,
                    phase: float = 0.0) -> Polygon:
    """An n-gon approximating a circle: vertices on it (inscribed, for solid
    material) or edges tangent to it (circumscribed, for clearances), so that
    polygon approximation never eats into a clearance; turned by ``phase``
    (in vertex steps)."""
    r = radius / np.cos(np.pi / n) if circumscribed else radius
    a = 2 * np.pi * (np.arange(n) + phase) / n
    return Polygon(np.stack([centre[0] + r * np.cos(a), centre[1] + r * np.sin(a)], -1))


def closed_corners(pattern: Pattern, state: int) -> np.ndarray:
    """Per-tile corners ``(T, 4, 2)`` of closed state ``state`` (stored, or computed and checked)."""
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
    corners: np.ndarray  # (T, 4, 2) closed-state corners, mm
    tiles: np.ndarray  # (T,) shapely Polygons, shrunk by gap/2
    hinge_tiles: np.ndarray  # (H, 2)
    hinge_xy: np.ndarray  # (H, 2) hinge point in the closed state
    seam_dir: np.ndarray  # (H, 2) unit vector along the folded seam, away from the hinge
    seam_end: np.ndarray  # (H, 2) far end of the folded seam
    partner: np.ndarray  # (H,) coincident hinge or -1
    top: np.ndarray  # (H,) True: the hinge's strip goes on the top face
    shrink_mm: float
    other_state_closes: bool = True  # False: a pattern that closes in the printed state only

    @property
    def n_hinges(self) -> int:
        return len(self.hinge_xy)

    @property
    def bounds(self) -> tuple[float, float, float, float]:
        return tuple(shapely.total_bounds(self.tiles).tolist())

    def face(self, h: int) -> str:
        return "top" if self.top[h] else "bottom"


def coincident_pairs(points: np.ndarray, tol: float) -> np.ndarray:
    """Partner index of every point (``-1`` if alone); raises if three coincide."""
    partner = np.full(len(points), -1, dtype=np.int64)
    if len(points) < 2:
        return partner
    pairs = cKDTree(points).query_pairs(tol, output_type="ndarray")
    if len(pairs):
        counts = np.bincount(pairs.ravel(), minlength=len(points))
        if counts.max() > 1:
            bad = int(np.argmax(counts))
            raise FabricationError(
                f"hinge {bad} coincides with {counts[bad]} other hinges in the closed state; "
                "a quad kirigami node carries at most two"
            )
        partner[pairs[:, 0]] = pairs[:, 1]
        partner[pairs[:, 1]] = pairs[:, 0]
    return partner


def face_rule(pattern: Pattern, states: dict[int, np.ndarray]) -> np.ndarray:
    """Top (True) or bottom face per hinge, opposite for hinges that coincide in any given state."""
    from .hinges import assign_faces

    faces = assign_faces(pattern, states)
    if faces.conflicts:
        i, j = next((int(a), int(b)) for a, b in faces.pairs if faces.face[a] == faces.face[b])
        raise FabricationError(
            f"hinges {i} and {j} coincide in a closed state but cannot take opposite faces "
            f"({faces.conflicts} conflicting pairs); no printed strip or pin layout exists"
        )
    return faces.face == 0


def closed_plan(pattern: Pattern, state: int, printer: Printer) -> ClosedPlan:
    if pattern.topology.n_hinges == 0:
        raise FabricationError("the pattern has a single tile and no hinges: there is nothing to hinge")
    corners = closed_corners(pattern, state)
    top_ = pattern.topology
    fold = top_.fold(state)
    A, B = top_.hinge_tiles.T
    cA, cB = top_.hinge_corner.T
    hxy = 0.5 * (corners[A, cA] + corners[B, cB])
    far = 0.5 * (corners[A, fold.fold_corner_ends[:, 0]] + corners[B, fold.fold_corner_ends[:, 1]])
    seam = far - hxy
    seam /= np.linalg.norm(seam, axis=1, keepdims=True)
    partner = coincident_pairs(hxy, COINCIDE_TOL_REL * pattern.tile_size)
    states = {state: corners}
    try:
        states[3 - state] = closed_corners(pattern, 3 - state)
    except CheckFailed:  # a pattern that closes one way only is still printable that way
        pass
    top = face_rule(pattern, states)
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
    return ClosedPlan(
        state=state, corners=corners, tiles=shrunk, hinge_tiles=top_.hinge_tiles.copy(), hinge_xy=hxy,
        seam_dir=seam, seam_end=far, partner=partner, top=top, shrink_mm=d, other_state_closes=other_closes,
    )


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
    union = shapely.simplify(shapely.union(shapely.buffer(a, eps, **grow), shapely.buffer(b, eps, **grow)), 2 * eps)
    pair = shapely.buffer(union, -(d + eps), **grow)
    bad = np.flatnonzero(~shapely.is_valid(pair) | (shapely.get_num_interior_rings(pair) > 0))
    for k in bad:
        parts = shapely.get_parts(shapely.make_valid(pair[k]))
        parts = parts[shapely.get_type_id(parts) == 3]
        pair[k] = shapely.Polygon(parts[np.argmax(shapely.area(parts))].exterior) if len(parts) else Polygon()
    return pair


def strip_outlines(plan: ClosedPlan, printer: Printer) -> Strips:
    """Strip outlines for every hinge (see the module docstring), checked:
    each strip crosses its seam, has a pad on both tiles, and keeps the radial
    clearance from every other strip on the same face and from other tiles."""
    H = plan.n_hinges
    d = plan.shrink_mm
    w, reach = printer.strip_width_mm, printer.strip_reach_mm
    eps = 1e-6 * max(1.0, float(np.abs(plan.corners).max()))
    A, B = plan.hinge_tiles.T
    raw = shapely.polygons(plan.corners)
    # the pair region: A and B merged along their closed seam, shrunk like the tiles
    pair = _pair_regions(raw[A], raw[B], d, eps)
    p, e, far_xy = plan.hinge_xy, plan.seam_dir, plan.seam_end
    n = np.stack([-e[:, 1], e[:, 0]], -1)
    # where the seam line enters the pair region (t0), measured along e from p
    L = 4.0 * (w + reach + d) + 1.0
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
    R = reach + d
    t1 = t0 + w
    band = np.stack([p + t0[:, None] * e - R * n, p + t1[:, None] * e - R * n,
                     p + t1[:, None] * e + R * n, p + t0[:, None] * e + R * n], 1)
    strips = shapely.intersection(shapely.polygons(band), pair)
    # the band's corners can land within micrometres of the pair's: drop such
    # near-duplicate vertices, which a float32 file would weld into degenerate faces
    outline = shapely.simplify(np.array([_largest(g) for g in strips], dtype=object), NOISE_MM)
    pads = np.stack([shapely.intersection(outline, plan.tiles[A]),
                     shapely.intersection(outline, plan.tiles[B])], -1)
    min_pad = 0.25 * w * min(reach, w)
    small = (shapely.area(pads) < min_pad).any(1)
    if small.any():
        h = int(np.flatnonzero(small)[0])
        raise FabricationError(
            f"hinge {h}: the strip pads on tiles {A[h]} and {B[h]} are too small "
            f"({shapely.area(pads[h]).min():.2f} mm² < {min_pad:.2f} mm²); the tile corners are too narrow "
            "for the strip width"
        )
    _check_strip_clearance(plan, outline, printer)
    # the pocket overshoots the tile edges (into the gap, never near another
    # tile) so no micrometre sliver of tile survives where strip and tile edges
    # meet. It is the band cut by the pair region grown by the overshoot, so its
    # outline runs clear of every tile edge: a pocket corner lying on a tile edge
    # (as band ∩ pair has) leaves manifold3d two vertices a nanometre apart,
    # which a float32 STL merges into edges shared by four faces.
    over = min(POCKET_OVERSHOOT_MM, 0.25 * printer.gap_mm)
    grown = shapely.buffer(pair, over, join_style="mitre", mitre_limit=MITRE_LIMIT)
    # ... and begins the overshoot before the band, whose end may lie along a tile edge
    t0o = t0 - over
    pband = np.stack([p + t0o[:, None] * e - R * n, p + t1[:, None] * e - R * n,
                      p + t1[:, None] * e + R * n, p + t0o[:, None] * e + R * n], 1)
    pocket = np.array([_largest(g) for g in shapely.intersection(shapely.polygons(pband), grown)], dtype=object)
    return Strips(outline=outline, pads=pads, top=plan.top.copy(), pocket=pocket)


def _check_strip_clearance(plan: ClosedPlan, outline: np.ndarray, printer: Printer) -> None:
    c = printer.radial_clearance_mm
    tol = 1e-9
    A, B = plan.hinge_tiles.T
    for face in (True, False):
        idx = np.flatnonzero(plan.top == face)
        if len(idx) < 2:
            continue
        tree = shapely.STRtree(outline[idx])
        i, j = tree.query(outline[idx], predicate="dwithin", distance=c - tol)
        sel = i < j
        if sel.any():
            h, k = idx[i[sel][0]], idx[j[sel][0]]
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
        raise FabricationError(f"the strip of hinge {h} comes within {c:g} mm of tile {t}, which it does not join")


# -------------------------------------------------------------------- pinned

@dataclass(frozen=True)
class PinLevels:
    """Z layout of the four ear levels of a pinned print (mm)."""

    thickness: float
    ear: float
    axial: float

    def level(self, k: int) -> tuple[float, float]:
        z0 = k * (self.ear + self.axial)
        return z0, z0 + self.ear


def pin_levels(printer: Printer) -> PinLevels:
    T = printer.pin.tile_thickness_mm
    az = printer.axial_clearance_mm
    ear = (T - 3 * az) / 4
    if ear < 3 * printer.layer_mm - 1e-9:
        raise FabricationError(
            f"pinned hinges need four stacked ears: a {T:g} mm tile leaves {ear:.2f} mm per ear after three "
            f"{az:g} mm axial clearances, under three layers ({3 * printer.layer_mm:g} mm); "
            "raise the preset's pin.tile_thickness_mm"
        )
    return PinLevels(thickness=T, ear=ear, axial=az)


@dataclass(frozen=True)
class PinGeometry:
    """Radii of one pin joint (mm). The pin flares upward (retains the ring)."""

    ear: float  # ear disc radius
    hollow: float  # the other tiles are cleared to this radius around the pivot
    pin_bottom: float
    pin_top: float
    hole_bottom: float  # ring hole, horizontal radius
    hole_top: float


def pin_geometry(printer: Printer, levels: PinLevels) -> PinGeometry:
    c = printer.radial_clearance_mm
    r = printer.pin.ear_radius_mm
    rp = printer.pin.pin_radius_mm
    flare = 2.0 * c  # the ring's narrowest hole is smaller than the pin's widest point
    slope = flare / levels.ear
    ch = float(c * np.sqrt(1.0 + slope * slope))  # horizontal clearance giving c normal to the cone
    g = PinGeometry(ear=r, hollow=r + c, pin_bottom=rp, pin_top=rp + flare, hole_bottom=rp + ch,
                    hole_top=rp + flare + ch)
    wall = r - g.hole_top
    if wall < 2 * printer.nozzle_mm - 1e-9:
        raise FabricationError(
            f"pinned hinges: the ear ring wall is {wall:.2f} mm (ear radius {r:g} mm, pin {rp:g} mm, clearance "
            f"{c:g} mm), under two nozzle widths ({2 * printer.nozzle_mm:g} mm); raise pin.ear_radius_mm"
        )
    if rp < printer.nozzle_mm:
        raise FabricationError(f"pin radius {rp:g} mm is under one nozzle width ({printer.nozzle_mm:g} mm)")
    return g


@dataclass(frozen=True, eq=False)
class PinPlan:
    """Where each pin joint sits and which ear levels it uses.

    ``level[h]`` is 0 (ears at levels 0-1) for the bottom hinge of a node and 2
    (levels 2-3) for the top one: the two coincident hinges stack coaxially.
    Tile A of the hinge owns the lower ear and the pin, tile B the ring.
    """

    levels: PinLevels
    geometry: PinGeometry
    level: np.ndarray  # (H,)
    phase: np.ndarray | None = None  # (H,) turn of the pivot polygons (pivot_phases)


def pin_plan(pattern: Pattern, plan: ClosedPlan, printer: Printer) -> PinPlan:
    """Plan print-in-place pins, or refuse with the reason the geometry does not allow them."""
    from ..pattern.residuals import hinge_sums

    levels = pin_levels(printer)
    g = pin_geometry(printer, levels)
    hs = np.abs(hinge_sums(pattern))
    if hs.max(initial=0.0) > 1e-6:
        h = int(np.argmax(hs))
        raise FabricationError(
            f"pinned hinges refused: the pattern is not rigid-deployable (hinge {h}: corner angles miss π by "
            f"{np.degrees(hs[h]):.2f}°), so rigid pinned tiles would have to bend to reconfigure; "
            "use --style strips or tiles-and-strips"
        )
    # one pivot per distinct point; the clearance discs of different pivots must not meet
    lone = (plan.partner < 0) | (np.arange(plan.n_hinges) < plan.partner)
    pivots = plan.hinge_xy[lone]
    wall = 2 * printer.nozzle_mm
    if len(pivots) > 1:
        dist, _ = cKDTree(pivots).query(pivots, k=2)
        i = int(np.argmin(dist[:, 1]))
        if dist[i, 1] < 2 * g.hollow + wall:
            raise FabricationError(
                f"pinned hinges refused: pivots {dist[i, 1]:.2f} mm apart cannot hold two ears of radius "
                f"{g.ear:g} mm with {printer.radial_clearance_mm:g} mm clearance and a {wall:g} mm wall; "
                "scale the pattern up or reduce pin.ear_radius_mm"
            )
    # an ear may only sweep the tiles that meet at its pivot
    A, B = plan.hinge_tiles.T
    discs = shapely.buffer(shapely.points(plan.hinge_xy), g.hollow, quad_segs=16)
    tree = shapely.STRtree(plan.tiles)
    hi, ti = tree.query(discs, predicate="intersects")
    own = (ti == A[hi]) | (ti == B[hi])
    pa = plan.partner[hi]
    own |= (pa >= 0) & ((ti == A[np.maximum(pa, 0)]) | (ti == B[np.maximum(pa, 0)]))
    if not own.all():
        h, t = int(hi[~own][0]), int(ti[~own][0])
        raise FabricationError(
            f"pinned hinges refused: the ear of hinge {h} (radius {g.hollow:g} mm with clearance) reaches tile "
            f"{t}, which does not meet at its pivot"
        )
    _refuse_slivers(plan, g, printer)
    level = np.where(plan.top, 2, 0)
    return PinPlan(levels=levels, geometry=g, level=level, phase=pivot_phases(plan, g))


PHASES = 8  # candidate turns of a pivot's polygons, in 1/PHASES of a vertex step


def pivot_phases(plan: ClosedPlan, g: PinGeometry) -> np.ndarray:
    """Per hinge, the turn of its pivot's polygons (ear, clearance, pin, ring
    hole) that keeps their vertices farthest from the edges of the tiles meeting
    there. A polygon vertex within float noise of a tile edge leaves manifold3d
    two vertices a nanometre apart, which merge in a float32 STL into edges
    shared by four faces; coincident hinges get the same turn (one pivot)."""
    n = CIRCLE_SEGMENTS
    radii = np.array([g.ear, g.pin_bottom, g.pin_top]
                     + [r / np.cos(np.pi / n) for r in (g.hollow, g.hole_bottom, g.hole_top)])
    A, B = plan.hinge_tiles.T
    rings = shapely.get_exterior_ring(plan.tiles)
    cand = np.arange(PHASES) / PHASES
    ang = 2 * np.pi * (np.arange(n)[None, :] + cand[:, None]) / n  # (P, n)
    phase = np.zeros(plan.n_hinges)
    for h in range(plan.n_hinges):
        pa = plan.partner[h]
        if 0 <= pa < h:
            phase[h] = phase[pa]
            continue
        tiles = {int(A[h]), int(B[h])} | ({int(A[pa]), int(B[pa])} if pa >= 0 else set())
        edges = shapely.union_all(rings[sorted(tiles)])
        c = plan.hinge_xy[h]
        xy = c + radii[None, :, None, None] * np.stack([np.cos(ang), np.sin(ang)], -1)[:, None]  # (P, R, n, 2)
        d = shapely.distance(shapely.multipoints(xy.reshape(PHASES, -1, 2)), edges)
        phase[h] = cand[int(np.argmax(d))]
    return phase


def clearance_discs(plan: ClosedPlan, g: PinGeometry) -> np.ndarray:
    """Per hinge, the disc cleared around its pivot (circumscribed polygon, as the solids)."""
    return np.array([regular_polygon(p, g.hollow, circumscribed=True) for p in plan.hinge_xy], dtype=object)


def clearance_mask(points: np.ndarray, g: PinGeometry) -> Polygon | MultiPolygon:
    """The pivot discs left out of the tile-outline comparison (round by design)."""
    return shapely.union_all([regular_polygon(p, g.hollow + MASK_MARGIN_MM, True) for p in points])


def grow_back(polys, shrink: float):
    """Printed outlines grown back to design size (mitre, as the shrink)."""
    return shapely.buffer(polys, shrink, join_style="mitre", mitre_limit=MITRE_LIMIT)


def pinned_sections(plan: ClosedPlan, g: PinGeometry) -> np.ndarray:
    """Per tile, its section where it carries no ear of its own (the axial
    gaps): the shrunk tile minus the clearance discs of all its pivots."""
    discs = clearance_discs(plan, g)
    A, B = plan.hinge_tiles.T
    out = np.empty(len(plan.tiles), dtype=object)
    for t in range(len(plan.tiles)):
        hs = np.flatnonzero((A == t) | (B == t))
        out[t] = plan.tiles[t].difference(shapely.union_all(discs[hs])) if len(hs) else plan.tiles[t]
    return out


def _outline_deviation(grown: np.ndarray, design: np.ndarray) -> np.ndarray:
    dev = shapely.hausdorff_distance(grown, design)
    e1, e2 = shapely.is_empty(grown), shapely.is_empty(design)
    return np.where(e1 & e2, 0.0, np.where(e1 | e2, np.inf, dev))


@dataclass(frozen=True, eq=False)
class SliverReport:
    """Per tile, how far its outline at the axial gaps (recovered as
    :func:`fabkiri.fabricate.mesh.check_printed_tiles` does: grown back by the
    shrink, pivot discs masked) lies from the design (Hausdorff, mm): as built,
    and without the slivers beside a clearance that are narrower than a nozzle
    (what a nozzle can actually lay down)."""

    as_built: np.ndarray  # (T,)
    printable: np.ndarray  # (T,)
    slivers: np.ndarray  # (T,) removed sliver area beside the clearances, mm²
    near_hinge: np.ndarray  # (T,) hinge whose clearance leaves the largest sliver (-1: none)

    @property
    def deviation(self) -> np.ndarray:
        return np.maximum(self.as_built, self.printable)


def clearance_slivers(plan: ClosedPlan, g: PinGeometry, printer: Printer) -> SliverReport:
    """Measure what the pivot clearances leave of every tile (see :class:`SliverReport`).

    A tile corner next to a pivot whose edge runs almost tangent to the
    clearance disc keeps a feather of material thinner than a nozzle: it
    cannot be printed, and the design corner there is not reproduced."""
    S = pinned_sections(plan, g)
    r = 0.5 * printer.nozzle_mm
    core = shapely.buffer(shapely.buffer(S, -r), r)  # where a nozzle fits (morphological opening)
    thin = shapely.difference(S, core)
    discs = clearance_discs(plan, g)
    A, B = plan.hinge_tiles.T
    eps = 1e-6 * max(1.0, float(np.abs(plan.corners).max()))
    printable = S.copy()
    sliver_area = np.zeros(len(S))
    near = np.full(len(S), -1, dtype=np.int64)
    for t in np.flatnonzero(~shapely.is_empty(thin)):
        hs = np.flatnonzero((A == t) | (B == t))
        if not len(hs):
            continue
        # only material within a nozzle of the clearance: the opening also trims the
        # tile's own sharp corners and leaves hairlines along straight edges
        near_disc = shapely.buffer(shapely.union_all(discs[hs]), 2 * r)
        pieces = shapely.get_parts(shapely.intersection(thin[t], near_disc))
        pieces = pieces[shapely.area(pieces) > 0]
        if not len(pieces):
            continue
        dist = shapely.distance(pieces[:, None], discs[hs][None, :])  # (pieces, hinges)
        beside = dist.min(1) < eps
        if not beside.any():
            continue  # thin corners of the tile itself: not the pins' doing
        cut = pieces[beside]
        sliver_area[t] = float(shapely.area(cut).sum())
        biggest = int(np.argmax(shapely.area(cut)))
        near[t] = int(hs[int(np.argmin(dist[beside][biggest]))])
        printable[t] = S[t].difference(shapely.buffer(shapely.union_all(cut), eps, join_style="mitre"))
    mask = clearance_mask(plan.hinge_xy, g)
    design = shapely.difference(shapely.polygons(plan.corners), mask)
    built = _outline_deviation(shapely.difference(grow_back(S, plan.shrink_mm), mask), design)
    core_dev = _outline_deviation(shapely.difference(grow_back(printable, plan.shrink_mm), mask), design)
    return SliverReport(as_built=built, printable=core_dev, slivers=sliver_area, near_hinge=near)


def _refuse_slivers(plan: ClosedPlan, g: PinGeometry, printer: Printer) -> None:
    rep = clearance_slivers(plan, g, printer)
    dev = rep.deviation
    tol = printer.tolerance_mm
    if dev.max(initial=0.0) <= tol:
        return
    t = int(np.argmax(dev))
    h = int(rep.near_hinge[t])
    if h < 0:  # no sliver found: name the tile's pivot nearest to its worst point
        hs = np.flatnonzero((plan.hinge_tiles == t).any(1))
        h = int(hs[np.argmin(shapely.distance(shapely.points(plan.hinge_xy[hs]), plan.tiles[t].exterior))])
    raise FabricationError(
        f"pinned hinges refused: tile {t} is too narrow beside the {g.hollow:g} mm clearance around the pivot of "
        f"hinge {h}: it keeps a sliver under one nozzle ({printer.nozzle_mm:g} mm) wide there, so its printed "
        f"outline would be {dev[t]:.2f} mm off the design (tolerance {tol:g} mm); "
        "scale the pattern up or reduce pin.ear_radius_mm"
    )
