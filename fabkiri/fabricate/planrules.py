"""How ``--scale auto``, ``design`` and ``info`` size a print style: a :class:`PlanRule` per kind of
printed hinge (``PrintStyle.plan``): strips (:data:`STRIP_PLAN`, both strip styles) and pins
(:data:`PIN_PLAN`). :mod:`.fabricability` bisects on the rule's plan check, started from its
closed-form bound; a style with new hinge geometry brings its own rule.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np
import shapely
import shapely.errors

from ..errors import FabricationError
from ..pattern import geometry
from ..pattern import thinness as fab
from ..pattern.model import Pattern
from .fabricability import MAX_SCALE, MIN_GUESS, PrintMinimum, ceil_sig, closest_pair
from .print.printers import Printer


@dataclass(frozen=True)
class PlanRule:
    """How ``--scale auto``, ``design`` and ``info`` size a print style (its ``PrintStyle.plan``):
    ``check(pattern, plan, printer)`` raises :class:`FabricationError` where the plan is refused,
    ``bound(pattern, corners, printer, s_shrink, state, face)`` is the smallest scale in closed form
    (``bound_is_lower``: a lower bound, so the bisection brackets upwards from it) and ``fields(printer)``
    the preset fields both read besides gap, radial clearance and nozzle."""

    check: Callable[..., Any]
    bound: Callable[..., PrintMinimum]
    fields: Callable[[Printer], tuple]
    bound_is_lower: bool = False


def _strip_check(pattern: Pattern, plan, printer: Printer) -> None:
    from .print import geometry as printgeom

    printgeom.strip_outlines(plan, printer)


def _pin_check(pattern: Pattern, plan, printer: Printer) -> None:
    from .print import pingeom

    pingeom.check_pins(pattern, plan, printer)


def _pin_fields(printer: Printer) -> tuple:
    return (
        printer.pin.ear_radius_mm,
        printer.pin.pin_radius_mm,
        printer.pin.tile_thickness_mm,
        printer.axial_clearance_mm,
        printer.layer_mm,
        printer.tolerance_mm,
    )


def _strip_fields(printer: Printer) -> tuple:
    return (printer.strip_width_mm, printer.strip_reach_mm)


def _strip_bound(
    pattern: Pattern, c: np.ndarray, printer: Printer, s_shrink: float, state: int, face: np.ndarray
) -> PrintMinimum:
    """Strips: the tile shrink, same-face strip clearance and pad area scales (see :func:`print_bound`)."""
    top_ = pattern.topology
    d = 0.5 * printer.gap_mm
    ends = top_.fold(state).fold_corner_ends
    same = fab.same_face_pairs(top_.hinge_tiles, face, top_.n_tiles)
    clear = fab.strip_clearance_scales(
        c,
        top_.hinge_tiles,
        top_.hinge_corner,
        ends,
        same,
        d,
        printer.strip_width_mm,
        printer.strip_reach_mm,
        printer.radial_clearance_mm,
    )
    s_clear = float(clear.max(initial=0.0))
    s = max(s_shrink, s_clear)
    try:
        s_pad = _pad_scale(c, top_.hinge_tiles, top_.hinge_corner, ends, printer, max(s, MIN_GUESS))
    except (
        shapely.errors.GEOSException
    ) as exc:  # a self-intersecting tile (the shared bow-tie reference)
        return PrintMinimum(None, None, f"the pad geometry failed in GEOS ({exc})")
    if s_pad is None:
        return PrintMinimum(
            None,
            None,
            "a strip pad is too small at any scale: a hinge corner is too sharp for "
            "the strip width",
        )
    why = "strip pads" if s_pad > s else "strip clearance" if s_clear >= s_shrink else "tile shrink"
    return PrintMinimum(ceil_sig(max(s, s_pad)), None, f"{why} (closed form)", exact=False)


def _pad_areas(
    c,
    hinge_tiles,
    hinge_corner,
    ends,
    printer: Printer,
    scale: np.ndarray,
    which: np.ndarray,
    need: float | None = None,
):
    """Area of both pads (band ∩ tile shrunk by gap/2) of hinges ``which`` at their ``scale``: ``(n, 2)``.
    With ``need``, a convex pad shown to hold a rectangle of that area or more is not clipped: inf."""
    d = 0.5 * printer.gap_mm
    w, R = printer.strip_width_mm, printer.strip_reach_mm + d
    cs = c[hinge_tiles[which]] * scale[:, None, None, None]  # (n, 2, 4, 2)
    sub = np.arange(len(which))
    tiles = cs.reshape(-1, 4, 2)
    p, e, n, t0 = fab.strip_frames(
        tiles, np.stack([2 * sub, 2 * sub + 1], 1), hinge_corner[which], ends[which], d
    )
    perp = n[:, 0]
    band = np.stack(
        [
            p + t0[:, None] * e - R * perp,
            p + (t0 + w)[:, None] * e - R * perp,
            p + (t0 + w)[:, None] * e + R * perp,
            p + t0[:, None] * e + R * perp,
        ],
        1,
    )
    shrunk, edges = fab.shrunk_tiles(tiles, d)
    band = np.repeat(band, 2, axis=0)
    # a degenerate tile (a bow-tie, a zero-length seam) has no pad: it gets no polygon, area 0
    ok = (
        (edges.min(-1) > fab.EDGE_EPS_MM)
        & np.isfinite(band).all((1, 2))
        & np.isfinite(shrunk).all((1, 2))
    )
    area = np.zeros(len(tiles))
    b, t = band[ok], shrunk[ok]
    if geometry.strictly_convex(b).all() and geometry.strictly_convex(t).all():
        # convex pads (a design's tiles are convex): clipped in numpy, for every pad at once (GEOS was
        # slow at 128x128); a concave or bow-tie tile keeps GEOS, and its refusal
        if need is not None:  # the others' exact areas are asked only whether they are below it
            held = ok & _holds(shrunk, p, e, n, t0, w, R, need)
            area[held], ok = np.inf, ok & ~held
            b, t = band[ok], shrunk[ok]
        area[ok] = geometry.clipped_areas(t, b)
    else:
        area[ok] = shapely.area(shapely.intersection(shapely.polygons(b), shapely.polygons(t)))
    return area.reshape(-1, 2)


HELD_ALONG, HELD_ACROSS = (0.125, 0.875), (0.5, 0.875)  # the rectangle a pad is shown to hold


def _holds(shrunk, p, e, n, t0, w: float, R: float, need: float) -> np.ndarray:
    """Which pads (band ∩ ``shrunk`` tile; the hinges' frames ``p, e, n, t0``, both sides of each) hold a
    rectangle of area ``need`` or more: the band's middle three quarters along the seam, from half to seven
    eighths of its reach on the tile's side (inside the band by an eighth of its sides, far more than
    round-off), when each of its corners is inside the convex shrunk tile by more than round-off."""
    (a0, a1), (b0, b1) = HELD_ALONG, HELD_ACROSS
    if not ((a1 - a0) * w * (b1 - b0) * R >= need * (1 + 1e-9) and min(w, R) > 0):
        return np.zeros(len(shrunk), dtype=bool)
    along = t0[:, None] + np.array([a0, a1, a1, a0]) * w  # (H, 4)
    across = np.array([b0, b0, b1, b1]) * R
    corner = p[:, None] + along[..., None] * e[:, None]  # (H, 4, 2), then each side's (2H, 4, 2):
    q = (corner[:, None] + across[:, None] * n[:, :, None]).reshape(-1, 4, 2)
    size = np.maximum(np.abs(q).max((1, 2)), np.abs(shrunk).max((1, 2)))
    orient = np.sign(geometry.signed_areas(shrunk))[:, None, None]
    edge = np.roll(shrunk, -1, 1) - shrunk
    inner = orient * geometry.cross2(
        edge[:, :, None], q[:, None] - shrunk[:, :, None]
    )  # (2H, 4, 4)
    return (inner > (1e-9 * size * size)[:, None, None]).all((1, 2))


def _pad_scale(c, hinge_tiles, hinge_corner, ends, printer: Printer, s0: float) -> float | None:
    """Smallest scale ≥ s0 at which every pad has the plan's area (bisection on the short pads only)."""
    need = 0.25 * printer.strip_width_mm * min(printer.strip_reach_mm, printer.strip_width_mm)
    H = len(hinge_tiles)
    short = np.flatnonzero(
        _pad_areas(
            c, hinge_tiles, hinge_corner, ends, printer, np.full(H, s0), np.arange(H), need
        ).min(1)
        < need
    )
    if not len(short):
        return s0
    top = np.full(len(short), MAX_SCALE)
    if (_pad_areas(c, hinge_tiles, hinge_corner, ends, printer, top, short).min(1) < need).any():
        return None
    lo, hi = np.full(len(short), s0), top
    while (hi - lo > 1e-4 * hi).any():
        mid = 0.5 * (lo + hi)
        bad = _pad_areas(c, hinge_tiles, hinge_corner, ends, printer, mid, short).min(1) < need
        lo, hi = np.where(bad, mid, lo), np.where(bad, hi, mid)
    return float(hi.max())


