"""Geometric proof that a pattern closes into both compact states (spec §6, §10).

:func:`verify_pattern` measures, with named tolerances:

* every tile simple (GEOS-valid, interior angles summing to 2π), CCW and not
  degenerate;
* per closed state: loop closure per hole, tiles congruent to the deployed
  tiles, holes of zero area, every folded gap closed (endpoints coincident for
  rhombus holes, or collinear with a T-junction for parallelogram holes),
  compactness (no overlaps, union area = sum of tile areas, no interior gaps,
  one outline), and agreement with a stored closed state;
* design residuals: edge pairs (or the parallelogram conditions) and rings per
  state, hinge sums when rigid deployability is claimed;
* the rigid deployment path, sampled at ``path_steps`` + 1 angles, when claimed;
* the shape of the outline against each recorded target curve (Hausdorff distance over the whole outline,
  deployed and closed states, against ``shape_tol``).

Closed states come from :func:`fabkiri.mechanics.contract.contract` (never
averaged); stored closed states are checked against them.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import shapely

from ..mechanics.contract import contract
from ..mechanics.deploy import place_rigid, rigid_angles
from ..pattern import geometry
from ..pattern.model import Pattern
from ..pattern.residuals import hinge_sums, state_residuals
from ..pattern.tessellation import tessellation
from ..pattern.topology import STATES, FoldRule
from . import geom
from .outlines import target_checks
from .report import Check, Report, measured

TIER_EXPORTED = 1e-9  # analytic or exported data, relative to the mean tile edge (spec §10)
TIER_OPTIMISED = 1e-5  # optimiser output
MIN_EDGE_REL = 1e-3
MIN_ANGLE_RAD = 1e-3
DEFAULT_PATH_STEPS = 32


@dataclass(frozen=True)
class Tolerances:
    length: float  # mm
    angle: float  # rad
    tile_size: float  # mm (mean tile edge)
    tier: str
    mm_angles: bool = False  # angle residuals compared as their displacement (rad x tile size) with ``length``

    @property
    def area(self) -> float:  # mm²: a length tolerance times the tile size
        return self.length * self.tile_size

    def describe(self) -> str:
        if self.mm_angles:
            return (f"{self.tier}: {self.length:.3g} mm for lengths, and for angles as their displacement at "
                    f"the tile size")
        return f"exact ({self.tier}): {self.length:.3g} mm, {self.angle:.3g} rad"


def fabrication_tolerances(tol_mm: float, tile_size: float, tier: str = "fabrication") -> Tolerances:
    """One tolerance in mm: lengths compare with it, angles by the displacement they cause at ``tile_size``."""
    return Tolerances(float(tol_mm), float(tol_mm) / float(tile_size), float(tile_size), tier, mm_angles=True)


def angle_check(name: str, rad: np.ndarray, sizes: np.ndarray | float, tol: Tolerances, worst: str, *,
                group: str, detail: str = "", applies: bool = True, id: str = "") -> Check:
    """An angle residual check: in rad (exact tier) or as mm of displacement at each item's tile size."""
    rad = np.asarray(rad, dtype=float)
    if not tol.mm_angles:
        return measured(name, _max(rad), tol.angle, "rad", worst=_worst(worst, rad), group=group, detail=detail,
                        applies=applies, id=id)
    mm = rad * np.broadcast_to(np.asarray(sizes, dtype=float), rad.shape)
    note = f"angle residual x tile size (largest angle {_max(rad):.3g} rad)"
    return measured(name, _max(mm), tol.length, "mm", worst=_worst(worst, mm), group=group,
                    detail=f"{detail}; {note}" if detail else note, applies=applies, id=id)


def tolerances(pattern: Pattern, tol_mm: float | None = None, tol_rad: float = 1e-6) -> Tolerances:
    """Resolve the tolerances: explicit mm (angles as displacement at the tile size), or the relative tier of spec §10."""
    size = pattern.tile_size
    if tol_mm is not None:
        return fabrication_tolerances(float(tol_mm), size)
    optimised = any(k in (pattern.design or {}) for k in ("solver", "solve", "residuals", "report"))
    rel = TIER_OPTIMISED if optimised else TIER_EXPORTED
    return Tolerances(rel * size, float(tol_rad), size, "optimiser output" if optimised else "exported data")


