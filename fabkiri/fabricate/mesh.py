"""Printable solids of a closed state: manifold3d for booleans, trimesh for files.

Every body is described once as an ordered list of prism operations
(:class:`Body`), so the meshes here and the STEP solids of
:mod:`fabkiri.fabricate.cad` are the same solids. Three styles:

* ``strips`` – one flat flexible strip per hinge (for laser-cut tiles), laid
  out on as many print beds as needed, each part named by its hinge;
* ``tiles-and-strips`` – rigid tiles with the strips recessed flush into
  pockets, two bodies for two materials;
* ``pinned`` – print-in-place pin joints, the two coincident hinges of a node
  stacked coaxially on four ear levels (see :mod:`.printgeom`).
"""

from __future__ import annotations

import io
import itertools
import json
from collections.abc import Iterable
from dataclasses import dataclass, field, replace

import numpy as np
import shapely
import shapely.affinity
from shapely.geometry import Polygon
from shapely.geometry.polygon import orient

from ..errors import FabricationError
from ..pattern.model import Pattern
from . import printgeom
from .printers import Printer
from .printgeom import regular_polygon

STYLES = ("strips", "tiles-and-strips", "pinned")
SECTION_NOISE_MM = 1e-4  # vertex noise of sliced meshes (float32 STL: ~1e-5 mm at bed size)


# ---------------------------------------------------------------- CSG spec

@dataclass(frozen=True, eq=False)
class Prism:
    """Disjoint polygons extruded from ``z0`` to ``z1``; with ``scale_top`` the
    top is scaled about ``centre`` (a frustum)."""

    polygons: tuple[Polygon, ...]
    z0: float
    z1: float
    scale_top: float = 1.0
    centre: tuple[float, float] = (0.0, 0.0)


@dataclass(frozen=True, eq=False)
class Body:
    """A named solid: prisms added and subtracted in order."""

    name: str
    kind: str  # "tile", "hinge", "tiles", "hinges"
    ops: tuple[tuple[str, Prism], ...]
    material: str = ""
    variants: tuple[Body, ...] = ()  # the same part described otherwise, tried if this one's file is not 2-manifold


def _rings(polys: Iterable[Polygon]) -> list[np.ndarray]:
    rings = []
    for p in polys:
        for g in getattr(p, "geoms", [p]):
            if g.is_empty:
                continue
            g = orient(g, 1.0)
            rings.append(np.asarray(g.exterior.coords)[:-1])
            rings.extend(np.asarray(r.coords)[:-1] for r in g.interiors)
    return rings


def float32_grid(extent_mm: float) -> float:
    """The finest power-of-two grid (mm) whose points up to ``extent_mm`` from the origin
    float32 stores exactly (24-bit significand)."""
    return float(2.0 ** (np.ceil(np.log2(max(extent_mm, 1.0))) - 23))


def bed_grid(printer: Printer) -> float:
    """:func:`float32_grid` of everything printed on this bed (cutting prisms reach 1 mm past it)."""
    return float32_grid(max(printer.bed_mm) + 2.0)


def _manifold(prism: Prism, grid: float = 0.0):
    """The prism as a manifold; with ``grid`` its outlines are snap-rounded onto it first,
    so two distinct outline vertices never become one once written in float32 (a weld
    that leaves edges shared by four faces) and no edge is shorter than the grid."""
    import manifold3d as m3d

    polys = prism.polygons if not grid else (shapely.set_precision(shapely.union_all(prism.polygons), grid),)
    cs = m3d.CrossSection(_rings(polys), fillrule=m3d.FillRule.Positive)
    h = prism.z1 - prism.z0
    if prism.scale_top != 1.0:
        cx, cy = prism.centre
        return (m3d.Manifold.extrude(cs.translate((-cx, -cy)), h, scale_top=(prism.scale_top, prism.scale_top))
                .translate((cx, cy, prism.z0)))
    return m3d.Manifold.extrude(cs, h).translate((0.0, 0.0, prism.z0))


def realise(body: Body, grid: float = 0.0):
    """The manifold3d solid of a body (outlines snapped to ``grid`` mm, see :func:`_manifold`)."""
    import manifold3d as m3d

    acc = m3d.Manifold()
    ops = [(op, prism) for op, prism in body.ops if any(not p.is_empty for p in prism.polygons)]  # e.g. no bottom strip
    for op, run in itertools.groupby(ops, key=lambda o: o[0]):  # a run of adds (or subs) as one batched union
        ms = [_manifold(prism, grid) for _, prism in run]
        m = ms[0] if len(ms) == 1 else m3d.Manifold.batch_boolean(ms, m3d.OpType.Add)
        acc = acc + m if op == "add" else acc - m
    return acc


def to_trimesh(manifold):
    import trimesh

    mesh = manifold.to_mesh64()
    return trimesh.Trimesh(np.asarray(mesh.vert_properties)[:, :3].astype(np.float64),
                           np.asarray(mesh.tri_verts).astype(np.int64), process=False)


def translate_body(body: Body, dx: float, dy: float) -> Body:
    ops = tuple((op, Prism(tuple(shapely.affinity.translate(p, dx, dy) for p in pr.polygons), pr.z0, pr.z1,
                           pr.scale_top, (pr.centre[0] + dx, pr.centre[1] + dy))) for op, pr in body.ops)
    return Body(body.name, body.kind, ops, body.material, tuple(translate_body(v, dx, dy) for v in body.variants))


# ------------------------------------------------------------- the styles

@dataclass(frozen=True, eq=False)
class PrintJob:
    """Everything one ``fabkiri print`` run produces, before writing.

    ``beds[k]`` lists the bodies printed together on bed k; ``shift`` moved the
    closed-state plan onto the bed (for whole-pattern styles).
    """

    style: str
    state: int
    printer: Printer
    plan: printgeom.ClosedPlan
    beds: list[list[Body]]
    shift: tuple[float, float] = (0.0, 0.0)
    strips: printgeom.Strips | None = None
    pins: printgeom.PinPlan | None = None
    placements: list[dict] = field(default_factory=list)  # strips style: where each part went
    unlabelled: list[int] = field(default_factory=list)  # strips too small for their engraved ID
    layout: str = "recessed"  # tiles-and-strips: "recessed" or "stacked" (see tiles_and_strips)
    layer_changes: list = field(default_factory=list)  # (print_z, kind, material) filament swaps, one extruder

    def z_levels(self) -> dict[str, float]:
        """Heights (mm) of the sections the checks take: bottom strips, bare tile, top strips."""
        T, ts = self.printer.tile_thickness_mm, self.printer.strip_thickness_mm
        if self.layout == "stacked":
            return {"bottom": 0.5 * ts, "tiles": 0.5 * (ts + T), "top": T + 0.5 * ts}
        return {"bottom": 0.5 * ts, "tiles": 0.5 * T, "top": T - 0.5 * ts}