def _pin_bound(
    pattern: Pattern,
    c: np.ndarray,
    printer: Printer,
    s_shrink: float,
    state: int = 1,
    face: np.ndarray | None = None,
) -> PrintMinimum:
    """Pinned: the checks that need no geometry (ear levels, ring wall, rigid-deployable) and the pivot
    spacing, linear in the scale; a lower bound (the sliver check beside the clearances is not modelled)."""
    from ..pattern.kinds.tessellation import tessellation
    from ..pattern.residuals import hinge_sums
    from .print import pinsizes

    try:
        g = pinsizes.pin_geometry(
            printer, pinsizes.pin_levels(printer, pinsizes.pin_stack(pattern))
        )
    except FabricationError as exc:
        return PrintMinimum(None, None, str(exc))
    if (
        tessellation(pattern.kind).rigid_family
        and np.abs(hinge_sums(pattern)).max(initial=0.0) > 1e-6
    ):
        return PrintMinimum(None, None, "not rigid-deployable: pinned tiles would have to bend")
    top_ = pattern.topology
    A, B = top_.hinge_tiles.T
    xy = 0.5 * (c[A, top_.hinge_corner[:, 0]] + c[B, top_.hinge_corner[:, 1]])
    pts = np.unique(
        np.round(xy / (1e-6 * max(pattern.tile_size, 1e-12))), axis=0, return_index=True
    )[1]
    piv = xy[np.sort(pts)]
    s = s_shrink
    if len(piv) > 1:
        s = max(s, (2 * g.hollow + 2 * printer.nozzle_mm) / closest_pair(piv))
    return PrintMinimum(
        ceil_sig(s),
        None,
        "pivot spacing (closed form, a lower bound: print also checks the "
        "slivers beside the clearances)",
        exact=False,
    )


STRIP_PLAN = PlanRule(_strip_check, _strip_bound, _strip_fields)  # strips and tiles-and-strips
PIN_PLAN = PlanRule(_pin_check, _pin_bound, _pin_fields, bound_is_lower=True)
