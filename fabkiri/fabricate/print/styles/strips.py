"""The ``strips`` print style: one flat flexible strip per hinge, to glue onto laser-cut tiles.

The strips are laid long side along x and shelf-packed onto as many beds as
needed, each part named by its hinge and engraved with its ID.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
import shapely
import shapely.affinity
from shapely.geometry import Polygon

from ....errors import FabricationError
from ....pattern.model import Pattern
from .. import geometry as printgeom
from ..build import PrintJob, Realised
from ..printers import Printer
from ..solid import Body, Prism

if TYPE_CHECKING:
    from ..checks import MeshReport

LABEL_MAX_MM = 2.5  # cap height of a strip's engraved hinge ID
LABEL_MIN_MM = 1.2  # smaller is not legible in 0.4 mm lines
ENGRAVE_LAYERS = 2  # depth of a strip's engraved ID, in layers


def hinge_label(strip: Polygon, text: str, printer: Printer) -> Polygon | None:
    """The hinge ID as single-stroke lines one nozzle wide, centred on a strip laid
    long side along x, kept a nozzle inside its outline; ``None`` if it does not fit."""
    from ...cut.text import text_strokes, text_width

    line = printer.nozzle_mm
    room = strip.buffer(-line, join_style="mitre")
    if room.is_empty:
        return None
    b = room.bounds
    c = shapely.centroid(strip)
    h = min(LABEL_MAX_MM, b[3] - b[1] - line, (b[2] - b[0] - line) / max(text_width(text), 1e-9))
    while h >= LABEL_MIN_MM:
        strokes = text_strokes(text, h, (c.x, c.y))
        glyphs = shapely.union_all(
            [
                shapely.LineString(p).buffer(0.5 * line, cap_style="round", quad_segs=4)
                for p in strokes
                if len(p) >= 2
            ]
        )
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


def build(pattern: Pattern, state: int, printer: Printer) -> PrintJob:
    """One flat strip part per hinge, shelf-packed onto beds in hinge order."""
    plan = printgeom.closed_plan(pattern, state, printer)
    strips = printgeom.strip_outlines(plan, printer)
    ts, gap = printer.strip_thickness_mm, printer.part_spacing_mm
    bx, by, _ = printer.bed_mm
    depth = ENGRAVE_LAYERS * printer.layer_mm  # whole layers, so the slicer resolves the ID
    if ts - depth < printer.first_layer_mm - 1e-9:
        raise FabricationError(
            f"a {ts:g} mm strip cannot hold an ID engraved {ENGRAVE_LAYERS} layers "
            f"({depth:g} mm) deep above a {printer.first_layer_mm:g} mm first layer; "
            "raise --strip-thickness"
        )
    beds: list[list[Body]] = [[]]
    placements = []
    x = y = row_h = gap
    unlabelled: list[int] = []
    for h, poly in enumerate(strips.outline):
        ang, turned = _min_rect_frame(poly)
        b = turned.bounds
        w, hgt = b[2] - b[0], b[3] - b[1]
        if w + 2 * gap > bx or hgt + 2 * gap > by:
            raise FabricationError(
                f"the strip of hinge {h} ({w:.1f} x {hgt:.1f} mm) does not fit the bed"
            )
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
        placements.append(
            {
                "hinge": h,
                "bed": len(beds),
                "face": plan.face(h),
                "tiles": plan.hinge_tiles[h].tolist(),
                "rotation_deg": round(float(np.degrees(ang)), 6),
                "offset_mm": [round(x - b[0], 6), round(y - b[1], 6)],
            }
        )
        x += w + gap
        row_h = max(row_h, hgt)
    return PrintJob(
        "strips",
        state,
        printer,
        plan,
        beds,
        strips=strips,
        placements=placements,
        unlabelled=unlabelled,
    )


def clearances(r: Realised, rep: MeshReport) -> None:
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
                rep.problems.append(
                    f"strip parts {rep.min_clearance_mm:.3f} mm apart on bed 1, "
                    f"under the part spacing {pr.part_spacing_mm:g} mm"
                )