def _fits(bounds, printer: Printer, what: str) -> None:
    w, h = bounds[2] - bounds[0], bounds[3] - bounds[1]
    bx, by, _ = printer.bed_mm
    if w > bx or h > by:
        raise FabricationError(
            f"{what} is {w:.1f} x {h:.1f} mm and does not fit the {bx:g} x {by:g} mm bed of printer "
            f"{printer.name}; scale the pattern down, choose a larger printer or use --style strips"
        )


def _centre_shift(bounds, printer: Printer) -> tuple[float, float]:
    bx, by, _ = printer.bed_mm
    return 0.5 * bx - 0.5 * (bounds[0] + bounds[2]), 0.5 * by - 0.5 * (bounds[1] + bounds[3])


LAYOUTS = ("recessed", "stacked")


def layer_top_above(z: float, printer: Printer) -> float:
    """Print height (top) of the first slicer layer lying above ``z``."""
    first, h = printer.first_layer_mm, printer.layer_mm
    if z < first - 1e-9:
        return first
    return first + (np.floor((z - first) / h + 1e-6) + 1) * h


def tiles_and_strips(pattern: Pattern, state: int, printer: Printer, layout: str | None = None) -> PrintJob:
    """Rigid tiles joined by flexible strips, in one of two layouts:

    * ``recessed`` (two extruders): strips flush in pockets of the top and bottom
      faces, so both materials share the bottom and top ``strip_thickness`` layers;
    * ``stacked`` (one extruder, the default there): a flexible base sheet
      (every tile plus the bottom-face strips) ``strip_thickness`` thick, the
      rigid tiles on it, the top-face strips lying on the tiles. Each layer holds
      one material, so two colour changes (M600 at the first rigid layer and at
      the first top-strip layer) swap the filament.
    """
    layout = layout or ("recessed" if printer.extruders >= 2 else "stacked")
    if layout not in LAYOUTS:
        raise FabricationError(f"unknown tiles-and-strips layout {layout!r}; choose one of {', '.join(LAYOUTS)}")
    plan = printgeom.closed_plan(pattern, state, printer)
    strips = printgeom.strip_outlines(plan, printer)
    T, ts = printer.tile_thickness_mm, printer.strip_thickness_mm
    _fits(plan.bounds, printer, "the closed pattern")
    top = tuple(strips.outline[strips.top])
    bot = tuple(strips.outline[~strips.top])
    changes: list[tuple[float, str, str]] = []
    if layout == "recessed":
        tiles = Body(f"tiles_{printer.tile_material}", "tiles", (
            ("add", Prism(tuple(plan.tiles), 0.0, T)),
            ("sub", Prism(tuple(strips.pocket[strips.top]), T - ts, T + 1.0)),  # +1: a clean cut through the face
            ("sub", Prism(tuple(strips.pocket[~strips.top]), -1.0, ts)),
        ), printer.tile_material)
        hinges = Body(f"hinges_{printer.strip_material}", "hinges", (
            ("add", Prism(top, T - ts, T)),
            ("add", Prism(bot, 0.0, ts)),
        ), printer.strip_material)
    else:
        base = shapely.simplify(shapely.union_all(list(plan.tiles) + list(bot)), printgeom.NOISE_MM)
        tiles = Body(f"tiles_{printer.tile_material}", "tiles", (("add", Prism(tuple(plan.tiles), ts, T)),),
                     printer.tile_material)
        hinges = Body(f"hinges_{printer.strip_material}", "hinges", (
            ("add", Prism(tuple(shapely.get_parts(base)), 0.0, ts)),
            ("add", Prism(top, T, T + ts)),
        ), printer.strip_material)
        changes = [(float(layer_top_above(ts, printer)), "colour-change", printer.tile_material),
                   (float(layer_top_above(T, printer)), "colour-change", printer.strip_material)]
    dx, dy = _centre_shift(plan.bounds, printer)
    beds = [[translate_body(tiles, dx, dy), translate_body(hinges, dx, dy)]]
    return PrintJob("tiles-and-strips", state, printer, plan, beds, (dx, dy), strips=strips, layout=layout,
                    layer_changes=changes)


LABEL_MAX_MM = 2.5  # cap height of a strip's engraved hinge ID
LABEL_MIN_MM = 1.2  # smaller is not legible in 0.4 mm lines
ENGRAVE_LAYERS = 2  # depth of a strip's engraved ID, in layers


def hinge_label(strip: Polygon, text: str, printer: Printer) -> Polygon | None:
    """The hinge ID as single-stroke lines one nozzle wide, centred on a strip laid
    long side along x, kept a nozzle inside its outline; ``None`` if it does not fit."""
    from .text import text_strokes, text_width

    line = printer.nozzle_mm
    room = strip.buffer(-line, join_style="mitre")
    if room.is_empty:
        return None
    b = room.bounds
    c = shapely.centroid(strip)
    h = min(LABEL_MAX_MM, b[3] - b[1] - line, (b[2] - b[0] - line) / max(text_width(text), 1e-9))
    while h >= LABEL_MIN_MM:
        strokes = text_strokes(text, h, (c.x, c.y))
        glyphs = shapely.union_all([shapely.LineString(p).buffer(0.5 * line, cap_style="round", quad_segs=4)
                                    for p in strokes if len(p) >= 2])
        if room.contains(glyphs):
            return glyphs if isinstance(glyphs, Polygon) else shapely.unary_union(glyphs)
        h *= 0.85
    return None


def _min_rect_frame(poly: Polygon) -> tuple[float, Polygon]:
    """Rotation (rad) turning the polygon's minimum rectangle axis-parallel, and the turned polygon."""
    rect = np.asarray(poly.minimum_rotated_rectangle.exterior.coords)
    edge = rect[1] - rect[0]
    ang = -float(np.arctan2(edge[1], edge[0]))
    turned = shapely.affinity.rotate(poly, ang, origin=(0, 0), use_radians=True)
    b = turned.bounds
    if b[3] - b[1] > b[2] - b[0]:  # lie long side along x
        ang -= np.pi / 2
        turned = shapely.affinity.rotate(poly, ang, origin=(0, 0), use_radians=True)
    return ang, turned


