"""The ``pinned`` print style: print-in-place pin joints.

The hinges that coincide at a point of the closed state are stacked coaxially,
two ear levels each (see :mod:`..pingeom`: quads two hinges, kagome three).
Besides the job: the scales at which a pattern prints pinned on a bed, and a
collision sweep of the printed tiles along a rigid deployment path (the rigid
path of the quad family, or the kind's deployment path where it keeps every
tile rigid).
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import TYPE_CHECKING

import numpy as np
import shapely

from ....errors import FabricationError
from ....pattern.model import Pattern
from .. import geometry as printgeom
from .. import pingeom
from ..build import PrintJob, Realised, StyleChecks, centre_shift, fits, scaled
from ..geometry import regular_polygon
from ..printers import Printer
from ..solid import Body, Prism, manifold_of, section_polys, translate_body

if TYPE_CHECKING:
    from ..checks import MeshReport


def build(pattern: Pattern, state: int, printer: Printer) -> PrintJob:
    """Print-in-place pinned tiles, or :class:`FabricationError` saying why not."""
    plan = printgeom.closed_plan(pattern, state, printer)
    pins = pingeom.pin_plan(pattern, plan, printer)
    fits(plan.bounds, printer, "the closed pattern")
    A, B = plan.hinge_tiles.T
    at_tile = [np.flatnonzero((A == t) | (B == t)).tolist() for t in range(len(plan.tiles))]
    foreign = list(zip(pins.foreign, pins.foreign_phase, strict=True))
    # the same tile with its pivot polygons turned: tried in turn when a turn
    # leaves a near-degenerate meeting that a float32 file cannot keep 2-manifold
    # (each tile's clearances are circumscribed and its ears inscribed, so
    # tiles need not share a turn)
    bodies = []
    for t in range(len(plan.tiles)):
        first = _tile_body(plan, pins, printer, (at_tile[t], foreign[t]), t, 0.0)
        alts = tuple(
            _tile_body(plan, pins, printer, (at_tile[t], foreign[t]), t, (j + 0.5) / pingeom.PHASES)
            for j in range(pingeom.PHASES)
        )
        bodies.append(replace(first, variants=alts))
    dx, dy = centre_shift(plan.bounds, printer)
    beds = [[translate_body(b, dx, dy) for b in bodies]]
    return PrintJob("pinned", state, printer, plan, beds, (dx, dy), pins=pins)


def _tile_body(
    plan: printgeom.ClosedPlan,
    pins: pingeom.PinPlan,
    printer: Printer,
    pivots: tuple[list[int], tuple[np.ndarray, np.ndarray]],
    t: int,
    turn: float,
) -> Body:
    """Tile ``t`` with the pivots of its hinges (``pivots``: its own hinges, and its foreign corners,
    :func:`~..pingeom.foreign_corners`): clearances cut, ears, pins and rings added; the pivot polygons
    turned by ``turn`` of a step."""
    hs, foreign = pivots
    lv, g = pins.levels, pins.geometry
    T = lv.thickness
    A, B = plan.hinge_tiles.T
    ph = pins.phase if pins.phase is not None else np.zeros(plan.n_hinges)
    X = plan.tiles[t]
    ops: list[tuple[str, Prism]] = [("add", Prism((X,), 0.0, T))]
    poly = {
        h: (lambda r, circ, h=h: regular_polygon(plan.hinge_xy[h], r, circ, phase=ph[h] + turn))
        for h in hs
    }
    for p, fp in zip(*foreign, strict=True):  # a free corner on a pivot in a closed state
        ops.append(
            ("sub", Prism((regular_polygon(p, g.hollow, True, phase=fp + turn),), -1.0, T + 1.0))
        )
    # A tile's corner at a pivot is cleared through the full height: the pivot's
    # own partner turns in one half, and the hinge that meets it in either
    # closed state stacks its ears in the other half; at its own ear level the
    # tile is left whole and the ear disc added. (Cutting the full height and
    # adding back tile ∩ disc would meet the cut at points computed twice, a
    # nanometre apart: edges shared by four faces once written as float32.)
    for h in hs:
        z0, z1 = lv.level(pins.level[h] + (0 if t == A[h] else 1))
        if z0 > 0.0:  # (a cut merely touching a face would leave a zero-thickness seam)
            ops.append(("sub", Prism((poly[h](g.hollow, True),), -1.0, z0)))
        if z1 < T:
            ops.append(("sub", Prism((poly[h](g.hollow, True),), z1, T + 1.0)))
    for h in hs:
        k = pins.level[h] + (0 if t == A[h] else 1)
        z0, z1 = lv.level(k)
        ops.append(("add", Prism((poly[h](g.ear, False),), z0, z1)))
        p = tuple(plan.hinge_xy[h])
        if t == A[h]:  # the pin: straight through its ear and the gap, flared through the ring
            zr0, zr1 = lv.level(k + 1)
            ops.append(("add", Prism((poly[h](g.pin_bottom, False),), z0, zr0)))
            ops.append(
                (
                    "add",
                    Prism((poly[h](g.pin_bottom, False),), zr0, zr1, g.pin_top / g.pin_bottom, p),
                )
            )
    for h in hs:
        if t == B[h]:
            z0, z1 = lv.level(pins.level[h] + 1)
            p = tuple(plan.hinge_xy[h])
            ops.append(
                (
                    "sub",
                    Prism(
                        (poly[h](g.hole_bottom, True),),
                        z0 - 1e-3,
                        z1 + 1e-3,
                        g.hole_top / g.hole_bottom,
                        p,
                    ),
                )
            )
    return Body(f"tile-{t:04d}", "tile", tuple(ops), printer.tile_material)


def _pinned_plans(pattern: Pattern, state: int, printer: Printer) -> str | None:
    """Why pinned hinges cannot be printed at this size on this bed (``None``: they can)."""
    try:
        plan = printgeom.closed_plan(pattern, state, printer)
        pingeom.check_pins(pattern, plan, printer)
        fits(plan.bounds, printer, "the closed pattern")
    except FabricationError as exc:
        return str(exc)
    return None


def pinned_scale_range(
    pattern: Pattern, state: int, printer: Printer, step: float = 0.01
) -> tuple[float, float] | None:
    """The smallest scale factor (to ``step``) at which the pattern prints pinned on
    the printer's bed, and the largest that fits the bed; ``None`` if none does.

    The refusals that depend on size (pivots too close, ears reaching foreign
    tiles, slivers beside a clearance) ease as the pattern grows, until it no
    longer fits the bed: bisect between the given size and the largest that fits."""
    c = printgeom.closed_corners(pattern, state).reshape(-1, 2)
    (x0, y0), (x1, y1) = c.min(0), c.max(0)
    bx, by, _ = printer.bed_mm
    kmax = (
        np.floor(min(bx / (x1 - x0), by / (y1 - y0)) / step) * step
    )  # the shrunk tiles fit inside
    if _pinned_plans(scaled(pattern, kmax), state, printer) is not None:
        return None
    lo, hi = step, kmax  # lo: fails or below every feasible size
    if _pinned_plans(scaled(pattern, lo), state, printer) is None:
        return lo, kmax
    while hi - lo > step * 0.999:
        mid = np.round(0.5 * (lo + hi) / step) * step
        if mid in (lo, hi):
            break
        if _pinned_plans(scaled(pattern, mid), state, printer) is None:
            hi = mid
        else:
            lo = mid
    return float(hi), float(kmax)


def pinned_advice(pattern: Pattern, state: int, printer: Printer, scale: float = 1.0) -> str:
    """Which ``--scale`` prints the pattern pinned on this printer (``scale``: the
    factor already applied to ``pattern``)."""
    try:
        rng = pinned_scale_range(pattern, state, printer)
    except FabricationError as exc:
        return f"no scale was searched ({exc})"
    bx, by, _ = printer.bed_mm
    if rng is None:
        c = printgeom.closed_corners(pattern, state).reshape(-1, 2)
        kmax = min(bx / np.ptp(c[:, 0]), by / np.ptp(c[:, 1]))
        why = _pinned_plans(scaled(pattern, np.floor(kmax * 100) / 100), state, printer)
        return (
            f"no scale prints it pinned on the {bx:g} x {by:g} mm bed of {printer.name}: at the largest that "
            f"fits ({scale * kmax:.2f}x) {why}"
        )
    lo, hi = rng
    return (
        f"it prints pinned on the {bx:g} x {by:g} mm bed of {printer.name} from --scale {scale * lo:.2f} "
        f"to {scale * hi:.2f}"
    )


def clearances(r: Realised, rep: MeshReport) -> None:
    """Pinned style: every pair of tiles meeting at a pivot, measured in 3D."""
    job, pr = r.job, r.job.printer
    plan = job.plan
    req = min(pr.radial_clearance_mm, pr.axial_clearance_mm)
    rep.required_clearance_mm = req
    ms = r.manifolds[0]
    pairs = set()
    for group in pingeom.pivot_tiles(plan):
        g = sorted(group)
        pairs |= {(a, b) for ai, a in enumerate(g) for b in g[ai + 1 :]}
    worst = np.inf
    for a, b in sorted(pairs):
        worst = min(worst, ms[a].min_gap(ms[b], 2 * pr.gap_mm + 1.0))
    rep.min_clearance_mm = None if worst == np.inf else float(worst)
    if rep.min_clearance_mm is not None and rep.min_clearance_mm < req * (1 - 1e-6):
        rep.problems.append(f"clearance {rep.min_clearance_mm:.4f} mm below {req:g} mm")
    for t, m in enumerate(ms):
        if len(m.decompose()) != 1:
            rep.problems.append(f"tile {t} falls apart into {len(m.decompose())} pieces")
            break


def tiles(r: Realised, mesh=None):
    """All tiles as one solid (or ``mesh``, e.g. re-read from the STL), sectioned in
    the axial gap between the two hinge halves, with the pivots' clearance discs
    masked (round by design)."""
    import manifold3d as m3d

    job = r.job
    assert job.pins is not None  # a pinned job always carries its pin plan
    lv = job.pins.levels
    z = lv.gaps()[1]  # the axial gap above the bottom hinges' ears: no pin crosses it
    mask = pingeom.clearance_mask(
        pingeom.mask_points(job.plan, list(job.pins.foreign)) + list(job.shift), job.pins.geometry
    )
    solid = (
        manifold_of(mesh)
        if mesh is not None
        else m3d.Manifold.batch_boolean(r.manifolds[0], m3d.OpType.Add)
    )
    return solid, z, mask


@dataclass
class SweepCheck:
    """Pinned tiles moved along the rigid deployment path (closed state 1 ->
    deployed -> closed state 2), level by level: the largest overlap area
    between two different tiles and their smallest distance, over all frames."""

    frames: int
    levels_mm: list[float]
    max_overlap_mm2: float
    min_distance_mm: float
    worst: str
    ok: bool

    def to_dict(self) -> dict:
        return dict(self.__dict__)


RIGID_MISFIT_REL = (
    1e-6  # a path keeps the tiles rigid if rigid tiles meet at every hinge to this (tile sizes)
)


def rigid_tiles_path(pattern: Pattern, steps: int = 24):
    """The deployment path the rigid pinned tiles follow: the quad family's rigid path (hinge sums
    π), else the elastic path of the pattern's kind (its default driver), accepted only where it
    keeps every tile rigid: each tile fitted rigidly (Kabsch) to every frame, its hinges' two
    corners must meet to ``RIGID_MISFIT_REL`` tile sizes. Otherwise :class:`FabricationError`
    with the worst hinge, its misfit and where on the path: pinned tiles would have to bend."""
    from ....errors import CheckFailed
    from ....mechanics.deploy import elastic_path, is_rigid_deployable, rigid_path

    try:
        if is_rigid_deployable(pattern, tol_rad=1e-6):
            return rigid_path(pattern, steps, tol_rad=1e-6)
        path = elastic_path(pattern, steps)
    except CheckFailed as exc:
        raise FabricationError(
            f"pinned hinges refused: no deployment path to sweep ({exc})"
        ) from None
    misfit = hinge_misfit(pattern, path.corners)
    f, h = np.unravel_index(int(np.argmax(misfit)), misfit.shape)
    if misfit[f, h] > RIGID_MISFIT_REL * pattern.tile_size:
        raise FabricationError(
            f"pinned hinges refused: the pattern's deployment path ({path.driver} driver, max E = "
            f"{path.energy.max():.3g}) bends its tiles, and rigid tiles would miss hinge {h} by "
            f"{misfit[f, h]:.3g} mm at t = {path.t[f]:.3f}; no rigid path between the closed states is "
            "known, so pinned tiles could not reconfigure; use --style strips or tiles-and-strips"
        )
    return path


def hinge_misfit(pattern: Pattern, frames: np.ndarray) -> np.ndarray:
    """Per frame and hinge, how far apart the hinge's two corners are when every tile is the design
    tile placed rigidly (Kabsch) on that frame's tile (mm): zero on a path of rigid tiles."""
    from ....pattern import geometry

    design = pattern.corners()  # (T, n, 2)
    top = pattern.topology
    th = geometry.kabsch_angles(np.broadcast_to(design, frames.shape), frames)  # (F, T)
    local = design - design.mean(axis=-2, keepdims=True)
    placed = geometry.rotate(local[None], th[..., None]) + frames.mean(axis=-2, keepdims=True)
    A, B = top.hinge_tiles.T
    cA, cB = top.hinge_corner.T
    return np.linalg.norm(placed[:, A, cA] - placed[:, B, cB], axis=-1)