def rigid_claimed(pattern: Pattern) -> bool:
    """Whether the pattern claims rigid deployability.

    A design report may say so (``rigid``, ``rigid_deployable`` or
    ``options.rigid``); an undesigned standard lattice is rigid-deployable.
    """
    d = pattern.design or {}
    for src in (d, d.get("options") or {}, d.get("constraints") or {}):
        if isinstance(src, dict):
            for key in ("rigid_deployable", "rigid"):
                if key in src and src[key] is not None:
                    return bool(src[key])
    lat = pattern.lattice or {}
    return not d and lat.get("kind") == "quad"


# ----------------------------------------------------------------- helpers


def _corner_index(tiles: np.ndarray, t: np.ndarray, n: np.ndarray) -> np.ndarray:
    return (tiles[t] == n[..., None]).argmax(axis=-1)


def _hole_outline(pattern: Pattern, Y: np.ndarray) -> np.ndarray:
    """``(K, 2m, 2)``: each hole walked along its ``m`` tile edges, in state ``Y``."""
    top = pattern.topology
    K = top.n_holes
    t = top.hole_tiles  # edge c -> c+1 belongs to hole_tiles[:, c]
    n0 = top.hole_nodes
    n1 = np.roll(top.hole_nodes, -1, axis=1)
    p0 = Y[t, _corner_index(top.tiles, t, n0)]
    p1 = Y[t, _corner_index(top.tiles, t, n1)]
    return np.stack([p0, p1], axis=2).reshape(K, 2 * n0.shape[1], 2)


def _worst(prefix: str, values: np.ndarray) -> str | None:
    return f"{prefix} {int(np.argmax(values))}" if len(values) else None


def _max(values: np.ndarray) -> float:
    return float(np.max(values, initial=0.0)) if len(values) else 0.0


# ----------------------------------------------------------------- checks


def tile_checks(pattern: Pattern, tol: Tolerances) -> list[Check]:
    corners = pattern.corners()
    angles = geometry.corner_angles(corners)
    simple_sum = (corners.shape[1] - 2) * np.pi  # a simple CCW n-gon's angle sum
    angle_sum_off = np.abs(angles.sum(axis=1) - simple_sum)
    invalid = ~shapely.is_valid(shapely.polygons(corners))
    crossed = np.flatnonzero(invalid | (angle_sum_off > 1e-6))
    out = []
    detail = ""
    if len(crossed):
        sums = ", ".join(f"tile {t}: angle sum {np.degrees(angles[t].sum()):.0f}°" for t in crossed[:8])
        detail = f"self-intersecting tiles {crossed.tolist()} ({sums})"
    out.append(Check("tiles simple", ok=not len(crossed), value=int(len(crossed)), tol=0, unit="count",
                     worst=f"tile {int(crossed[0])}" if len(crossed) else None, detail=detail, group="tiles"))
    area = geometry.signed_areas(corners)
    out.append(measured("tiles counter-clockwise", float(area.min()), 0.0, "mm²", op=">=",
                        worst=_worst("tile", -area), group="tiles",
                        detail=f"clockwise or flat tiles: {np.flatnonzero(area <= 0).tolist()[:20]}"))
    i, j, depth = geom.overlap_depths(corners)  # hinged neighbours touch only at a corner: depth 0
    k = int(np.argmax(depth)) if len(depth) else None
    out.append(measured("deployed: no overlaps", _max(depth), tol.length, "mm", group="tiles",
                        worst=f"tiles {i[k]}/{j[k]}" if k is not None else None, id="deployed.no-overlaps",
                        detail=f"{int((depth > tol.length).sum())} overlapping pairs in the deployed state"))
    edges = geometry.edge_lengths(corners)
    out.append(measured("tiles min edge", float(edges.min()), MIN_EDGE_REL * tol.tile_size, "mm", op=">=",
                        worst=_worst("tile", -edges.min(axis=1)), group="tiles"))
    inner = np.minimum(angles, geometry.TWO_PI - angles)  # distance from a flat or folded corner
    out.append(measured("tiles min angle", float(inner.min()), MIN_ANGLE_RAD, "rad", op=">=",
                        worst=_worst("tile", -inner.min(axis=1)), group="tiles"))
    return out


