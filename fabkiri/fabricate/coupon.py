"""Calibration coupons (``fabkiri coupon``): small test pieces that set a preset's fields.

Laser (a material preset): one small sheet, DXF + SVG + PNG through the
project's writers (so it opens at its size in mm), with three rows:

1. **kerf comb**: a 100 mm bar cut into ten 10 mm pieces. Each piece loses
   half a kerf on both sides, so the ten pushed together measure 100 - 10·kerf.
2. **press-fit slots**: open slots of the nominal thickness + δ (δ engraved
   under each, in mm); a strip of the same sheet tried in each.
3. **hinge pieces**: two tiles joined by the material's hinge kind, cut by the
   real ``fabkiri cut`` pipeline (a 1×2 pattern), at several values of the
   field that kind depends on (ligament width; separate tiles' kerf
   compensation; tape: tile size, i.e. the narrowest tile the hinge holds).

Printer (a printer preset): a clearance ladder (pegs standing in holes of
radial clearance c, left to right ascending, printed in place) and strip
hinges (two tiles with a flexible strip recessed flush in their top face) at
several strip widths; 3MF (one object per body) + STL, checked watertight and
free of intersections.

Each coupon comes with what to measure and which preset field it sets.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..exchange.drawing import SheetDrawing
from ..exchange.dxf.writer import dxf_bytes
from ..exchange.svg import svg_bytes
from ..mechanics.contract import with_contracted_states
from ..pattern.kinds.quad.lattice import standard_pattern
from .cut.hingekinds import hinge_kind
from .cut.materials import Material
from .cut.preview import png_bytes
from .cut.sheets import CutOptions, cut_pattern
from .cut.text import text_strokes, text_width
from .print.printers import Printer

MARGIN = 5.0
ROW_GAP = 6.0
COMB_PIECES = 10
COMB_PITCH = 10.0
COMB_HEIGHT = 12.0
SLOT_DELTAS = (-0.15, -0.1, -0.05, 0.0, 0.05, 0.1, 0.15, 0.2, 0.25)
SLOT_DEPTH = 8.0
SLOT_PITCH = 12.0
LABEL_H = 2.5


@dataclass
class Coupon:
    """A coupon: its files, what to measure, and the sizes it was drawn at."""

    files: dict[str, bytes]
    instructions: list[dict[str, str]]
    info: dict[str, Any] = field(default_factory=dict)


def _label(sd: SheetDrawing, text: str, x: float, y: float, h: float = LABEL_H) -> None:
    for p in text_strokes(text, h, (x, y)):
        sd.add("ENGRAVE", p, False)


def _comb(sd: SheetDrawing, x0: float, y0: float) -> float:
    """The kerf comb with its lower left at (x0, y0); returns its height."""
    W = COMB_PIECES * COMB_PITCH
    sd.add(
        "CUT",
        np.array([[x0, y0], [x0 + W, y0], [x0 + W, y0 + COMB_HEIGHT], [x0, y0 + COMB_HEIGHT]]),
        True,
    )
    for k in range(1, COMB_PIECES):
        x = x0 + k * COMB_PITCH
        sd.add("CUT", np.array([[x, y0], [x, y0 + COMB_HEIGHT]]), False)
    for k in range(COMB_PIECES):
        _label(sd, str(k + 1), x0 + (k + 0.5) * COMB_PITCH, y0 + COMB_HEIGHT / 2, 4.0)
    return COMB_HEIGHT


def _slots(sd: SheetDrawing, mat: Material, x0: float, y0: float) -> float:
    """A comb of open slots cut into the top edge of a plate; returns its height."""
    n = len(SLOT_DELTAS)
    W = n * SLOT_PITCH
    H = SLOT_DEPTH + 4.0 + LABEL_H + 2.0
    top = y0 + H
    pts = [[x0, y0], [x0 + W, y0], [x0 + W, top]]
    for k in reversed(range(n)):  # the top edge runs right to left, dipping into each slot
        w = mat.thickness_mm + SLOT_DELTAS[k]
        cx = x0 + (k + 0.5) * SLOT_PITCH
        pts += [
            [cx + w / 2, top],
            [cx + w / 2, top - SLOT_DEPTH],
            [cx - w / 2, top - SLOT_DEPTH],
            [cx - w / 2, top],
        ]
        text = f"{SLOT_DELTAS[k]:.2f}"
        _label(
            sd, text, cx, y0 + 1.0 + LABEL_H / 2, min(LABEL_H, 0.9 * SLOT_PITCH / text_width(text))
        )
    pts.append([x0, top])
    sd.add("CUT", np.array(pts, float), True)
    return H


def hinge_variants(mat: Material) -> tuple[str, str, list[dict[str, float]]]:
    """The field the hinge pieces sweep, its engraved prefix, and the cut settings of each piece
    (the material's hinge kind decides)."""
    return hinge_kind(mat.hinge).coupon_variants(mat)


def _hinge_piece(mat: Material, v: dict[str, float]) -> SheetDrawing:
    """Two tiles joined by one hinge, cut in closed state 1 by ``cut_pattern``."""
    p = with_contracted_states(standard_pattern(1, 2, tile_size=v["tile"], name="hinge coupon"))
    m = mat.override(kerf_mm=v.get("kerf"))
    res = cut_pattern(
        p,
        CutOptions(
            material=m,
            reference_mm=0.0,
            sheet=(200.0, 200.0),
            margin=1.0,
            ligament_width=v.get("ligament_width"),
            stem="coupon",
            formats=("dxf",),
        ),
    )
    return res.sheets[0]


def _bounds(sd: SheetDrawing, layers: tuple[str, ...] = ("CUT",)) -> np.ndarray:
    pts = np.concatenate([p for name in layers for p, _ in sd.layers[name]])
    return np.r_[pts.min(0), pts.max(0)]


def _paste(dst: SheetDrawing, src: SheetDrawing, dx: float, dy: float) -> None:
    for name in ("CUT", "ENGRAVE", "SCORE"):
        for (p, closed), g in zip(src.layers[name], src.groups[name]):
            dst.add(name, p + [dx, dy], closed, g)


def laser_coupon(mat: Material, notes: bool = False) -> Coupon:
    """The laser coupon of a material (see the module doc)."""
    field_name, prefix, variants = hinge_variants(mat)
    pieces = [_hinge_piece(mat, v) for v in variants]
    boxes = [_bounds(sd) for sd in pieces]
    row_w = max(
        COMB_PIECES * COMB_PITCH,
        len(SLOT_DELTAS) * SLOT_PITCH,
        sum(b[2] - b[0] for b in boxes) + ROW_GAP * (len(boxes) - 1),
    )
    piece_h = max(b[3] - b[1] for b in boxes)
    slots_h = SLOT_DEPTH + 4.0 + LABEL_H + 2.0
    H = 2 * MARGIN + COMB_HEIGHT + slots_h + piece_h + LABEL_H + 2.0 + 2 * ROW_GAP
    W = 2 * MARGIN + row_w
    sd = SheetDrawing(index=1, width=float(np.ceil(W)), height=float(np.ceil(H)))
    y = MARGIN
    x = MARGIN
    for v, piece, b in zip(
        variants, pieces, boxes
    ):  # bottom row: hinge pieces, value engraved under each
        _paste(sd, piece, x - b[0], y + LABEL_H + 2.0 - b[1])
        _label(sd, f"{prefix}{v['value']:g}", x + (b[2] - b[0]) / 2, y + LABEL_H / 2)
        x += b[2] - b[0] + ROW_GAP
    y += LABEL_H + 2.0 + piece_h + ROW_GAP
    y += _slots(sd, mat, MARGIN, y) + ROW_GAP
    _comb(sd, MARGIN, y)
    if notes:
        sd.add(
            "NOTES",
            np.array([[0, 0], [sd.width, 0], [sd.width, sd.height], [0, sd.height]], float),
            True,
        )
    stem = f"coupon-{mat.name}"
    colors = mat.colors
    files = {
        f"{stem}.dxf": dxf_bytes(sd, colors),
        f"{stem}.svg": svg_bytes(sd, colors),
        f"{stem}.png": png_bytes([sd], colors, px_per_mm=8.0),
    }
    instructions = _laser_instructions(mat, field_name, prefix)
    info = {
        "material": mat.name,
        "hinge": mat.hinge,
        "sheet_mm": [sd.width, sd.height],
        "comb": {
            "pieces": COMB_PIECES,
            "pitch_mm": COMB_PITCH,
            "length_mm": COMB_PIECES * COMB_PITCH,
        },
        "slots": {
            "widths_mm": [round(mat.thickness_mm + d, 4) for d in SLOT_DELTAS],
            "deltas_mm": list(SLOT_DELTAS),
        },
        "hinge_pieces": {"field": field_name, "values": [v["value"] for v in variants]},
        "files": sorted(files),
    }
    return Coupon(files=files, instructions=instructions, info=info)


def _laser_instructions(mat: Material, field_name: str, prefix: str) -> list[dict]:
    """How to measure each feature of the laser coupon and which material field it sets."""
    hinge_how = {
        "ligament_width_mm": "fold each piece through the full closing angle 20 times; the widest ligament that "
        "neither cracks nor whitens",
        "kerf_mm": "measure each tile with calipers; the piece whose tiles measure exactly 10.00 mm across",
        "min_web_mm": "tape each pair as the engraved face letter says and fold it closed 20 times; the smallest "
        "tile size that cut cleanly and held: its width",
    }[field_name]
    return [
        {
            "feature": "kerf comb (10 pieces, 10 mm pitch)",
            "measure": "push the ten pieces together end to end and measure the total length L in mm",
            "sets": "kerf_mm = (100 - L) / 10",
        },
        {
            "feature": f"press-fit slots (nominal {mat.thickness_mm:g} mm + engraved δ)",
            "measure": "slide an offcut strip of the same sheet into each slot; note δ of the narrowest slot it enters "
            "with a firm press",
            "sets": f"thickness_mm = {mat.thickness_mm:g} + δ (the sheet's effective thickness, once kerf_mm is set)",
        },
        {
            "feature": f"{mat.hinge} hinge pieces ({prefix} = {field_name})",
            "measure": hinge_how,
            "sets": field_name,
        },
    ]


# ------------------------------------------------------------------ printer

LADDER_STEPS = (0.1, 0.15, 0.2, 0.25, 0.3, 0.35, 0.4, 0.5)
PEG_R = 3.0
LADDER_PITCH = 9.0
HINGE_TILE = 15.0


def _box(x0, y0, x1, y1, z0, z1):
    import manifold3d as m3d

    return m3d.Manifold.cube((x1 - x0, y1 - y0, z1 - z0)).translate((x0, y0, z0))


def _cyl(x, y, r, z0, z1):
    import manifold3d as m3d

    return m3d.Manifold.cylinder(z1 - z0, r, r, 96).translate((x, y, z0))


def printer_bodies(pr: Printer) -> dict[str, Any]:
    """Manifold solids of the printer coupon: ``plate`` (ladder plate + hinge tiles), ``pegs``, ``strips``."""
    t = pr.tile_thickness_mm
    n = len(LADDER_STEPS)
    L = n * LADDER_PITCH + 4.0
    plate = _box(0, 0, L, 2 * PEG_R + 8.0, 0, t)
    plate = plate + _box(
        0, 2 * PEG_R + 8.0, 4.0, 2 * PEG_R + 12.0, 0, t
    )  # a tab marks the smallest end
    pegs = None
    yc = PEG_R + 4.0
    for k, c in enumerate(LADDER_STEPS):
        x = 2.0 + (k + 0.5) * LADDER_PITCH
        plate = plate - _cyl(x, yc, PEG_R + c, -1.0, t + 1.0)
        peg = _cyl(x, yc, PEG_R, 0.0, t + 2.0)
        pegs = peg if pegs is None else pegs + peg
    widths = sorted(
        {
            round(w, 2)
            for w in (
                0.5 * pr.strip_width_mm,
                0.75 * pr.strip_width_mm,
                pr.strip_width_mm,
                1.5 * pr.strip_width_mm,
                2.0 * pr.strip_width_mm,
            )
        }
    )
    y0 = 2 * PEG_R + 12.0 + pr.part_spacing_mm + 2.0
    g = pr.gap_mm
    reach = min(pr.strip_reach_mm, HINGE_TILE - 1.0)
    st = pr.strip_thickness_mm
    tiles = strips = None
    x = 0.0
    for w in widths:
        a = _box(x, y0, x + HINGE_TILE, y0 + HINGE_TILE, 0, t)
        b = _box(x + HINGE_TILE + g, y0, x + 2 * HINGE_TILE + g, y0 + HINGE_TILE, 0, t)
        ym = y0 + HINGE_TILE / 2
        s = _box(
            x + HINGE_TILE - reach, ym - w / 2, x + HINGE_TILE + g + reach, ym + w / 2, t - st, t
        )
        pair = (a + b) - s  # the strip's pocket, flush with the top face
        tiles = pair if tiles is None else tiles + pair
        strips = s if strips is None else strips + s
        x += 2 * HINGE_TILE + g + pr.part_spacing_mm
    return {"plate": plate + tiles, "pegs": pegs, "strips": strips, "widths": widths}


def printer_coupon(pr: Printer) -> Coupon:
    """The printer coupon (see the module doc), centred on the bed."""
    import trimesh

    from .print.mesh import export_3mf
    from .print.solid import to_trimesh

    bodies = printer_bodies(pr)
    widths = bodies.pop("widths")
    lo = np.min([m.bounding_box()[:3] for m in bodies.values()], axis=0)
    hi = np.max([m.bounding_box()[3:] for m in bodies.values()], axis=0)
    shift = (
        0.5 * pr.bed_mm[0] - 0.5 * (lo[0] + hi[0]),
        0.5 * pr.bed_mm[1] - 0.5 * (lo[1] + hi[1]),
        0.0,
    )
    bodies = {k: m.translate(shift) for k, m in bodies.items()}
    meshes = {k: to_trimesh(m) for k, m in bodies.items()}
    checks = {
        k: {
            "watertight": bool(tm.is_watertight),
            "winding_consistent": bool(tm.is_winding_consistent),
            "volume_mm3": round(float(tm.volume), 4),
            "solid_volume_mm3": round(float(bodies[k].volume()), 4),
        }
        for k, tm in meshes.items()
    }
    inter = {
        "plate & pegs": float((bodies["plate"] ^ bodies["pegs"]).volume()),
        "plate & strips": float((bodies["plate"] ^ bodies["strips"]).volume()),
    }
    size = (hi - lo).tolist()
    scene = trimesh.Scene()
    material = {"plate": pr.tile_material, "pegs": pr.tile_material, "strips": pr.strip_material}
    for k, tm in meshes.items():
        scene.add_geometry(tm, geom_name=f"{k}_{material[k]}", node_name=f"{k}_{material[k]}")
    stem = f"coupon-{pr.name}"
    files = {f"{stem}.3mf": export_3mf(scene)}
    for k, tm in meshes.items():
        files[f"{stem}_{k}.stl"] = tm.export(file_type="stl")
    instructions = [
        {
            "feature": f"clearance ladder: {len(LADDER_STEPS)} pegs, radial clearance "
            f"{LADDER_STEPS[0]:g} to {LADDER_STEPS[-1]:g} mm, smallest at the tab",
            "measure": "push each peg down; note the smallest clearance whose peg comes free and turns by hand",
            "sets": "radial_clearance_mm",
        },
        {
            "feature": f"strip hinges, widths {', '.join(f'{w:g}' for w in widths)} mm (narrowest at the left), "
            f"{pr.strip_material} strips in {pr.tile_material} tiles",
            "measure": "fold each pair closed 20 times; the narrowest strip that neither tears nor peels out",
            "sets": "strip_width_mm",
        },
    ]
    info = {
        "printer": pr.name,
        "size_mm": [round(v, 3) for v in size],
        "clearances_mm": list(LADDER_STEPS),
        "strip_widths_mm": widths,
        "checks": checks,
        "intersection_mm3": inter,
        "files": sorted(files),
    }
    return Coupon(files=files, instructions=instructions, info=info)