def strips_only(pattern: Pattern, state: int, printer: Printer) -> PrintJob:
    """One flat strip part per hinge, shelf-packed onto beds in hinge order."""
    plan = printgeom.closed_plan(pattern, state, printer)
    strips = printgeom.strip_outlines(plan, printer)
    ts, gap = printer.strip_thickness_mm, printer.part_spacing_mm
    bx, by, _ = printer.bed_mm
    depth = ENGRAVE_LAYERS * printer.layer_mm  # whole layers, so the slicer resolves the ID
    if ts - depth < printer.first_layer_mm - 1e-9:
        raise FabricationError(f"a {ts:g} mm strip cannot hold an ID engraved {ENGRAVE_LAYERS} layers "
                               f"({depth:g} mm) deep above a {printer.first_layer_mm:g} mm first layer; "
                               "raise --strip-thickness")
    beds: list[list[Body]] = [[]]
    placements = []
    x = y = row_h = gap
    unlabelled: list[int] = []
    for h, poly in enumerate(strips.outline):
        ang, turned = _min_rect_frame(poly)
        b = turned.bounds
        w, hgt = b[2] - b[0], b[3] - b[1]
        if w + 2 * gap > bx or hgt + 2 * gap > by:
            raise FabricationError(f"the strip of hinge {h} ({w:.1f} x {hgt:.1f} mm) does not fit the bed")
        if x + w + gap > bx:  # next shelf
            x, y, row_h = gap, y + row_h + gap, 0.0
        if y + hgt + gap > by:  # next bed
            beds.append([])
            x = y = gap
            row_h = 0.0
        placed = shapely.affinity.translate(turned, x - b[0], y - b[1])
        name = f"hinge-{h:04d}-{plan.face(h)}"
        ops = [("add", Prism((placed,), 0.0, ts))]
        label = hinge_label(placed, str(h), printer)
        if label is not None:
            ops.append(("sub", Prism((label,), ts - depth, ts + 1.0)))
        else:
            unlabelled.append(h)
        beds[-1].append(Body(name, "hinge", tuple(ops), printer.strip_material))
        placements.append({"hinge": h, "bed": len(beds), "face": plan.face(h), "tiles": plan.hinge_tiles[h].tolist(),
                           "rotation_deg": round(float(np.degrees(ang)), 6),
                           "offset_mm": [round(x - b[0], 6), round(y - b[1], 6)]})
        x += w + gap
        row_h = max(row_h, hgt)
    return PrintJob("strips", state, printer, plan, beds, strips=strips, placements=placements,
                    unlabelled=unlabelled)


def pinned(pattern: Pattern, state: int, printer: Printer) -> PrintJob:
    """Print-in-place pinned tiles, or :class:`FabricationError` saying why not."""
    plan = printgeom.closed_plan(pattern, state, printer)
    pins = printgeom.pin_plan(pattern, plan, printer)
    _fits(plan.bounds, printer, "the closed pattern")
    lv, g = pins.levels, pins.geometry
    T = lv.thickness
    A, B = plan.hinge_tiles.T
    H = plan.n_hinges
    ph = pins.phase if pins.phase is not None else np.zeros(H)
    # A tile's corner at a pivot is cleared through the full height: the pivot's
    # own partner turns in one half, and the hinge that meets it in either
    # closed state stacks its ears in the other half; at its own ear level the
    # tile is left whole and the ear disc added. (Cutting the full height and
    # adding back tile ∩ disc would meet the cut at points computed twice, a
    # nanometre apart: edges shared by four faces once written as float32.)
    at_tile: dict[int, list[int]] = {t: [] for t in range(len(plan.tiles))}
    for h in range(H):
        at_tile[int(A[h])].append(h)
        at_tile[int(B[h])].append(h)
    def tile_body(t: int, turn: float) -> Body:
        X = plan.tiles[t]
        ops: list[tuple[str, Prism]] = [("add", Prism((X,), 0.0, T))]
        hs = at_tile[t]
        poly = {h: (lambda r, circ, h=h: regular_polygon(plan.hinge_xy[h], r, circ, phase=ph[h] + turn)) for h in hs}
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
                ops.append(("add", Prism((poly[h](g.pin_bottom, False),), zr0, zr1, g.pin_top / g.pin_bottom, p)))
        for h in hs:
            if t == B[h]:
                z0, z1 = lv.level(pins.level[h] + 1)
                p = tuple(plan.hinge_xy[h])
                ops.append(("sub", Prism((poly[h](g.hole_bottom, True),), z0 - 1e-3, z1 + 1e-3,
                                         g.hole_top / g.hole_bottom, p)))
        return Body(f"tile-{t:04d}", "tile", tuple(ops), printer.tile_material)

    # the same tile with its pivot polygons turned: tried in turn when a turn
    # leaves a near-degenerate meeting that a float32 file cannot keep 2-manifold
    # (each tile's clearances are circumscribed and its ears inscribed, so
    # tiles need not share a turn)
    bodies = []
    for t in range(len(plan.tiles)):
        first = tile_body(t, 0.0)
        alts = tuple(tile_body(t, (j + 0.5) / printgeom.PHASES) for j in range(printgeom.PHASES))
        bodies.append(replace(first, variants=alts))
    dx, dy = _centre_shift(plan.bounds, printer)
    beds = [[translate_body(b, dx, dy) for b in bodies]]
    return PrintJob("pinned", state, printer, plan, beds, (dx, dy), pins=pins)


def scaled(pattern: Pattern, k: float) -> Pattern:
    """The pattern ``k`` times its size (nodes and stored closed states)."""
    return replace(pattern, nodes=pattern.nodes * k, contracted={s: c * k for s, c in pattern.contracted.items()})


def _pinned_plans(pattern: Pattern, state: int, printer: Printer) -> str | None:
    """Why pinned hinges cannot be printed at this size on this bed (``None``: they can)."""
    try:
        plan = printgeom.closed_plan(pattern, state, printer)
        printgeom.pin_plan(pattern, plan, printer)
        _fits(plan.bounds, printer, "the closed pattern")
    except FabricationError as exc:
        return str(exc)
    return None


