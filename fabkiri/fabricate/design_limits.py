"""The fabrication limits ``design`` solves under, read from the material and printer presets.

``design --material/--hinge/--printer/--style`` turns a preset into plain numbers in mm (thinnest
tile, hinge spacing, smallest hole) that the design layer's fabrication inequalities keep; the same
presets decide, in :mod:`.fabricability`, the size at which ``cut`` and ``print`` accept the result.
"""

from __future__ import annotations

import numpy as np

from ..design.quad.fabrication import FabricationLimits
from ..design.targets.curve import Target
from ..errors import FabricationError, InputError, Param
from .cut.hingekinds import hinge_kind
from .cut.materials import HINGE_KINDS, Material, load_material
from .print.job import print_style
from .print.printers import Printer, load_printer, min_pad_mm2

PAD_MARGIN_DEG = (
    5.0  # above the corner angle at which a strip pad reaches the printer's minimum area
)


def material_limits(material: Material, kind: str | None = None) -> dict:
    """What ``cut`` needs of every tile, as plain numbers for ``design`` (mm)."""
    kind = kind or material.hinge
    if kind not in HINGE_KINDS:
        raise FabricationError(f"hinge kind must be one of {', '.join(HINGE_KINDS)}, got {kind!r}")
    hk = hinge_kind(kind)
    if hk.never(material):
        raise FabricationError(
            f"{material.name} cannot be cut as a {kind} sheet: {hk.never(material)}"
        )
    shrink = hk.shrink(material)
    return {
        "min_width_mm": hk.min_width(material),
        "shrink_mm": shrink,
        "min_edge_mm": material.min_web_mm if shrink else 0.0,
        "hinge_spacing_mm": hk.hinge_spacing(material),
    }


def printer_limits(printer: Printer, style: str) -> dict:
    """What ``print`` needs of every tile (mm): two perimeters wide once shrunk by gap/2, hinge corners
    wide enough for a strip pad (strip styles) or pivots far enough apart for two ears (pinned)."""
    out = {
        "min_width_mm": 2.0 * printer.nozzle_mm,
        "shrink_mm": 0.5 * printer.gap_mm,
        "min_edge_mm": printer.nozzle_mm,
    }
    hinges = print_style(style).limits
    if hinges is not None:  # what the style's hinges ask of the tiles
        out.update(hinges(printer))
    return out


def strip_limits(printer: Printer) -> dict:
    """What a printed strip asks of the tiles it joins (the strip styles' ``PrintStyle.limits``)."""
    # a pad on an acute corner is about a triangle: ½ tan α w² against the printer's 0.25 w min(reach, w)
    w, reach = printer.strip_width_mm, printer.strip_reach_mm
    out = {
        "min_hinge_angle_deg": float(np.degrees(np.arctan(0.5 * min(reach, w) / w)))
        + PAD_MARGIN_DEG
    }
    # two strips on one face of a tile keep the radial clearance (their boxes, as print_bound); a thin
    # tile is no obstacle by itself, the strip is clipped to it (the old 2·reach + clearance width row
    # asked 8.3 mm of every tile on prusa-mk4 where print accepts the 8x8 circle from 1.6 mm tiles)
    out.update(
        strip_clearance_mm=printer.radial_clearance_mm, strip_width_mm=w, strip_reach_mm=reach
    )
    out["strip_pad_mm2"] = min_pad_mm2(printer)  # the pad area print's plan asks
    out["hinge_edge_mm"] = (
        w + printer.gap_mm
    )  # the strip runs w along the seam from the shrunk corner
    return out


def combine(*limits: dict) -> dict:
    """The strictest of several requirements (shrinking by more and needing more width is conservative)."""
    out: dict = {}
    for lim in limits:
        for k, v in lim.items():
            out[k] = max(out.get(k, 0.0), v)
    return out


def resolve(
    material: str | None,
    hinge: str | None,
    printer: str | None,
    style: str | None,
    min_feature: float | None,
    min_hole: float | None,
    target: Target | None,
) -> tuple[FabricationLimits | None, dict]:
    """``design``'s ``--material/--hinge``, ``--printer/--style``, ``--min-feature`` and ``--min-hole`` as plain
    mm limits (None: no fabrication rows), and the intent stored in the design for ``cut``/``print``."""
    parts, names = [], []
    intent: dict[
        str, str | float
    ] = {}  # cut/print defaults: material, hinge, printer, style, size, scale
    if hinge and not material:
        raise InputError(
            Param("hinge"), " needs ", Param("material"), " (the hinge kind of a laser-cut sheet)"
        )
    if style and not printer:
        raise InputError(Param("style"), " needs ", Param("printer"))
    if material:
        mat = load_material(material)
        kind = hinge or mat.hinge
        try:
            parts.append(material_limits(mat, kind))
        except FabricationError as exc:
            raise InputError(str(exc)) from None
        names.append(f"{mat.name} {kind}")
        intent.update(material=material, hinge=kind)
    if printer:
        pr = load_printer(printer)
        style = style or "tiles-and-strips"
        parts.append(printer_limits(pr, style))
        names.append(f"{pr.name} {style}")
        intent.update(printer=printer, style=style)
    if min_feature:
        parts.append({"min_width_mm": min_feature})
        names.append(f"--min-feature {min_feature:g}")
    if min_hole:
        parts.append({"min_hole_mm": min_hole})
        names.append(f"--min-hole {min_hole:g}")
    if not parts:
        return None, {}
    if target is not None:
        intent["size_mm"] = float(target.size)
    intent["scale"] = 1.0  # the design is made at the size it will be cut or printed
    return FabricationLimits(**combine(*parts), source=", ".join(names)), intent


def fits_bed(corners: np.ndarray, printer: str) -> bool:
    """Whether a closed state's tiles ``(T, 4, 2)`` (mm) lie within ``printer``'s bed, as ``print`` lays them
    (axis-aligned, not turned)."""
    bx, by, _ = load_printer(printer).bed_mm
    w, h = np.ptp(np.asarray(corners, float).reshape(-1, 2), axis=0)
    return bool(w <= bx and h <= by)


def bed_state(states: dict, printer: str) -> int:
    """The closed state ``print`` should make on ``printer``: 1 when its tiles ``states[1]`` (mm) fit the bed,
    else 2 when those do, else 1 (neither fits; the design reports ``fits_bed`` false)."""
    if fits_bed(states[1], printer) or 2 not in states or not fits_bed(states[2], printer):
        return 1
    return 2
