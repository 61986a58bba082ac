"""2D plan of print-in-place pinned hinges on a closed state (docs/fabrication.md#print-styles).

The hinges that coincide in a closed state are stacked coaxially, two ear
levels per hinge: tile A of a hinge owns the lower ear and the pin, tile B the
ring. A kind whose closed states join ``hole_arity / 2`` hinges at a point
stacks that many (quads two, four ear levels; kagome three, six). Here: where
each pin sits and which levels it uses (or why the geometry refuses pins), the
turn of each pivot's polygons, and the slivers a pivot clearance leaves beside a
tile's outline; the levels and radii from the printer preset are :mod:`.pinsizes`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import shapely
from shapely.geometry import MultiPolygon, Polygon

from ...errors import FabricationError
from ...kdtree import KDTree
from ...pattern.kinds.tessellation import tessellation
from ...pattern.model import Pattern
from . import geometry as printgeom
from .geometry import CIRCLE_SEGMENTS, ClosedPlan, grow_back, regular_polygon
from .pinsizes import PinGeometry, PinLevels, pin_geometry, pin_levels, pin_stack
from .pinslots import pin_slots
from .printers import Printer

MASK_MARGIN_MM = 1e-3  # the tile check masks the pivot clearances with this margin


@dataclass(frozen=True, eq=False)
class PinPlan:
    """Where each pin joint sits and which ear levels it uses.

    ``level[h]`` is ``2 · place`` (ears at levels ``2·place`` and ``2·place + 1``),
    its place in the coaxial stack (:func:`pin_slots`; quads: 0 for the bottom-face
    hinge of a node, 2 for the top-face one). Tile A of the hinge owns the lower
    ear and the pin, tile B the ring.
    """

    levels: PinLevels
    geometry: PinGeometry
    level: np.ndarray  # (H,)
    phase: np.ndarray | None = None  # (H,) turn of the pivot polygons (pivot_phases)
    foreign: tuple = ()  # per tile, (m, 2) corners cleared all through (foreign_corners)
    foreign_phase: tuple = ()  # per tile, (m,) turn of those corners' clearance polygons


def pin_plan(pattern: Pattern, plan: ClosedPlan, printer: Printer) -> PinPlan:
    """Plan print-in-place pins, or refuse with the reason the geometry does not allow them."""
    levels, g, foreign, slot = _admitted(pattern, plan, printer)
    phase = pivot_phases(plan, g)
    return PinPlan(
        levels=levels,
        geometry=g,
        level=2 * slot,
        phase=phase,
        foreign=tuple(foreign),
        foreign_phase=tuple(_foreign_phases(plan, g, foreign, phase)),
    )


def check_pins(pattern: Pattern, plan: ClosedPlan, printer: Printer) -> None:
    """Refuse as :func:`pin_plan` does, without turning the pivots' polygons (which never refuses): for
    a caller that asks only whether pins print at this size."""
    _admitted(pattern, plan, printer)


def _admitted(
    pattern: Pattern, plan: ClosedPlan, printer: Printer
) -> tuple[PinLevels, PinGeometry, list[np.ndarray], np.ndarray]:
    """Every refusal of :func:`pin_plan`, in its order; the levels, geometry, foreign corners and slots."""
    from ...pattern.residuals import hinge_sums

    stack = pin_stack(pattern)
    levels = pin_levels(printer, stack)
    g = pin_geometry(printer, levels)
    if tessellation(pattern.kind).rigid_family:  # the family in closed form: hinge sums π
        hs = np.abs(hinge_sums(pattern))
        if hs.max(initial=0.0) > 1e-6:
            h = int(np.argmax(hs))
            raise FabricationError(
                f"pinned hinges refused: the pattern is not rigid-deployable (hinge {h}: corner angles miss "
                f"π by {np.degrees(hs[h]):.2f}°), so rigid pinned tiles would have to bend to reconfigure"
            )
    _refuse_close_pivots(plan, g, printer)
    # an ear may only sweep the tiles that meet at its pivot
    discs = shapely.buffer(shapely.points(plan.hinge_xy), g.hollow, quad_segs=16)
    hi, ti = shapely.STRtree(plan.tiles).query(discs, predicate="intersects")
    at = pivot_tiles(plan)
    own = np.array([int(t) in at[int(h)] for h, t in zip(hi, ti, strict=True)], dtype=bool)
    if not own.all():
        h, t = int(hi[~own][0]), int(ti[~own][0])
        raise FabricationError(
            f"pinned hinges refused: the ear of hinge {h} (radius {g.hollow:g} mm with clearance) reaches tile "
            f"{t}, which does not meet at its pivot; scale the pattern up or reduce pin.ear_radius_mm"
        )
    foreign = foreign_corners(pattern, plan)
    _refuse_slivers(plan, g, printer, foreign)
    return levels, g, foreign, pin_slots(pattern, plan, stack)


def _refuse_close_pivots(plan: ClosedPlan, g: PinGeometry, printer: Printer) -> None:
    """One pivot per distinct point; the clearance discs of different pivots must not meet."""
    lone = (plan.partner < 0) | (np.arange(plan.n_hinges) < plan.partner)
    pivots = plan.hinge_xy[lone]
    wall = 2 * printer.nozzle_mm
    if len(pivots) < 2:
        return
    dist, idx = KDTree(pivots).query(pivots, k=2)
    i = int(np.argmin(dist[:, 1]))
    if dist[i, 1] < 2 * g.hollow + wall:
        h, k = np.flatnonzero(lone)[[i, int(idx[i, 1])]]
        raise FabricationError(
            f"pinned hinges refused: the pivots of hinges {h} and {k} are {dist[i, 1]:.2f} mm apart and cannot "
            f"hold two ears of radius {g.ear:g} mm with {printer.radial_clearance_mm:g} mm clearance and a "
            f"{wall:g} mm wall; scale the pattern up or reduce pin.ear_radius_mm"
        )


def pivot_tiles(plan: ClosedPlan) -> list[set[int]]:
    """Per hinge, the tiles that meet at its pivot in the printed state: its own two, those of the
    hinges that coincide with it there, and any tile with a corner there that is not hinged at it
    (a kagome closed state lays a foreign tile's corner on a fold hinge). The clearance disc cuts
    them all."""
    A, B = plan.hinge_tiles.T
    T, n = plan.corners.shape[:2]
    edge = float(np.linalg.norm(np.roll(plan.corners, -1, 1) - plan.corners, axis=-1).mean())
    hits = KDTree(plan.corners.reshape(-1, 2)).query_ball_point(
        plan.hinge_xy, printgeom.COINCIDE_TOL_REL * edge
    )
    out = []
    for h in range(plan.n_hinges):
        hs = [h, *printgeom.coinciding(plan.partner, h)]
        at = {int(A[k]) for k in hs} | {int(B[k]) for k in hs}
        out.append(at | {int(i) // n for i in hits[h]})
    return out


def foreign_corners(pattern: Pattern, plan: ClosedPlan) -> list[np.ndarray]:
    """Per tile, the corners (printed-state points, ``(m, 2)``) it is cleared around through the full
    height: its corners that are not hinged but lie on a hinge's pivot in either closed state (a
    kagome closed state lays a free corner on a fold hinge). An ear sweeps there in one state or
    the other, so the corner must keep out of every ear level."""
    top = pattern.topology
    T, n = plan.corners.shape[:2]
    hinged = np.zeros((T, n), dtype=bool)
    hinged[top.hinge_tiles[:, 0], top.hinge_corner[:, 0]] = True
    hinged[top.hinge_tiles[:, 1], top.hinge_corner[:, 1]] = True
    states = [plan.corners]
    if plan.other_state_closes:
        states.append(printgeom.closed_corners(pattern, 3 - plan.state))
    on_pivot = np.zeros((T, n), dtype=bool)
    tol = printgeom.COINCIDE_TOL_REL * pattern.tile_size
    for c in states:
        xy = 0.5 * (
            c[top.hinge_tiles[:, 0], top.hinge_corner[:, 0]]
            + c[top.hinge_tiles[:, 1], top.hinge_corner[:, 1]]
        )
        d, _ = KDTree(xy).query(c.reshape(-1, 2))
        on_pivot |= (d <= tol).reshape(T, n)
    free = on_pivot & ~hinged
    return [plan.corners[t][free[t]] for t in range(T)]


def _disc_table(
    plan: ClosedPlan, g: PinGeometry, foreign: list[np.ndarray] | None
) -> tuple[np.ndarray, list[np.ndarray]]:
    """Every clearance disc (the hinges' first, then the foreign corners') and, per tile, the indices
    of those that cut it."""
    discs = list(clearance_discs(plan, g))
    A, B = plan.hinge_tiles.T
    cut = []
    for t in range(len(plan.tiles)):
        own = np.flatnonzero((A == t) | (B == t))
        pts = foreign[t] if foreign is not None else np.zeros((0, 2))
        extra = np.arange(len(discs), len(discs) + len(pts))
        discs += [regular_polygon(p, g.hollow, circumscribed=True) for p in pts]
        cut.append(np.concatenate([own, extra]).astype(np.int64))
    return np.array(discs, dtype=object), cut


PHASES = 8  # candidate turns of a pivot's polygons, in 1/PHASES of a vertex step


def pivot_phases(plan: ClosedPlan, g: PinGeometry) -> np.ndarray:
    """Per hinge, the turn of its pivot's polygons (ear, clearance, pin, ring
    hole) that keeps their vertices farthest from the edges of the tiles meeting
    there. A polygon vertex within float noise of a tile edge leaves manifold3d
    two vertices a nanometre apart, which merge in a float32 STL into edges
    shared by four faces; coincident hinges get the same turn (one pivot)."""
    n = CIRCLE_SEGMENTS
    radii = np.array(
        [g.ear, g.pin_bottom, g.pin_top]
        + [r / np.cos(np.pi / n) for r in (g.hollow, g.hole_bottom, g.hole_top)]
    )
    A, B = plan.hinge_tiles.T
    rings = shapely.get_exterior_ring(plan.tiles)
    cand = np.arange(PHASES) / PHASES
    ang = 2 * np.pi * (np.arange(n)[None, :] + cand[:, None]) / n  # (P, n)
    phase = np.zeros(plan.n_hinges)
    at = pivot_tiles(plan)
    for h in range(plan.n_hinges):
        pa = plan.partner[h]
        if 0 <= pa < h:
            phase[h] = phase[pa]
            continue
        tiles = at[h]
        edges = shapely.union_all(rings[sorted(tiles)])
        c = plan.hinge_xy[h]
        xy = (
            c + radii[None, :, None, None] * np.stack([np.cos(ang), np.sin(ang)], -1)[:, None]
        )  # (P, R, n, 2)
        d = shapely.distance(shapely.multipoints(xy.reshape(PHASES, -1, 2)), edges)
        phase[h] = cand[int(np.argmax(d))]
    return phase


def _foreign_phases(
    plan: ClosedPlan, g: PinGeometry, foreign: list[np.ndarray], phase: np.ndarray
) -> list[np.ndarray]:
    """Per foreign corner (:func:`foreign_corners`), the turn of its clearance polygon: the pivot's
    where it lies on one in the printed state (one polygon family per point), else the turn that
    keeps the polygon's vertices farthest from its own tile's edges (as :func:`pivot_phases`)."""
    n = CIRCLE_SEGMENTS
    cand = np.arange(PHASES) / PHASES
    ang = 2 * np.pi * (np.arange(n)[None, :] + cand[:, None]) / n  # (P, n)
    rings = shapely.get_exterior_ring(plan.tiles)
    tree = KDTree(plan.hinge_xy)
    tol = 1e-6 * max(1.0, float(np.abs(plan.corners).max()))
    out = []
    for t, pts in enumerate(foreign):
        ph = np.zeros(len(pts))
        for i, p in enumerate(pts):
            d, h = tree.query(p)
            if d <= tol:
                ph[i] = phase[int(h)]
                continue
            r = g.hollow / np.cos(np.pi / n)
            xy = p + r * np.stack([np.cos(ang), np.sin(ang)], -1)  # (P, n, 2)
            ph[i] = cand[int(np.argmax(shapely.distance(shapely.multipoints(xy), rings[t])))]
        out.append(ph)
    return out


def clearance_discs(plan: ClosedPlan, g: PinGeometry) -> np.ndarray:
    """Per hinge, the disc cleared around its pivot (circumscribed polygon, as the solids)."""
    return np.array(
        [regular_polygon(p, g.hollow, circumscribed=True) for p in plan.hinge_xy], dtype=object
    )


def clearance_mask(points: np.ndarray, g: PinGeometry) -> Polygon | MultiPolygon:
    """The pivot discs left out of the tile-outline comparison (round by design)."""
    return shapely.union_all([regular_polygon(p, g.hollow + MASK_MARGIN_MM, True) for p in points])


def pinned_sections(
    plan: ClosedPlan, g: PinGeometry, foreign: list[np.ndarray] | None = None
) -> np.ndarray:
    """Per tile, its section where it carries no ear of its own (the axial
    gaps): the shrunk tile minus the clearance discs of all its pivots and
    foreign corners (:func:`foreign_corners`)."""
    discs, cut = _disc_table(plan, g, foreign)
    out = np.empty(len(plan.tiles), dtype=object)
    for t in range(len(plan.tiles)):
        hs = cut[t]
        out[t] = (
            plan.tiles[t].difference(shapely.union_all(discs[hs])) if len(hs) else plan.tiles[t]
        )
    return out


def _outline_deviation(grown: np.ndarray, design: np.ndarray) -> np.ndarray:
    dev = shapely.hausdorff_distance(grown, design)
    e1, e2 = shapely.is_empty(grown), shapely.is_empty(design)
    return np.where(e1 & e2, 0.0, np.where(e1 | e2, np.inf, dev))


@dataclass(frozen=True, eq=False)
class SliverReport:
    """Per tile, how far its outline at the axial gaps (recovered as
    :func:`fabkiri.fabricate.print.mesh.check_printed_tiles` does: grown back by the
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


def clearance_slivers(
    plan: ClosedPlan, g: PinGeometry, printer: Printer, foreign: list[np.ndarray] | None = None
) -> SliverReport:
    """Measure what the pivot clearances leave of every tile (see :class:`SliverReport`).

    A tile corner next to a pivot whose edge runs almost tangent to the
    clearance disc keeps a feather of material thinner than a nozzle: it
    cannot be printed, and the design corner there is not reproduced."""
    S = pinned_sections(plan, g, foreign)
    r = 0.5 * printer.nozzle_mm
    core = shapely.buffer(shapely.buffer(S, -r), r)  # where a nozzle fits (morphological opening)
    thin = shapely.difference(S, core)
    discs, cut_by = _disc_table(plan, g, foreign)
    eps = 1e-6 * max(1.0, float(np.abs(plan.corners).max()))
    printable = S.copy()
    sliver_area = np.zeros(len(S))
    near = np.full(len(S), -1, dtype=np.int64)
    for t in np.flatnonzero(~shapely.is_empty(thin)):
        hs = cut_by[t]
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
        d = int(hs[int(np.argmin(dist[beside][biggest]))])
        near[t] = d if d < plan.n_hinges else -1  # a foreign corner's disc: no hinge to name
        printable[t] = S[t].difference(
            shapely.buffer(shapely.union_all(cut), eps, join_style="mitre")
        )
    mask = clearance_mask(mask_points(plan, foreign), g)
    design = shapely.difference(shapely.polygons(plan.corners), mask)
    built = _outline_deviation(shapely.difference(grow_back(S, plan.shrink_mm), mask), design)
    core_dev = _outline_deviation(
        shapely.difference(grow_back(printable, plan.shrink_mm), mask), design
    )
    return SliverReport(as_built=built, printable=core_dev, slivers=sliver_area, near_hinge=near)


def mask_points(plan: ClosedPlan, foreign: list[np.ndarray] | None) -> np.ndarray:
    """The centres of every clearance disc (pivots, then foreign corners), printed-state mm."""
    if not foreign:
        return plan.hinge_xy
    return np.concatenate([plan.hinge_xy, *[f.reshape(-1, 2) for f in foreign]])


def _refuse_slivers(
    plan: ClosedPlan, g: PinGeometry, printer: Printer, foreign: list[np.ndarray]
) -> None:
    rep = clearance_slivers(plan, g, printer, foreign)
    dev = rep.deviation
    tol = printer.tolerance_mm
    if dev.max(initial=0.0) <= tol:
        return
    t = int(np.argmax(dev))
    h = int(rep.near_hinge[t])
    if h < 0:  # no sliver found: name the tile's pivot nearest to its worst point
        hs = np.flatnonzero((plan.hinge_tiles == t).any(1))
        h = int(
            hs[
                np.argmin(
                    shapely.distance(shapely.points(plan.hinge_xy[hs]), plan.tiles[t].exterior)
                )
            ]
        )
    raise FabricationError(
        f"pinned hinges refused: tile {t} is too narrow beside the {g.hollow:g} mm clearance around the pivot of "
        f"hinge {h}: it keeps a sliver under one nozzle ({printer.nozzle_mm:g} mm) wide there, so its printed "
        f"outline would be {dev[t]:.2f} mm off the design (tolerance {tol:g} mm); "
        "scale the pattern up or reduce pin.ear_radius_mm"
    )