def topology_checks(pattern: Pattern) -> list[Check]:
    """Counts of spec §10.2: one hole per independent cycle of the tile graph,
    every hinge a corner of one or two holes (or as many hole-less hinges as the kind's lattice has)."""
    top = pattern.topology
    tess = tessellation(pattern.kind)
    T, H, K = top.n_tiles, top.n_hinges, top.n_holes
    expected = H - T + 1
    holes_per_hinge = (top.gap_face >= 0).sum(axis=1)
    orphan = np.flatnonzero(holes_per_hinge == 0) if K else np.zeros(0, dtype=np.int64)
    bad = abs(K - expected)
    lat = pattern.lattice or {}
    detail = f"{T} tiles, {H} hinges, {len(top.free_nodes)} free corners, {K} holes (cycles: {expected})"
    counts = tess.lattice_counts
    if lat.get("rows") and lat.get("cols") and counts is not None:
        m, n = int(lat["rows"]), int(lat["cols"])
        holes, free, holeless = counts(m, n)
        bad += abs(K - holes) + abs(len(top.free_nodes) - free) + abs(len(orphan) - holeless)
        detail += f"; a {m}x{n} lattice expects {holes} holes and {free} free corners"
        if holeless:
            detail += f" and {holeless} hinges bordering no hole"
    elif tess.hinges_border_holes:
        bad += len(orphan)
    if len(orphan):
        detail += f"; hinges bordering no hole: {orphan[:10].tolist()}"
    return [Check("topology", ok=bad == 0, value=int(bad), tol=0, unit="count", group="tiles",
                  worst=f"hinge {int(orphan[0])}" if len(orphan) else None, detail=detail)]


def state_check_id(state: int | str, what: str) -> str:
    """The stable :attr:`Check.id` of a closed-state check, e.g. ``state1.loop-closure``."""
    return f"state{state}.{what}"


def closed_state_checks(pattern: Pattern, Y: np.ndarray, state: int | str, tol: Tolerances,
                        closure: np.ndarray | None = None) -> list[Check]:
    """Closedness and compactness of one closed state ``Y`` (T, n, 2)."""
    top = pattern.topology
    g = f"state {state}"
    out = []
    if closure is not None:
        out.append(measured(f"{g}: loop closure", _max(closure), tol.length, "mm",
                            worst=_worst("hole", closure), group=g, id=state_check_id(state, "loop-closure")))
    # congruence with the deployed tiles
    X = pattern.corners()
    dl = np.abs(geometry.edge_lengths(Y) - geometry.edge_lengths(X)).max(axis=1)
    da = np.abs(geometry.wrap_angle(geometry.corner_angles(Y) - geometry.corner_angles(X))).max(axis=1)
    _, fit = geom.tile_kabsch(X, Y)
    mirrored = np.flatnonzero(np.sign(geometry.signed_areas(Y)) != np.sign(geometry.signed_areas(X)))
    cong = np.maximum(dl, fit)
    cong[mirrored] = np.inf
    out.append(measured(f"{g}: tiles congruent (lengths)", _max(cong), tol.length, "mm",
                        worst=_worst("tile", cong), group=g,
                        detail=f"mirrored tiles {mirrored.tolist()}" if len(mirrored) else
                        "per-corner edge-length change and per-tile rigid-fit residual",
                        id=state_check_id(state, "congruent-lengths")))
    out.append(angle_check(f"{g}: tiles congruent (angles)", da, geometry.edge_lengths(X).mean(axis=1), tol, "tile",
                           group=g, id=state_check_id(state, "congruent-angles")))
    # holes of zero area, measured as an equivalent width 2|A|/perimeter (mm)
    if top.n_holes:
        outline = _hole_outline(pattern, Y)
        hole_area = np.abs(geometry.signed_areas(outline))
        perim = np.linalg.norm(np.roll(outline, -1, axis=1) - outline, axis=-1).sum(axis=1)
        hole_width = 2 * hole_area / np.maximum(perim, 1e-300)
    else:
        hole_area = hole_width = np.zeros(0)
    out.append(measured(f"{g}: holes closed", _max(hole_width), tol.length, "mm",
                        worst=_worst("hole", hole_width), group=g,
                        detail=f"equivalent width 2|area|/perimeter; largest |area| {_max(hole_area):.3g} mm²",
                        id=state_check_id(state, "holes-closed")))
    # every folded gap (hole fold corner or boundary notch) closed
    if isinstance(state, int) or str(state).isdigit():
        fold = top.fold(int(state))
        out.append(_folded_gaps(pattern, Y, fold, tol, g, state))
    out.extend(compactness_checks(Y, tol, g, _blame(pattern), state=state))
    return out


