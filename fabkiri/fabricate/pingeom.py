"""2D plan of print-in-place pinned hinges on a closed state (fabrication.md §3.4).

The two coincident hinges of a node are stacked coaxially on four ear levels:
tile A of a hinge owns the lower ear and the pin, tile B the ring. Here: the
levels and radii from the printer preset, where each pin sits and which levels
it uses (or why the geometry refuses pins), the turn of each pivot's polygons,
and the slivers a pivot clearance leaves beside a tile's outline.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import shapely
from shapely.geometry import MultiPolygon, Polygon

from ..errors import FabricationError
from ..kdtree import KDTree
from ..pattern.model import Pattern
from ..pattern.tessellation import tessellation
from .printers import Printer
from .printgeom import CIRCLE_SEGMENTS, ClosedPlan, grow_back, regular_polygon

MASK_MARGIN_MM = 1e-3  # the tile check masks the pivot clearances with this margin
PIN_STACK = 2  # hinges stacked coaxially at one pivot: four ear levels, two per hinge


def kind_refusal(pattern: Pattern) -> str:
    """Why no scale prints a pattern of this tessellation kind pinned ('' if its kind can be): the
    sweep follows the rigid deployment path, which exists for a kind with a rigid family only,
    and a pivot stacks two hinges, while a closed state may join ``hole_arity / 2`` at a point."""
    kind = tessellation(pattern.kind)
    if not kind.rigid_family:
        return (
            f"pinned hinges refused: rigid pinned tiles need the rigid deployment path, which {pattern.kind} "
            f"patterns do not have, and a pivot stacks {PIN_STACK} hinges while a {pattern.kind} closed state "
            f"joins {kind.hole_arity // 2} at a point; use --style strips or tiles-and-strips"
        )
    return ""


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
    g = PinGeometry(
        ear=r,
        hollow=r + c,
        pin_bottom=rp,
        pin_top=rp + flare,
        hole_bottom=rp + ch,
        hole_top=rp + flare + ch,
    )
    wall = r - g.hole_top
    if wall < 2 * printer.nozzle_mm - 1e-9:
        raise FabricationError(
            f"pinned hinges: the ear ring wall is {wall:.2f} mm (ear radius {r:g} mm, pin {rp:g} mm, clearance "
            f"{c:g} mm), under two nozzle widths ({2 * printer.nozzle_mm:g} mm); raise pin.ear_radius_mm"
        )
    if rp < printer.nozzle_mm:
        raise FabricationError(
            f"pin radius {rp:g} mm is under one nozzle width ({printer.nozzle_mm:g} mm)"
        )
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

    if why := kind_refusal(pattern):
        raise FabricationError(why)
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
        dist, _ = KDTree(pivots).query(pivots, k=2)
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
    radii = np.array(
        [g.ear, g.pin_bottom, g.pin_top]
        + [r / np.cos(np.pi / n) for r in (g.hollow, g.hole_bottom, g.hole_top)]
    )
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
        xy = (
            c + radii[None, :, None, None] * np.stack([np.cos(ang), np.sin(ang)], -1)[:, None]
        )  # (P, R, n, 2)
        d = shapely.distance(shapely.multipoints(xy.reshape(PHASES, -1, 2)), edges)
        phase[h] = cand[int(np.argmax(d))]
    return phase


def clearance_discs(plan: ClosedPlan, g: PinGeometry) -> np.ndarray:
    """Per hinge, the disc cleared around its pivot (circumscribed polygon, as the solids)."""
    return np.array(
        [regular_polygon(p, g.hollow, circumscribed=True) for p in plan.hinge_xy], dtype=object
    )


def clearance_mask(points: np.ndarray, g: PinGeometry) -> Polygon | MultiPolygon:
    """The pivot discs left out of the tile-outline comparison (round by design)."""
    return shapely.union_all([regular_polygon(p, g.hollow + MASK_MARGIN_MM, True) for p in points])


def pinned_sections(plan: ClosedPlan, g: PinGeometry) -> np.ndarray:
    """Per tile, its section where it carries no ear of its own (the axial
    gaps): the shrunk tile minus the clearance discs of all its pivots."""
    discs = clearance_discs(plan, g)
    A, B = plan.hinge_tiles.T
    out = np.empty(len(plan.tiles), dtype=object)
    for t in range(len(plan.tiles)):
        hs = np.flatnonzero((A == t) | (B == t))
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
        printable[t] = S[t].difference(
            shapely.buffer(shapely.union_all(cut), eps, join_style="mitre")
        )
    mask = clearance_mask(plan.hinge_xy, g)
    design = shapely.difference(shapely.polygons(plan.corners), mask)
    built = _outline_deviation(shapely.difference(grow_back(S, plan.shrink_mm), mask), design)
    core_dev = _outline_deviation(
        shapely.difference(grow_back(printable, plan.shrink_mm), mask), design
    )
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