def sweep_pinned(
    pattern: Pattern, r: Realised, steps: int = 24, overlap_tol_mm2: float = 1e-6
) -> SweepCheck:
    """Collision sweep of the printed pinned tiles (sections of the solids at
    every ear level and axial gap) along :func:`rigid_tiles_path`."""
    from ....pattern import geometry

    job = r.job
    if job.style != "pinned":
        raise FabricationError("the deployment sweep is for pinned tiles")
    assert job.pins is not None  # a pinned job always carries its pin plan
    lv = job.pins.levels
    zs = [0.5 * sum(lv.level(k)) for k in range(lv.count)] + lv.gaps()
    back = -np.asarray(job.shift)
    T = len(job.plan.tiles)
    sections = {
        z: [np.array(section_polys(m, z), dtype=object) for m in r.manifolds[0]] for z in zs
    }
    for z in zs:
        sections[z] = [shapely.transform(g, lambda c: c + back) for g in sections[z]]
    path = rigid_tiles_path(pattern, steps)
    src = job.plan.corners
    worst_area, worst_dist, worst = 0.0, np.inf, ""
    for f in range(len(path.t)):
        poses = [geometry.kabsch(src[t], path.corners[f, t]) for t in range(T)]
        for z in zs:
            parts: list = []  # every moved section piece, and the tile it belongs to
            owners: list[int] = []
            for t in range(T):
                th, tr = poses[t]
                moved = shapely.transform(
                    sections[z][t], lambda c, th=th, tr=tr: geometry.rotate(c, th) + tr
                )
                parts.extend(moved)
                owners.extend([t] * len(moved))
            geoms = np.array(parts, dtype=object)
            owner = np.asarray(owners)
            i, j = shapely.STRtree(geoms).query(geoms, predicate="dwithin", distance=1.0)
            sel = (i < j) & (owner[i] != owner[j])
            if not sel.any():
                continue
            i, j = i[sel], j[sel]
            area = shapely.area(shapely.intersection(geoms[i], geoms[j]))
            dist = shapely.distance(geoms[i], geoms[j])
            k = int(np.argmax(area))
            if area[k] > worst_area:
                worst_area = float(area[k])
                worst = f"tiles {owner[i[k]]}/{owner[j[k]]} at z = {z:.2f} mm, t = {path.t[f]:.3f}"
            worst_dist = min(worst_dist, float(dist.min()))
    return SweepCheck(
        frames=len(path.t),
        levels_mm=[round(z, 4) for z in zs],
        max_overlap_mm2=worst_area,
        min_distance_mm=worst_dist,
        worst=worst,
        ok=worst_area <= overlap_tol_mm2,
    )


def pinned_checks(pattern: Pattern, r: Realised, rep: MeshReport) -> StyleChecks:
    """The printed tiles moved along the rigid deployment path must not collide."""
    sweep = sweep_pinned(pattern, r)
    rep.sweep = sweep.to_dict()
    out = StyleChecks()
    if not sweep.ok:
        out.problems.append(
            f"pinned tiles collide while reconfiguring: {sweep.max_overlap_mm2:.3g} mm² overlap "
            f"({sweep.worst})"
        )
    return out