def _blame(pattern: Pattern) -> dict[int, int]:
    """Self-intersecting tiles and the tiles hinged to them -> the crossed tile."""
    crossed = geometry.self_intersecting_tiles(pattern.corners())
    out: dict[int, int] = {}
    for t in crossed.tolist():
        out[t] = t
        ht = pattern.topology.hinge_tiles
        for n in ht[(ht == t).any(1)].ravel().tolist():
            out.setdefault(n, t)
    return out


def _folded_gaps(pattern: Pattern, Y: np.ndarray, fold: FoldRule, tol: Tolerances, g: str,
                 state: int | str) -> Check:
    top = pattern.topology
    A, B = top.hinge_tiles.T
    cA, cB = top.hinge_corner.T
    eA, eB = fold.fold_corner_ends.T
    hA, hB = Y[A, cA], Y[B, cB]
    a, b = Y[A, eA], Y[B, eB]
    split = np.linalg.norm(hA - hB, axis=1)  # the hinge's two copies
    coincide = np.linalg.norm(a - b, axis=1)
    la, lb = np.linalg.norm(a - hA, axis=1), np.linalg.norm(b - hB, axis=1)
    a_short = la <= lb
    short_end = np.where(a_short[:, None], a, b)
    long_h = np.where(a_short[:, None], hB, hA)
    long_end = np.where(a_short[:, None], b, a)
    collinear = geom.point_segment_distance(short_end, long_h, long_end)
    gap = np.maximum(split, np.minimum(coincide, collinear))
    tjunction = int(((coincide > tol.length) & (collinear <= tol.length)).sum())
    kind = (f"{tjunction} folded gaps close as T-junctions (parallelogram holes)" if tjunction
            else "every folded gap closes with coincident endpoints (rhombus holes)")
    return measured(f"{g}: folded gaps closed", _max(gap), tol.length, "mm", worst=_worst("hinge", gap),
                    group=g, detail=kind, id=state_check_id(state, "folded-gaps"))