def pinned_scale_range(pattern: Pattern, state: int, printer: Printer, step: float = 0.01
                       ) -> tuple[float, float] | None:
    """The smallest scale factor (to ``step``) at which the pattern prints pinned on
    the printer's bed, and the largest that fits the bed; ``None`` if none does.

    The refusals that depend on size (pivots too close, ears reaching foreign
    tiles, slivers beside a clearance) ease as the pattern grows, until it no
    longer fits the bed: bisect between the given size and the largest that fits."""
    c = printgeom.closed_corners(pattern, state).reshape(-1, 2)
    (x0, y0), (x1, y1) = c.min(0), c.max(0)
    bx, by, _ = printer.bed_mm
    kmax = np.floor(min(bx / (x1 - x0), by / (y1 - y0)) / step) * step  # the shrunk tiles fit inside
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
        return (f"no scale prints it pinned on the {bx:g} x {by:g} mm bed of {printer.name}: at the largest that "
                f"fits ({scale * kmax:.2f}x) {why}")
    lo, hi = rng
    return (f"it prints pinned on the {bx:g} x {by:g} mm bed of {printer.name} from --scale {scale * lo:.2f} "
            f"to {scale * hi:.2f}")


def build_job(pattern: Pattern, style: str, state: int, printer: Printer, advise_scale: float | None = None
              ) -> PrintJob:
    """The print job of a style; with ``advise_scale`` (the scale the pattern was
    given at) a refused pinned job names the scales that print on this bed."""
    if style not in STYLES:
        raise FabricationError(f"unknown print style {style!r}; choose one of {', '.join(STYLES)}")
    try:
        return {"strips": strips_only, "tiles-and-strips": tiles_and_strips, "pinned": pinned}[style](
            pattern, state, printer)
    except FabricationError as exc:
        if style != "pinned" or advise_scale is None:
            raise
        raise FabricationError(f"{exc}; {pinned_advice(pattern, state, printer, advise_scale)}") from None


# ------------------------------------------------------------------ checks

@dataclass
class MeshReport:
    """Measured properties of the meshes of one job (mm, mm³)."""

    bodies: list[dict] = field(default_factory=list)
    intersection_volume_mm3: float = 0.0
    min_clearance_mm: float | None = None
    required_clearance_mm: float = 0.0
    problems: list[str] = field(default_factory=list)
    sweep: dict | None = None  # pinned: collision sweep along the deployment path

    @property
    def ok(self) -> bool:
        return not self.problems

    def to_dict(self) -> dict:
        return {"ok": self.ok, "bodies": self.bodies, "intersection_volume_mm3": self.intersection_volume_mm3,
                "min_clearance_mm": self.min_clearance_mm, "required_clearance_mm": self.required_clearance_mm,
                "problems": self.problems, "deployment_sweep": self.sweep}


@dataclass(eq=False)
class Realised:
    """A job with its solids: ``manifolds[k][i]`` is body i of bed k."""

    job: PrintJob
    manifolds: list[list]
    meshes: list[list]
    snaps: list[list[float]] = field(default_factory=list)  # grid (mm) a body's outlines were snapped to, 0: exact


def edge_defects(vertices: np.ndarray, faces: np.ndarray) -> int:
    """Edges not used by exactly two faces, plus faces with a repeated vertex,
    once the vertices are welded by position, as any STL reader does."""
    v = np.ascontiguousarray(vertices)
    _, weld = np.unique(v.view(np.dtype((np.void, 3 * v.dtype.itemsize))).ravel(), return_inverse=True)
    f = weld.reshape(-1)[np.asarray(faces)]
    degenerate = (f[:, 0] == f[:, 1]) | (f[:, 1] == f[:, 2]) | (f[:, 0] == f[:, 2])
    e = np.sort(np.concatenate([f[:, [0, 1]], f[:, [1, 2]], f[:, [2, 0]]]), axis=1).astype(np.int64)
    _, counts = np.unique(e[:, 0] * (int(weld.max(initial=0)) + 1) + e[:, 1], return_counts=True)
    return int((counts != 2).sum() + degenerate.sum())


def float32_defects(tm) -> int:
    """:func:`edge_defects` of a mesh as a file stores it (float32 coordinates)."""
    return edge_defects(np.asarray(tm.vertices, dtype=np.float32), tm.faces)


def _realise_clean(body: Body, grid: float):
    """The body (or its first variant) whose float32 mesh is a closed 2-manifold, each
    tried as designed and then with its outlines snapped to the float32 ``grid`` (which
    merges vertices a file would weld; the exact solid is kept whenever it writes
    cleanly); the last one tried if none is (the mesh check then reports it)."""
    for b, g in itertools.product((body, *body.variants), (0.0, grid)):
        m = realise(b, g)
        if m.status().name != "NoError" or m.is_empty():
            raise FabricationError(f"body {b.name} came out empty or invalid ({m.status().name})")
        tm = to_trimesh(m)
        if float32_defects(tm) == 0:
            break
    return b, m, tm, g


def realise_job(job: PrintJob) -> Realised:
    grid = bed_grid(job.printer)
    done = [[_realise_clean(b, grid) for b in bed] for bed in job.beds]
    beds = [[replace(b, variants=()) for b, *_ in bed] for bed in done]
    job = replace(job, beds=beds)
    return Realised(job, [[d[1] for d in bed] for bed in done], [[d[2] for d in bed] for bed in done],
                    [[d[3] for d in bed] for bed in done])


def check_meshes(r: Realised, vol_rtol: float = 1e-9) -> MeshReport:
    """Watertight, consistently wound, positive volume, on the bed, no two bodies
    sharing volume, and clearances between bodies that may move apart."""
    import manifold3d as m3d

    job, pr = r.job, r.job.printer
    rep = MeshReport()
    bx, by, bz = pr.bed_mm
    eps = 1e-6
    for k, (bed, ms, tms) in enumerate(zip(job.beds, r.manifolds, r.meshes), 1):
        snaps = r.snaps[k - 1] if r.snaps else [0.0] * len(bed)
        for b, m, tm, snap in zip(bed, ms, tms, snaps):
            lo, hi = tm.bounds
            info = {"bed": k, "name": b.name, "kind": b.kind, "watertight": bool(tm.is_watertight),
                    "winding_consistent": bool(tm.is_winding_consistent), "volume_mm3": float(tm.volume),
                    "manifold_volume_mm3": float(m.volume()), "triangles": int(len(tm.faces)),
                    "bounds_mm": [lo.round(4).tolist(), hi.round(4).tolist()]}
            info["float32_edge_defects"] = float32_defects(tm)
            info["outlines_snapped_to_mm"] = snap  # 0: as designed; else the float32 grid it needed
            rep.bodies.append(info)
            if info["float32_edge_defects"]:
                rep.problems.append(f"{b.name}: {info['float32_edge_defects']} edges not shared by exactly two faces "
                                    "once written with float32 coordinates")
            if not (info["watertight"] and info["winding_consistent"]):
                rep.problems.append(f"{b.name}: mesh not watertight or not consistently wound")
            if not tm.volume > 0 or abs(tm.volume - m.volume()) > vol_rtol * max(1.0, m.volume()) + 1e-6:
                rep.problems.append(f"{b.name}: volume {tm.volume:.6g} mm³ disagrees with the solid")
            if (lo < -eps).any() or hi[0] > bx + eps or hi[1] > by + eps or hi[2] > bz + eps:
                rep.problems.append(f"{b.name}: outside the {bx:g} x {by:g} x {bz:g} mm bed")
        # bodies printed together never share volume
        if len(ms) > 1:
            inter = 0.0
            if job.style == "tiles-and-strips":
                inter = (ms[0] ^ ms[1]).volume()
            else:  # many small disjoint parts: their union loses no volume
                inter = sum(m.volume() for m in ms) - m3d.Manifold.batch_boolean(ms, m3d.OpType.Add).volume()
            rep.intersection_volume_mm3 = max(rep.intersection_volume_mm3, float(inter))
    if rep.intersection_volume_mm3 > 1e-6:
        rep.problems.append(f"bodies overlap by {rep.intersection_volume_mm3:.3g} mm³")
    _check_clearances(r, rep)
    return rep