def compactness_checks(Y: np.ndarray, tol: Tolerances, g: str,
                       blame: dict[int, int] | None = None, state: int | str | None = None) -> list[Check]:
    """No overlaps, union area = sum of tile areas, no interior gaps, one outline.

    ``blame`` maps tiles to the self-intersecting tile they are (or are hinged
    to), so overlaps caused by a crossed tile are named as such. Given a
    ``state``, the checks carry its stable ids (``state1.no-overlaps``, ...).
    """
    ids = {w: "" if state is None else state_check_id(state, w)
           for w in ("no-overlaps", "union-area", "no-interior-gaps", "one-outline")}
    out = []
    i, j, inter = geom.overlap_depths(Y)
    bad = np.flatnonzero(inter > tol.length)
    order = bad[np.argsort(-inter[bad])]
    listed = ", ".join(f"tiles {i[k]}/{j[k]}: {inter[k]:.3g} mm" for k in order[:10])
    if len(order) > 10:
        listed += f", … ({len(order)} pairs)"
    k = int(np.argmax(inter)) if len(inter) else None
    cause = ""
    if len(order) and blame:
        culprits = [blame.get(int(i[m]), blame.get(int(j[m]))) for m in order]
        found = [c for c in culprits if c is not None]
        if len(found) == len(culprits):
            cause = f"; all caused by self-intersecting tile(s) {sorted(set(found))}"
        else:
            cause = f"; {len(found)} of {len(order)} caused by self-intersecting tiles"
    out.append(measured(f"{g}: no overlaps", _max(inter), tol.length, "mm",
                        worst=f"tiles {i[k]}/{j[k]}" if k is not None else None, group=g,
                        detail=(f"overlapping pairs (penetration depth): {listed}{cause}" if len(order) else
                                "largest penetration depth between any two tiles"), id=ids["no-overlaps"]))
    polys, _ = geom.tile_polygons(Y)
    areas = shapely.area(polys)
    total = float(areas.sum())
    union = geom.tiles_union(Y, max(tol.length, 1e-12 * tol.tile_size), coverage=not len(bad))
    deficit = abs(total - float(union.area))
    # a strip of the length tolerance along every tile edge, counted once
    half_perimeter = 0.5 * float(geometry.edge_lengths(Y).sum())
    out.append(measured(f"{g}: union area = sum of tile areas", deficit, max(tol.length * half_perimeter,
                                                                             1e-9 * total), "mm²",
                        worst=f"tiles {i[k]}/{j[k]}" if k is not None and len(order) else None, group=g,
                        detail=f"sum {total:.6g} mm², union {float(union.area):.6g} mm²", id=ids["union-area"]))
    gaps = [(2 * g.area / max(g.length, 1e-300), g.area, g) for g in enclosed_gaps(union)]
    big = [x for x in gaps if x[0] > tol.length]
    worst_gap = max(gaps, key=lambda x: x[0]) if gaps else None
    where = None
    if worst_gap is not None:
        c = worst_gap[2].representative_point()
        where = f"at ({c.x:.4g}, {c.y:.4g}) mm"
    out.append(measured(f"{g}: no interior gaps", worst_gap[0] if worst_gap else 0.0, tol.length, "mm",
                        worst=where, group=g,
                        detail=(f"{len(big)} enclosed gaps wider than the tolerance (largest {worst_gap[1]:.3g} mm²)"
                                if big and worst_gap else "equivalent width 2|area|/perimeter of enclosed gaps"),
                        id=ids["no-interior-gaps"]))
    # one outline: components after closing cracks narrower than the tolerance
    eps = max(tol.length, 1e-12 * tol.tile_size)
    closed = union.buffer(eps, join_style="mitre").buffer(-eps, join_style="mitre")
    n_parts = len(getattr(closed, "geoms", [closed])) if not closed.is_empty else 0
    out.append(Check(f"{g}: one outline", ok=n_parts == 1, value=n_parts, tol=1, unit="count", group=g,
                     op="==", detail="" if n_parts == 1 else f"the tiles form {n_parts} separate pieces",
                     id=ids["one-outline"]))
    return out


def enclosed_gaps(union: shapely.Geometry) -> list[shapely.Polygon]:
    """The uncovered regions enclosed by a tile union, as polygons.

    A hole ring of the union may enclose islands of tiles (a crack of rounding
    width around a block of tiles, as T-junctions of parallelogram holes
    leave): the gap is the ring minus the tiles inside it, not the ring.
    """
    parts = list(getattr(union, "geoms", [union]))
    rings = [shapely.Polygon(r) for part in parts for r in part.interiors]
    if not rings:
        return []
    if len(parts) > 1:  # islands exist: take them out of the rings they sit in
        rings = shapely.get_parts(shapely.difference(np.array(rings, dtype=object), union)).tolist()
    return [g for g in rings if not g.is_empty and g.area > 0]


def residual_checks(pattern: Pattern, tol: Tolerances, claimed: bool) -> list[Check]:
    top = pattern.topology
    x = pattern.nodes
    out = []
    # parallelogram holes (spec §2.9) are a quad fact; other kinds' fold pairs must be equal
    quad_holes = top.n_holes and top.hole_nodes.shape[1] == 4
    if quad_holes:
        hole_len = np.linalg.norm(x[np.roll(top.hole_nodes, -1, 1)] - x[top.hole_nodes], axis=-1)
        para = np.maximum(np.abs(hole_len[:, 0] - hole_len[:, 2]), np.abs(hole_len[:, 1] - hole_len[:, 3]))
    else:
        para = np.full(top.n_holes, np.inf)
    rhombus = bool((para <= tol.length).all()) and bool(
        (np.abs(hole_len - hole_len[:, :1]) <= tol.length).all()) if quad_holes else True
    for s in STATES:
        g = f"state {s}"
        r = state_residuals(pattern, s)
        fold = top.fold(s)
        # a hole's fold pair may differ when the hole is a parallelogram (spec §2.9)
        res = r.edge_pairs.copy()
        gap_face = top.gap_face[np.arange(top.n_hinges), fold.fold_gap]
        in_hole = gap_face >= 0
        res[in_hole] = np.minimum(res[in_hole], para[gap_face[in_hole]])
        detail = "equal fold-pair lengths, or opposite hole sides equal (parallelogram)"
        notch = ~in_hole
        if not rhombus and notch.any() and res[notch].max() > tol.length:
            # with parallelogram holes a notch may close as a T-junction on the
            # outline; whether it closes is the 'folded gaps closed' check
            detail += (f"; notch pairs differ by up to {res[notch].max():.3g} mm (T-junctions on the outline, "
                       f"not counted)")
            res[notch] = 0.0
        out.append(measured(f"{g}: edge pairs", _max(res), tol.length, "mm", worst=_worst("hinge", res),
                            group="design", detail=detail, id=state_check_id(s, "edge-pairs")))
        rings = np.abs(r.rings)
        wrapped = r.wrapped_tiles.tolist()
        out.append(angle_check(f"{g}: rings", rings, tol.tile_size, tol, "hole", group="design",
                               id=state_check_id(s, "rings"), detail=f"wrapped by 2π because of tiles {wrapped}" if wrapped else ""))
    if not claimed and not tessellation(pattern.kind).rigid_family:
        return out  # θA+θB = π is the quad rigid family's test; nothing to report for other kinds
    hs = np.abs(hinge_sums(pattern))
    out.append(angle_check("hinge sums", hs, tol.tile_size, tol, "hinge", group="design", applies=claimed,
                           detail="" if claimed else "rigid deployability not claimed; measured for information"))
    return out


# ----------------------------------------------------------------- rigid path