def _slice_polys(manifold, z: float) -> list[Polygon]:
    """The section of a solid at height ``z`` as disjoint polygons (holes kept)."""
    rings = [np.asarray(r, dtype=float) for r in manifold.slice(z).to_polygons()]
    rings = [r for r in rings if len(r) >= 3]
    if not rings:
        return []
    idx = np.repeat(np.arange(len(rings)), [len(r) for r in rings])
    lr = shapely.linearrings(np.concatenate(rings), indices=idx)
    polys = shapely.polygons(lr)
    ccw = shapely.is_ccw(lr)
    outer, holes = polys[ccw], polys[~ccw]
    if not len(holes):
        return list(outer)
    out = []
    tree = shapely.STRtree(holes)
    for o in outer:
        inside = holes[tree.query(o, predicate="contains_properly")]
        out.append(o.difference(shapely.union_all(inside)) if len(inside) else o)
    return out


def _check_clearances(r: Realised, rep: MeshReport) -> None:
    """Clearances between bodies that may move apart, measured the way the
    print style needs (registry :data:`_CLEARANCE_CHECKS`, by style)."""
    _CLEARANCE_CHECKS[r.job.style](r, rep)


def _strips_clearances(r: Realised, rep: MeshReport) -> None:
    """Strips style: loose parts, so only the spacing on the bed matters."""
    job, pr = r.job, r.job.printer
    rep.required_clearance_mm = pr.part_spacing_mm
    polys = [Polygon(b.ops[0][1].polygons[0]) for b in job.beds[0]]
    if len(polys) > 1:
        tree = shapely.STRtree(polys)
        i, j = tree.query(polys, predicate="dwithin", distance=3 * pr.part_spacing_mm)
        sel = i < j
        if sel.any():
            arr = np.array(polys, dtype=object)
            rep.min_clearance_mm = float(shapely.distance(arr[i[sel]], arr[j[sel]]).min())
            if rep.min_clearance_mm < pr.part_spacing_mm - 1e-6:
                rep.problems.append(f"strip parts {rep.min_clearance_mm:.3f} mm apart on bed 1, "
                                    f"under the part spacing {pr.part_spacing_mm:g} mm")


def _tiles_and_strips_clearances(r: Realised, rep: MeshReport) -> None:
    """Tiles-and-strips style: clearances measured on sections of the mesh."""
    job, pr = r.job, r.job.printer
    # measured on the mesh: sections of both bodies at the bottom pocket, the
    # bare middle and the top pocket. Each section piece is attributed to
    # the tile or strip it belongs to; pieces of different tiles keep the
    # gap, a strip touches only the two tiles it joins and keeps the radial
    # clearance from everything else.
    tiles_m, hinges_m = r.manifolds[0]
    req = pr.radial_clearance_mm
    rep.required_clearance_mm = req
    shift = np.asarray(job.shift)
    design_t = shapely.transform(job.plan.tiles, lambda c: c + shift)
    design_s = shapely.transform(job.strips.outline, lambda c: c + shift)
    A, B = job.plan.hinge_tiles.T
    worst = np.inf
    lv = job.z_levels()
    zs = (lv["bottom"], lv["tiles"], lv["top"])
    if job.layout == "stacked":  # the base sheet joins tiles by design: it must be the planned sheet
        zs = zs[1:]
        planned = shapely.union_all(list(design_t) + list(design_s[~job.strips.top]))
        got = shapely.union_all(_slice_polys(hinges_m, lv["bottom"]))
        off = float(shapely.area(shapely.symmetric_difference(planned, got)))
        if off > 1e-6 * max(1.0, planned.area):
            rep.problems.append(f"the base sheet deviates from its plan by {off:.3g} mm²")
    for z in zs:
        parts = _slice_polys(tiles_m, z)
        sparts = _slice_polys(hinges_m, z)
        allp = np.array(parts + sparts, dtype=object)
        kind = np.array([0] * len(parts) + [1] * len(sparts))
        owner = np.full(len(allp), -1)
        pts = shapely.point_on_surface(allp)
        for k, design in ((0, design_t), (1, design_s)):
            sel = np.flatnonzero(kind == k)
            qi, di = shapely.STRtree(design).query(pts[sel], predicate="dwithin", distance=1e-3)
            owner[sel[qi]] = di
        if (owner < 0).any():
            rep.problems.append(f"a section piece at z = {z:g} mm belongs to no planned tile or strip")
        i, j = shapely.STRtree(allp).query(allp, predicate="dwithin", distance=2 * pr.gap_mm)
        sel = (i < j) & ~((kind[i] == kind[j]) & (owner[i] == owner[j]))  # same body: no clearance
        i, j = i[sel], j[sel]
        d = shapely.distance(allp[i], allp[j])
        mixed = kind[i] != kind[j]
        st_, tl = np.where(kind[i] == 1, i, j)[mixed], np.where(kind[i] == 1, j, i)[mixed]
        joined = np.zeros(len(i), dtype=bool)
        joined[mixed] = (owner[tl] == A[owner[st_]]) | (owner[tl] == B[owner[st_]])
        free = d[~joined]
        if len(free):
            worst = min(worst, float(free.min()))
    rep.min_clearance_mm = None if worst == np.inf else worst
    if rep.min_clearance_mm is not None and rep.min_clearance_mm < req - 1e-6:
        rep.problems.append(f"clearance {rep.min_clearance_mm:.3f} mm below the radial clearance {req:g} mm")