def rigid_path(pattern: Pattern, Y1: np.ndarray, omegas: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Tile corners along the rigid path from state 1 (spec §7), and hinge mismatch per step.

    Tiles turn by ±ω (checkerboard, sign from the deployed state); translations
    are placed breadth-first so each tree hinge's two copies coincide; the
    mismatch of every hinge is then measured. Returns ``(S, T, 4, 2)`` and ``(S,)``.
    """
    eps, _ = rigid_angles(pattern, {1: Y1})
    corners = place_rigid(pattern, Y1, eps, np.asarray(omegas, dtype=float))
    top = pattern.topology
    A, B = top.hinge_tiles.T
    cA, cB = top.hinge_corner.T
    mismatch = np.linalg.norm(corners[:, A, cA] - corners[:, B, cB], axis=-1).max(axis=1, initial=0.0)
    return corners, mismatch


def rigid_path_checks(pattern: Pattern, Y1: np.ndarray, Y2: np.ndarray, tol: Tolerances,
                      steps: int = DEFAULT_PATH_STEPS) -> list[Check]:
    omegas = np.linspace(0.0, np.pi / 2, steps + 1)
    corners, mismatch = rigid_path(pattern, Y1, omegas)
    out = [measured("rigid path: hinge closure", _max(mismatch), tol.length, "mm",
                    worst=f"ω = {np.degrees(omegas[int(np.argmax(mismatch))]):.4g}°", group="rigid path",
                    detail=f"{len(omegas)} samples of ω on [0, 90°]")]
    is_convex = geom.convex(Y1)
    depth = np.zeros(len(omegas))
    pairs: list[tuple[int, int] | None] = [None] * len(omegas)  # the deepest pair per sample
    for s in range(len(omegas)):
        depth[s], pairs[s] = geom.max_overlap_depth(corners[s], is_convex)
    k = int(np.argmax(depth))
    pk = pairs[k]
    out.append(measured("rigid path: no overlap", _max(depth), tol.length, "mm",
                        worst=(f"tiles {pk[0]}/{pk[1]} at ω = {np.degrees(omegas[k]):.4g}°"
                               if pk else None), group="rigid path",
                        detail="largest penetration depth between any two tiles"))
    end = geometry.aligned_distance(corners[-1], Y2)
    out.append(measured("rigid path: ends in state 2", end, tol.length * np.sqrt(len(Y1)), "mm",
                        group="rigid path", detail="aligned distance of the ω = 90° frame to state 2"))
    return out


# ----------------------------------------------------------------- entry point


def verify_pattern(pattern: Pattern, tol_mm: float | None = None, tol_rad: float = 1e-6, *,
                   rigid: bool | None = None, path_steps: int = DEFAULT_PATH_STEPS,
                   shape_tol: str | tuple = "2%") -> Report:
    """Verify that ``pattern`` closes into both compact states.

    ``tol_mm`` None uses the relative tier of spec §10 (1e-9 of the mean tile
    edge for exported data, 1e-5 for optimiser output). ``rigid`` overrides
    whether rigid deployability is claimed (default: :func:`rigid_claimed`);
    when claimed, the rigid path is sampled at ``path_steps`` + 1 angles. ``shape_tol``: the largest
    Hausdorff distance of an outline to its stored target (:func:`target_checks`).
    """
    tol = tolerances(pattern, tol_mm, tol_rad)
    claimed = rigid_claimed(pattern) if rigid is None else bool(rigid)
    rep = Report(subject=pattern.name or "(unnamed pattern)", kind="pattern",
                 meta={"tol_mm": tol.length, "tol_rad": tol.angle, "tile_size_mm": tol.tile_size,
                       "tier": tol.tier, "tolerance": tol.describe(), "tiles": pattern.n_tiles, "holes": pattern.topology.n_holes,
                       "rigid_claimed": claimed})
    for chk in topology_checks(pattern) + tile_checks(pattern, tol):
        rep.add(chk)
    states: dict[int, np.ndarray] = {}
    for s in STATES:
        c = contract(pattern, s)
        Y = pattern.contracted.get(s, c.corners)
        states[s] = Y
        for chk in closed_state_checks(pattern, Y, s, tol, closure=c.hole_closure):
            rep.add(chk)
        if s in pattern.contracted:
            d = geometry.aligned_distance(c.corners, Y)
            rep.add(measured(f"state {s}: stored state matches computed", d, tol.length * np.sqrt(pattern.n_tiles),
                             "mm", group=f"state {s}", detail="after one proper rigid alignment"))
    for chk in residual_checks(pattern, tol, claimed):
        rep.add(chk)
    if claimed:
        for chk in rigid_path_checks(pattern, states[1], states[2], tol, path_steps):
            rep.add(chk)
    for chk in target_checks(pattern, states, shape_tol):
        rep.add(chk)
    from .outlines import contracted_outline_checks
    from .seam import seam_checks

    for chk in contracted_outline_checks(pattern, states, tol) + seam_checks(pattern, states, tol):
        rep.add(chk)
    return rep