def _pinned_clearances(r: Realised, rep: MeshReport) -> None:
    """Pinned style: every pair of tiles meeting at a pivot, measured in 3D."""
    job, pr = r.job, r.job.printer
    plan = job.plan
    req = min(pr.radial_clearance_mm, pr.axial_clearance_mm)
    rep.required_clearance_mm = req
    ms = r.manifolds[0]
    pairs = set()
    A, B = plan.hinge_tiles.T
    for h in range(plan.n_hinges):
        group = {int(A[h]), int(B[h])}
        if plan.partner[h] >= 0:
            group |= {int(A[plan.partner[h]]), int(B[plan.partner[h]])}
        g = sorted(group)
        pairs |= {(a, b) for ai, a in enumerate(g) for b in g[ai + 1:]}
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


_CLEARANCE_CHECKS = {"strips": _strips_clearances, "tiles-and-strips": _tiles_and_strips_clearances,
                     "pinned": _pinned_clearances}


# ------------------------------------------------------------ pinned sweep

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


def sweep_pinned(pattern: Pattern, r: Realised, steps: int = 24, overlap_tol_mm2: float = 1e-6) -> SweepCheck:
    """Collision sweep of the printed pinned tiles (sections of the solids at
    every ear level and axial gap) along :func:`fabkiri.mechanics.deploy.rigid_path`."""
    from ..mechanics.deploy import rigid_path
    from ..pattern import geometry

    job = r.job
    if job.style != "pinned":
        raise FabricationError("the deployment sweep is for pinned tiles")
    lv = job.pins.levels
    zs = [0.5 * sum(lv.level(k)) for k in range(4)] + [lv.level(k)[1] + 0.5 * lv.axial for k in range(3)]
    back = -np.asarray(job.shift)
    T = len(job.plan.tiles)
    sections = {z: [np.array(_slice_polys(m, z), dtype=object) for m in r.manifolds[0]] for z in zs}
    for z in zs:
        sections[z] = [shapely.transform(g, lambda c: c + back) for g in sections[z]]
    path = rigid_path(pattern, steps, tol_rad=1e-6)
    src = job.plan.corners
    worst_area, worst_dist, worst = 0.0, np.inf, ""
    for f in range(len(path.t)):
        poses = [geometry.kabsch(src[t], path.corners[f, t]) for t in range(T)]
        for z in zs:
            geoms, owner = [], []
            for t in range(T):
                th, tr = poses[t]
                moved = shapely.transform(sections[z][t], lambda c, th=th, tr=tr: geometry.rotate(c, th) + tr)
                geoms.extend(moved)
                owner.extend([t] * len(moved))
            geoms = np.array(geoms, dtype=object)
            owner = np.asarray(owner)
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
    return SweepCheck(frames=len(path.t), levels_mm=[round(z, 4) for z in zs], max_overlap_mm2=worst_area,
                      min_distance_mm=worst_dist, worst=worst, ok=worst_area <= overlap_tol_mm2)


# --------------------------------------------------------- top-face check

@dataclass
class TileCheck:
    """Printed tile outlines recovered from the mesh against the closed state."""

    state: int
    tolerance_mm: float
    max_deviation_mm: float
    max_overlap_mm2: float
    tiles: int
    ok: bool

    def to_dict(self) -> dict:
        return dict(self.__dict__)


def check_printed_tiles(r: Realised, tiles_mesh=None) -> TileCheck:
    """Recover each tile's outline from the printed tile mesh (section at the
    bare mid-plane, grown back by the shrink), and compare with the closed state:
    every recovered vertex within ``printer.tolerance_mm`` of its design tile
    outline and vice versa (Hausdorff), and no two recovered tiles overlapping.

    For pinned tiles the ear discs around the pivots are excluded on both sides
    (they are round by design). ``tiles_mesh`` (a trimesh, e.g. re-read from the
    STL) replaces the in-memory solid when given.
    """
    import manifold3d as m3d

    job = r.job
    if job.style == "strips":
        raise FabricationError("the strips style prints no tiles")
    plan, pr = job.plan, job.printer
    dx, dy = job.shift
    if tiles_mesh is not None:
        man = m3d.Manifold(m3d.Mesh(vert_properties=np.asarray(tiles_mesh.vertices, dtype=np.float32),
                                    tri_verts=np.asarray(tiles_mesh.faces, dtype=np.uint32)))
    elif job.style == "tiles-and-strips":
        man = r.manifolds[0][0]
    else:
        man = m3d.Manifold.batch_boolean(r.manifolds[0], m3d.OpType.Add)
    if job.style == "tiles-and-strips":
        z = job.z_levels()["tiles"]
        mask = None
    else:
        lv = job.pins.levels
        z = 0.5 * (lv.level(1)[1] + lv.level(2)[0])  # the axial gap between the two hinge halves
        mask = printgeom.clearance_mask(plan.hinge_xy + [dx, dy], job.pins.geometry)
    # mesh sections carry float noise (near-duplicate vertices where booleans meet);
    # the mitre growth would turn such a zero-length edge into a spike of up to
    # MITRE_LIMIT x the shrink, so drop vertices that deviate less than SECTION_NOISE_MM
    parts = list(shapely.simplify(np.array(_slice_polys(man, z), dtype=object), SECTION_NOISE_MM))
    design = shapely.transform(shapely.polygons(plan.corners), lambda c: c + np.array([dx, dy]))
    grown = list(printgeom.grow_back(np.array(parts, dtype=object), plan.shrink_mm)) if parts else []
    if mask is not None:
        design = np.array([g.difference(mask) for g in design], dtype=object)
        grown = [g.difference(mask) for g in grown]
    grown = [g for g in grown if not g.is_empty and g.area > 1e-6]
    # match recovered parts to design tiles by containment of a representative point
    tree = shapely.STRtree(design)
    dev = 0.0
    matched = set()
    for g in grown:
        pt = g.representative_point()
        hits = tree.query(pt, predicate="intersects")
        if len(hits) == 0:
            dev = np.inf
            continue
        t = int(hits[0])
        matched.add(t)
        dev = max(dev, shapely.hausdorff_distance(g, design[t]))
    # pinned tiles may come back in several pieces after masking; every tile must be seen
    if len(matched) != len(plan.tiles):
        dev = np.inf
    overlap = 0.0
    if len(grown) > 1:
        t2 = shapely.STRtree(grown)
        i, j = t2.query(grown, predicate="intersects")
        sel = i < j
        if sel.any():
            g = np.array(grown, dtype=object)
            overlap = float(shapely.area(shapely.intersection(g[i[sel]], g[j[sel]])).max())
    tol = pr.tolerance_mm
    ok = bool(dev <= tol and overlap <= tol * tol)
    return TileCheck(state=job.state, tolerance_mm=tol, max_deviation_mm=float(dev), max_overlap_mm2=overlap,
                     tiles=len(matched), ok=ok)


def top_face_dxf(r: Realised, tiles_mesh=None) -> bytes:
    """The printed tiles' outlines (section of the tile body at its bare
    mid-plane, at printed size) as a plain DXF: closed LWPOLYLINEs on ``CUT``."""
    import ezdxf
    import manifold3d as m3d

    job = r.job
    if job.style != "tiles-and-strips":
        raise FabricationError("top faces as a layout exist for tiles-and-strips only")
    man = r.manifolds[0][0] if tiles_mesh is None else m3d.Manifold(m3d.Mesh(
        vert_properties=np.asarray(tiles_mesh.vertices, dtype=np.float32),
        tri_verts=np.asarray(tiles_mesh.faces, dtype=np.uint32)))
    doc = ezdxf.new("R2010", units=ezdxf.units.MM)
    doc.layers.add("CUT", color=1)
    msp = doc.modelspace()
    for ring in man.slice(job.z_levels()["tiles"]).to_polygons():
        msp.add_lwpolyline(np.asarray(ring, dtype=float).tolist(), format="xy", close=True,
                           dxfattribs={"layer": "CUT"})
    out = io.StringIO()
    doc.write(out)
    return out.getvalue().encode("utf-8")


BRIDGE_INSET_MM = 1e-3


def printed_bridges(r: Realised) -> list[dict]:
    """The flexible material spanning each gap, measured on the hinge mesh:
    sections of the strips at the middle of their thickness, minus the tiles,
    each attributed to the hinge whose planned strip holds it."""
    job = r.job
    tiles_m, hinges_m = r.manifolds[0]
    planned = shapely.transform(job.strips.outline, lambda c: c + np.asarray(job.shift))
    tree = shapely.STRtree(planned)
    feats = []
    lv = job.z_levels()
    tiles = np.array(_slice_polys(tiles_m, lv["tiles"]), dtype=object)
    tile_tree = shapely.STRtree(tiles)
    for z in (lv["bottom"], lv["top"]):
        parts = np.array(_slice_polys(hinges_m, z), dtype=object)
        if job.layout == "stacked" and z == lv["bottom"]:  # a base sheet: each bottom strip's share of it
            mine = shapely.intersection(shapely.union_all(parts), planned[~job.strips.top])
            parts = np.array([g for g in shapely.get_parts(mine) if g.area > 1e-4], dtype=object)
        pi, hi = tree.query(shapely.point_on_surface(parts), predicate="within")
        owner = np.full(len(parts), -1)
        once = np.bincount(pi, minlength=len(parts)) == 1
        owner[pi[once[pi]]] = hi[once[pi]]
        qi, ti = tile_tree.query(parts, predicate="intersects")
        feats += _bridge_features(parts, owner, tiles, qi, ti)
    return sorted(feats, key=lambda f: f["hinge"])


def _bridge_features(parts, owner, tiles, qi, ti) -> list[dict]:
    """Each owned strip section minus the tiles it touches, drawn a hair inside;
    the differences and insets run as one vectorised call each."""
    keep = np.flatnonzero(owner >= 0)
    order = np.argsort(qi, kind="stable")  # stable: each part's tiles in query order, as before
    firsts, starts = np.unique(qi[order], return_index=True)
    span = {int(q): (lo, hi) for q, lo, hi in zip(firsts, starts, np.append(starts[1:], len(qi)))}
    cut = [shapely.union_all(tiles[ti[order[slice(*span[k])]]]) if k in span else None for k in keep.tolist()]
    has = np.array([c is not None for c in cut], dtype=bool)
    bridges = parts[keep].copy()
    if has.any():
        bridges[has] = shapely.difference(parts[keep][has], np.array([c for c in cut if c is not None]))
    live = ~shapely.is_empty(bridges)
    # drawn a hair inside the bridge, so the verifier's "material minus
    # ligaments" never leaves slivers along the tile edges it shares
    cores = shapely.buffer(bridges[live], -BRIDGE_INSET_MM, join_style="mitre")
    feats = []
    for k, core in zip(keep[live], cores):
        for piece in shapely.get_parts(core):
            if piece.geom_type != "Polygon" or piece.area < 1e-4:
                continue  # slivers where a strip edge meets a tile edge
            feats.append({"hinge": int(owner[k]), "sheet": 1,
                          "polygon": np.asarray(piece.exterior.coords)[:-1].tolist()})
    return feats


def verify_printed_tiles(pattern: Pattern, r: Realised, tiles_mesh=None):
    """Run the layout verifier (:func:`fabkiri.verify.verify_layout`) on the
    printed tiles' top faces: read back as an in-place layout of the printed
    closed state whose tiles were shrunk by half the gap, at the printer's
    tolerance. Returns the verifier's :class:`~fabkiri.verify.Report`."""
    import tempfile
    from pathlib import Path

    from ..verify import verify_layout

    job = r.job
    data = top_face_dxf(r, tiles_mesh)
    manifest = {"format": "fabkiri.cut", "version": 1, "units": "mm", "hinge": "ligament", "layout": "in-place",
                "state": job.state, "scale": 1.0, "kerf_offset_mm": 0.0, "tile_shrink_mm": job.plan.shrink_mm,
                "hinge_features": printed_bridges(r)}
    with tempfile.TemporaryDirectory() as d:
        path = Path(d) / "printed-top-faces.dxf"
        path.write_bytes(data)
        rep = verify_layout(pattern, path, manifest=manifest, tol_mm=job.printer.tolerance_mm)
    rep.subject = "printed tile top faces"
    rep.meta["files"] = []
    return rep


# ----------------------------------------------------------------- writing

def export_3mf(scene) -> bytes:
    """A trimesh scene as a plain 3MF, one object per geometry, reproducible bytes
    (:func:`.threemf.objects_3mf`; print jobs write projects with :func:`job_files`)."""
    from .threemf import objects_3mf

    return objects_3mf({name: (np.asarray(g.vertices), np.asarray(g.faces)) for name, g in scene.geometry.items()})


def _parts(bed: list[Body], tms: list) -> list:
    from .threemf import Part

    return [Part(b.name, b.material, np.asarray(tm.vertices), np.asarray(tm.faces)) for b, tm in zip(bed, tms)]


def job_files(r: Realised, stem: str, preview: bool = True) -> dict[str, bytes]:
    """File name -> bytes of every file of a job: per bed one 3MF project (one
    object, one volume per body, see :mod:`.threemf`) and a preview PNG, and
    STLs (per body kind for tiles-and-strips, per bed otherwise)."""
    import trimesh

    from .printpreview import preview_png
    from .threemf import LayerChange, project_3mf

    job = r.job
    files: dict[str, bytes] = {}
    for k, (bed, tms) in enumerate(zip(job.beds, r.meshes), 1):
        suffix = "" if len(job.beds) == 1 else f"-bed{k}"
        changes = [LayerChange(z, kind, m) for z, kind, m in job.layer_changes]
        files[f"{stem}{suffix}.3mf"] = project_3mf(f"{stem}{suffix}", _parts(bed, tms), job.printer, changes)
        if preview:
            files[f"{stem}{suffix}.png"] = preview_png(bed, r.manifolds[k - 1], job.printer,
                                                       f"{stem}{suffix} ({job.style})")
        if job.style == "tiles-and-strips":
            for b, tm in zip(bed, tms):
                files[f"{stem}_{b.kind}.stl"] = tm.export(file_type="stl")
        else:  # disjoint bodies: their concatenation is still a closed 2-manifold
            files[f"{stem}{suffix}.stl"] = trimesh.util.concatenate(tms).export(file_type="stl")
    return files


def print_plan(job: PrintJob) -> str:
    """How the job prints on its printer (one line for the user), or
    :class:`FabricationError` when it cannot print there."""
    pr = job.printer
    mats = sorted({b.material for bed in job.beds for b in bed})
    if len(mats) == 1:
        return f"one material ({mats[0]}), extruder 1"
    if pr.extruders >= 2:
        return ", ".join(f"{m} on extruder {pr.extruder_of(m)}" for m in mats) + " (tool changes in one print)"
    if job.layer_changes:
        T, ts = pr.tile_thickness_mm, pr.strip_thickness_mm
        swaps = " and ".join(f"z = {z:.2f} mm (load {m})" for z, _, m in job.layer_changes)
        return (f"one extruder: {job.style} stacked ({pr.strip_material} base sheet 0-{ts:g} mm, {pr.tile_material} "
                f"tiles {ts:g}-{T:g} mm, {pr.strip_material} top strips {T:g}-{T + ts:g} mm), colour changes (M600) "
                f"in the 3MF at {swaps}")
    raise FabricationError(
        f"printer {pr.name} has one extruder and {job.style} puts {' and '.join(mats)} in the same layers (the "
        f"recessed strips share the tiles' bottom and top {pr.strip_thickness_mm:g} mm), which no pause or colour "
        "change can split; use a multi-material printer (--printer prusa-xl-2t) or --style strips "
        "(flexible strips to glue onto laser-cut tiles)"
    )




def read_back_files(files: dict[str, bytes]) -> dict[str, dict]:
    """Every STL/3MF as written, re-read by trimesh (vertices welded, as slicers
    do) and by manifold3d: watertight, every edge used by exactly two faces, one
    valid manifold per body. This, not the in-memory solid, is what the manifest reports."""
    import manifold3d as m3d
    import trimesh

    from .threemf import read_volumes

    out = {}
    for name, data in sorted(files.items()):
        ext = name.rsplit(".", 1)[-1]
        if ext not in ("stl", "3mf"):
            continue
        if ext == "3mf":  # one object of several volumes (parts): each volume is a closed body
            geoms = [trimesh.Trimesh(v, f, process=True) for _, _, _, v, f in read_volumes(data)]
        else:
            geoms = [trimesh.load(io.BytesIO(data), file_type=ext, process=True)]
        bad_edges, watertight, m3d_ok, volume = 0, True, True, 0.0
        for g in geoms:
            bad_edges += edge_defects(g.vertices, g.faces)
            watertight &= bool(g.is_watertight and g.is_winding_consistent)
            man = m3d.Manifold(m3d.Mesh(vert_properties=np.asarray(g.vertices, dtype=np.float32),
                                        tri_verts=np.asarray(g.faces, dtype=np.uint32)))
            m3d_ok &= man.status().name == "NoError" and not man.is_empty()
            volume += float(g.volume)
        out[name] = {"meshes": len(geoms), "watertight": watertight, "edges_not_shared_by_two_faces": bad_edges,
                     "manifold3d_ok": bool(m3d_ok), "volume_mm3": volume,
                     "ok": bool(watertight and bad_edges == 0 and m3d_ok)}
    return out


def manifest(r: Realised, rep: MeshReport, tiles: TileCheck | None, pattern_name: str,
             files: Iterable[str], verifier=None, read_back: dict | None = None) -> str:
    job = r.job
    plan = job.plan
    d = {
        "format": "fabkiri.print", "version": 1, "units": "mm",
        "pattern": pattern_name, "style": job.style, "state": job.state,
        "printer": job.printer.to_dict(),
        "shift_mm": [round(float(v), 6) for v in job.shift],
        "layout": job.layout if job.style == "tiles-and-strips" else None,
        "layer_changes": [{"print_z_mm": round(z, 6), "gcode": "M600" if k == "colour-change" else "M601",
                           "load": m} for z, k, m in job.layer_changes],
        "beds": [[b.name for b in bed] for bed in job.beds],
        "hinges": [{"hinge": h, "tiles": plan.hinge_tiles[h].tolist(), "face": plan.face(h),
                    "coincides_with": int(plan.partner[h]) if plan.partner[h] >= 0 else None,
                    "xy": [round(float(v), 6) for v in plan.hinge_xy[h] + np.asarray(job.shift)]}
                   for h in range(plan.n_hinges)],
        "files": sorted(files),
        "checks": {"meshes": rep.to_dict(), "files": read_back, "tiles": tiles.to_dict() if tiles else None,
                   "verifier": verifier.to_dict() if verifier is not None else None},
    }
    if job.placements:
        d["placements"] = job.placements
        d["assembly"] = ("glue every strip with its engraved face up, as seen from above the pattern: top-face "
                         "strips on the tiles, bottom-face strips under them with the engraved face against them")
        d["unlabelled_hinges"] = job.unlabelled
    if job.pins is not None:
        d["pins"] = {"levels_mm": [list(job.pins.levels.level(k)) for k in range(4)],
                     "geometry_mm": dict(job.pins.geometry.__dict__),
                     "level": {"bottom_hinges": "ear levels 0-1", "top_hinges": "ear levels 2-3"}}
    return json.dumps(d, indent=1, sort_keys=False) + "\n"
