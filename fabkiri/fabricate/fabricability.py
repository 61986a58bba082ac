"""At what size a pattern can be cut or printed: the numbers behind ``cut``/``print`` refusals and
``--scale auto``, and the fabricability summary ``design`` and ``info`` show.

Cutting: every tile that stays (shrunk by gap/2 for a ligament sheet) must be at least the material's
minimum web wide, in the thinnest-width sense of :mod:`fabkiri.pattern.thinness` (the check
``cut`` runs), and a shrunk tile must keep its four edges; both are linear in the scale, so the
smallest scale is exact (:func:`cut_minimum`). Printing: the printer's plan checks (tile shrink,
strip seams, pads and clearances, pins) are shapely geometry, monotone in the scale, so the smallest
scale is found by bisection on those very checks (:func:`print_minimum`), and the bed sets the largest.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING, Any

import numpy as np
import shapely
import shapely.errors

from ..errors import CheckFailed, FabricationError, Param, cli_text
from ..pattern import thinness as fab
from ..pattern.model import Pattern
from .cut.hingekinds import hinge_kind
from .cut.materials import HINGE_KINDS, Material, available, load_material
from .fabricability_text import summary_lines  # noqa: F401 (its callers read it from here)
from .print.job import print_style
from .print.printers import Printer, available_printers, load_printer

if TYPE_CHECKING:
    from .planrules import PlanRule

DIGITS = (
    4  # stated minima are rounded up to this many significant digits (so the stated value passes)
)
BISECT_RTOL = 1e-3  # print minimum: the bracket is this tight before the upper end is stated
MAX_SCALE = 1e3


def ceil_sig(x: float, digits: int = DIGITS) -> float:
    """``x`` rounded up to ``digits`` significant digits (never below ``x``)."""
    if not (np.isfinite(x) and x > 0):
        return x
    q = 10.0 ** (math.floor(math.log10(x)) - digits + 1)
    v = float(f"{math.ceil(x / q) * q:.{digits + 1}g}")
    return v if v >= x else float(f"{v + q:.{digits + 1}g}")


def floor_sig(x: float, digits: int = DIGITS) -> float:
    """``x`` rounded down to ``digits`` significant digits (never above ``x``)."""
    if not (np.isfinite(x) and x > 0):
        return x
    q = 10.0 ** (math.floor(math.log10(x)) - digits + 1)
    v = float(f"{math.floor(x / q) * q:.{digits + 1}g}")
    return v if v <= x else float(f"{v - q:.{digits + 1}g}")


def shrink_of(material: Material, kind: str) -> float:
    """How far ``cut`` shrinks every tile for this hinge kind (mm)."""
    return hinge_kind(kind).shrink(material)


def closed_span(corners: np.ndarray) -> float:
    """x extent of a closed state: ``cut --width`` is this times the scale."""
    return float(corners[..., 0].max() - corners[..., 0].min())


@dataclass(frozen=True)
class CutMinimum:
    """Smallest scale (and --width) at which ``cut`` accepts a closed state; ``scale`` None: never."""

    scale: float | None
    width_mm: float | None
    tile: int = -1
    limit: str = ""  # "width" (thinnest tile), "edge" (a shrunk tile loses an edge) or why never
    exact: float | None = None  # unrounded

    def advice(self) -> str:
        """The advice in the command line's words (``--scale ≥ ...``)."""
        return cli_text(self.advice_parts())

    def advice_parts(self) -> tuple:
        """The advice as message parts: ``scale ≥ ...`` to a library caller, ``--scale ≥ ...`` on the
        command line (:class:`~fabkiri.errors.Param`)."""
        if self.scale is None:
            return (f"no scale works ({self.limit})",)
        return (
            "cut at ", Param("scale"), f" ≥ {self.scale:g}, ", Param("width"),
            f" ≥ {self.width_mm:g} mm (or ", Param("scale", "auto"), ")",
        )  # fmt: skip

    def to_dict(self) -> dict:
        return {
            "min_scale": self.scale,
            "min_width_mm": self.width_mm,
            "tile": self.tile,
            "limit": self.limit,
        }


def ligament_never(material: Material) -> str:
    """Why a ligament sheet of this material cannot be cut at any scale ('' if it can)."""
    spacing = material.gap_mm - max(material.min_web_mm, 0.0)
    if spacing < material.min_web_mm + material.kerf_mm - 1e-9:
        return (
            f"gap {material.gap_mm:g} mm leaves less than min web + kerf between the two ligaments of a node "
            f"at any scale"
        )
    return ""


def cut_minimum(corners: np.ndarray, material: Material, kind: str, memo=None) -> CutMinimum:
    """Smallest scale of the closed state ``corners`` (pattern units) that ``cut`` accepts for ``kind``."""
    why = hinge_kind(kind).never(material)
    if why:
        return CutMinimum(None, None, -1, why)
    shrink = shrink_of(material, kind)
    web = material.min_web_mm
    s, t, limit = _kept(memo, fab.TileScales, corners)(web, shrink, web if shrink else 0.0)
    if not np.isfinite(s):
        return CutMinimum(None, None, t, "a tile is degenerate")
    scale = ceil_sig(s)
    return CutMinimum(scale, ceil_sig(scale * closed_span(corners)), t, limit, s)


def _kept(memo: dict | None, fn: Callable, first, *args) -> Any:
    """``fn(first, *args)`` kept in ``memo`` (the summary's: presets ask alike of state 1) by ``fn``, ``first``'s
    identity (the summary holds it while the memo lives) and ``args``."""
    if memo is None:
        return fn(first, *args)
    key = (fn, id(first), *args)
    return memo[key] if key in memo else memo.setdefault(key, fn(first, *args))


def check_webs(
    regions: np.ndarray, material: Material, kind: str, corners: np.ndarray, scale: float
) -> None:
    """``cut``'s web check: every tile that stays is at least the minimum web wide (thinnest width)."""
    w = fab.widths(regions)
    shrinks = hinge_kind(kind).shrinks
    if shrinks:  # a shrunk tile's edge shorter than a web is a sliver corner: as thin as it
        w = np.minimum(w, fab.shrunk_edges(regions, 0.0).min(-1))
    bad = np.flatnonzero(w < material.min_web_mm - fab.WEB_SLACK_MM)
    if len(bad):
        t = int(bad[np.argmin(w[bad])])
        what = f" once shrunk by gap/2 ({shrink_of(material, kind):g} mm)" if shrinks else ""
        need = cut_minimum(corners / scale, material, kind)
        raise CheckFailed(
            f"tile {t} is {w[t]:.3g} mm wide at its thinnest{what} at scale {scale:.4g}, thinner than the minimum "
            f"web {material.min_web_mm:g} mm of {material.name} ({len(bad)} tile(s) too thin); ",
            *need.advice_parts(),
            *(SMALLER_GAP if shrinks else ()),
        )


def lost_edge(
    corners: np.ndarray, material: Material, kind: str, scale: float, tile: int
) -> CheckFailed:
    """The refusal for a ligament tile that loses an edge when shrunk, with the scale that avoids it."""
    need = cut_minimum(corners / scale, material, kind)
    return CheckFailed(
        f"tile {tile} loses an edge once shrunk by gap/2 ({shrink_of(material, kind):g} mm) at scale "
        f"{scale:.4g}; ",
        *need.advice_parts(),
        *SMALLER_GAP,
    )


SMALLER_GAP = ("; or use a smaller ", Param("gap_mm", flag="--gap"))  # a material field: --gap


# ------------------------------------------------------------------ printing
@dataclass(frozen=True)
class PrintMinimum:
    """Scales at which ``print`` accepts the plan (``min_scale``) and the closed pattern fits the bed."""

    min_scale: float | None
    max_scale: float | None  # None: any (strips are packed part by part)
    limit: str = ""
    exact: bool = (
        True  # False: the closed form of print_bound (see its docstring for how it relates)
    )

    @property
    def possible(self) -> bool:
        return self.min_scale is not None and (
            self.max_scale is None or self.min_scale <= self.max_scale
        )

    def advice(self, printer: str) -> str:
        """The advice in the command line's words (``--scale ≥ ...``)."""
        return cli_text(self.advice_parts(printer))

    def advice_parts(self, printer: str, at: float = 1.0) -> tuple:
        """The advice as message parts (``scale ≥ ...`` to a library caller, ``--scale ≥ ...`` on the
        command line), for the pattern at scale ``at`` (the scales it names are of the pattern at 1)."""
        if self.min_scale is None:
            return (f"no scale works ({self.limit})",)
        least = self.min_scale if at == 1.0 else ceil_sig(self.min_scale * at)
        if not self.possible:
            return (
                "it needs ", Param("scale"), f" ≥ {least:g} but the bed of {printer} takes at most "
                f"{self.max_scale:g}",
            )  # fmt: skip
        top: tuple = ()
        if self.max_scale is not None:
            most = self.max_scale if at == 1.0 else floor_sig(self.max_scale * at)
            top = (f"; the bed of {printer} takes up to ", Param("scale", most, "g"))
        return (
            "print at ",
            Param("scale"),
            f" ≥ {least:g} (or ",
            Param("scale", "auto"),
            ")",
            *top,
        )

    def to_dict(self, at: float = 1.0) -> dict:
        ok = (
            self.possible
            and self.min_scale is not None
            and self.min_scale <= at
            and (self.max_scale is None or at <= self.max_scale)
        )
        return {
            "min_scale": self.min_scale,
            "max_scale": self.max_scale,
            "fits_bed": self.possible,
            "ok_at_scale_1": bool(ok),
            "limit": self.limit,
            "exact": self.exact,
        }


def scaled(pattern: Pattern, k: float) -> Pattern:
    """The pattern ``k`` times its size (nodes and stored closed states)."""
    return replace(
        pattern,
        nodes=pattern.nodes * k,
        contracted={s: v * k for s, v in pattern.contracted.items()},
    )


def _plan_error(pattern: Pattern, style: str, state: int, printer: Printer) -> str:
    """Why the print plan of ``style`` is refused at this size ('' if accepted; the bed is not asked)."""
    from .print import geometry as printgeom

    if not pattern.contracted and not _closes(pattern):
        return "the pattern does not close: nothing to hinge"
    try:
        plan = printgeom.closed_plan(pattern, state, printer)
        _rule(style).check(pattern, plan, printer)
    except FabricationError as exc:
        return str(exc)
    except (
        shapely.errors.GEOSException
    ) as exc:  # seen once in a bisection (ellipse 16x16 rigid, prusa-mk4):
        return f"the plan geometry failed in GEOS ({exc})"  # refused there, never a crash of design or info
    return ""


def _closes(pattern: Pattern) -> bool:
    from .print.geometry import closed_corners

    try:
        closed_corners(pattern, 1)
    except CheckFailed:
        return False
    return True


def bed_scale(
    pattern: Pattern, style: str, state: int, printer: Printer, corners: np.ndarray | None = None
) -> float | None:
    """The largest scale at which closed state ``state`` (``corners`` if given) fits the printer's bed,
    or None when the style prints no tiles or the state has no extent."""
    if (
        print_style(style).tiles is None
    ):  # no tiles printed (strips): the bed does not bound the pattern
        return None
    if corners is None:  # design gives them: the plan geometry is loaded only without
        from .print.geometry import closed_corners

        corners = closed_corners(pattern, state)
    w, h = np.ptp(corners[..., 0]), np.ptp(corners[..., 1])
    bx, by, _ = printer.bed_mm
    return float(min(bx / w, by / h) * (1 - 1e-12)) if w > 0 and h > 0 else None


def _never(pattern: Pattern, style: str, error: str) -> bool:
    """A refusal no scale changes (a non-rigid pattern for pins, a single tile, three hinges at a point)."""
    return (
        "not rigid-deployable" in error
        or "nothing to hinge" in error
        or "coincides with" in error
        or "cannot take opposite faces" in error
    )


def print_minimum(pattern: Pattern, style: str, printer: Printer, state: int = 1) -> PrintMinimum:
    """Smallest scale at which the print plan checks pass (bisection on them to 0.1 %, started from the
    closed-form :func:`print_bound`), and the bed's largest."""
    top = bed_scale(pattern, style, state, printer)
    err = _plan_error(pattern, style, state, printer)
    if err and _never(pattern, style, err):
        return PrintMinimum(None, top, err)
    lo, hi = (None, 1.0) if not err else (1.0, None)
    guess = print_bound(pattern, style, printer, state)
    if (
        guess.min_scale is not None and MIN_GUESS < guess.min_scale < MAX_SCALE
    ):  # bracket around the bound
        g = guess.min_scale
        lower = _rule(style).bound_is_lower  # then bracket upwards from it
        for k in (
            (g, g * (1 - GUESS_BRACKET)) if not lower else (g * (1 - 1e-9), g * (1 + GUESS_BRACKET))
        ):
            if _plan_error(scaled(pattern, k), style, state, printer):
                lo = k if lo is None else max(lo, k)
            else:
                hi = k if hi is None else min(hi, k)
        if lo is not None and hi is not None and lo >= hi:
            lo, hi = (None, 1.0) if not err else (1.0, None)  # not monotone there: the plain search
    k = hi if hi is not None else (lo or 1.0)
    last = (1.0, err)  # the binding limit at the largest scale refused, not at scale 1
    while hi is None:  # bracket: double until accepted
        k *= 2.0
        if k > MAX_SCALE:
            return PrintMinimum(
                None, top, f"refused up to scale {MAX_SCALE:g}; at --scale {last[0]:g}: {last[1]}"
            )
        e = _plan_error(scaled(pattern, k), style, state, printer)
        (lo, hi) = (k, None) if e else (lo, k)
        last = (k, e) if e else last
    k = hi
    while lo is None:  # ... or halve until refused
        k *= 0.5
        e = _plan_error(scaled(pattern, k), style, state, printer)
        lo, hi = (k, hi) if e else (lo, k)
        if k < 1e-6:
            lo = 0.0
    while hi - lo > BISECT_RTOL * hi:
        mid = 0.5 * (lo + hi)
        if _plan_error(scaled(pattern, mid), style, state, printer):
            lo = mid
        else:
            hi = mid
    return PrintMinimum(ceil_sig(hi), None if top is None else floor_sig(top), "plan checks")


def print_refusal(
    pattern: Pattern,
    style: str,
    printer: Printer,
    state: int,
    scale: float,
    memo: dict | None = None,
) -> str:
    """Why ``print`` refuses ``pattern`` at ``scale`` on ``printer`` in ``style``: the plan checks, then the
    bed ('' if both accept it). The gate the refusal advice (``api/advice.py``) checks each option with;
    its ``memo`` shares the plan checks between presets of one :func:`plan_family` (a pinned plan of a
    32x32 pattern is seconds of geometry, the same for every preset that differs only in the bed)."""
    at = scaled(pattern, scale)
    key = ("plan", plan_family(printer, style), state, float(scale))
    if memo is not None and key in memo:
        err = memo[key]
    else:
        err = _plan_error(at, style, state, printer)
        if memo is not None:
            memo[key] = err
    if err:
        return err
    top = bed_scale(at, style, state, printer)
    if top is not None and top < 1.0:
        return f"the closed pattern does not fit the bed of {printer.name}"
    return ""


def plan_family(printer: Printer, style: str) -> tuple:
    """Printers and styles with equal keys share the plan checks (they may differ in the bed)."""
    return (_rule(style), _plan_key(printer, style))


MIN_GUESS = 1e-6
GUESS_BRACKET = 0.03  # the closed-form bound is within a few % of the plan checks' minimum (tests)


def _plan_key(printer: Printer, style: str) -> tuple:
    """The preset fields the plan checks of ``style`` read (not the bed)."""
    return (printer.gap_mm, printer.radial_clearance_mm, printer.nozzle_mm) + _rule(style).fields(
        printer
    )


def _closed(pattern: Pattern, state: int) -> np.ndarray | None:
    from .print.geometry import closed_corners

    try:
        return closed_corners(pattern, state)
    except CheckFailed:
        return None


def print_bound(
    pattern: Pattern,
    style: str,
    printer: Printer,
    state: int = 1,
    corners: np.ndarray | None = None,
    memo: dict | None = None,
) -> PrintMinimum:
    """The smallest print scale in closed form, no plan geometry (``exact`` False).

    Strip styles: the largest of the scale at which every tile survives the gap/2 shrink
    (:func:`fabkiri.pattern.thinness.min_scale`), at which same-face strips keep the radial
    clearance (:func:`fabkiri.pattern.thinness.strip_clearance_scales`, their boxes: a bound, so
    ``print`` accepts it) and at which every strip pad has its area (a vectorised bisection on the pads,
    band ∩ shrunk tile, only for pads short at the other two). Pinned: the pivot spacing only, a lower
    bound (``print`` also checks the slivers beside the clearances). ``memo``: see :func:`_kept`."""
    top_ = pattern.topology
    if top_.n_hinges == 0:
        return PrintMinimum(
            None, None, "the pattern has a single tile and no hinges: there is nothing to hinge"
        )
    c = corners if corners is not None and state == 1 else _closed(pattern, state)
    if c is None:
        return PrintMinimum(None, None, "the pattern does not close: nothing to hinge")
    d = 0.5 * printer.gap_mm
    face, clash = _kept(memo, fab.hinge_faces, top_, state, tuple(pattern.contracted))
    if clash:
        return PrintMinimum(
            None, None, "hinges that coincide in a closed state cannot take opposite faces"
        )
    s_shrink, t_shrink, _ = _kept(memo, fab.TileScales, c)(fab.EDGE_EPS_MM, d, fab.EDGE_EPS_MM)
    return _rule(style).bound(pattern, c, printer, s_shrink, state, face)


def closest_pair(points: np.ndarray) -> float:
    """The smallest distance between two of ``points`` (distinct rows), by a KD-tree: O(n log n) where the
    pairwise matrix was O(n²) memory (too much for large patterns)."""
    from ..kdtree import KDTree

    d, _ = KDTree(points).query(points, k=2)
    return float(d[:, 1].min())


# ------------------------------------------------------------------ summary
PRINT_STYLES = ("tiles-and-strips", "strips", "pinned")


def summary(pattern: Pattern, prints=None) -> dict:
    """Fabricability of a pattern at its stored size (mm): the measures, per material preset and hinge
    kind the smallest cut scale and width, and per printer preset (``prints``: ``(name, styles)`` pairs,
    default every preset and style) the smallest print scale in closed form (:func:`print_bound`) and
    whether the closed pattern then fits the bed. No plan geometry is built: a few ms at 8x8."""
    from ..mechanics.contract import contract  # not .cut: design would import the DXF/SVG writers

    top = pattern.topology
    c1 = pattern.contracted[1] if 1 in pattern.contracted else contract(pattern, 1).corners
    out = {
        "definition": "thinnest width = smallest altitude: min over a tile's edges of the largest distance of "
        "its corners from that edge's line (the tile's minimum width)",
        **fab.measures(c1, top.hinge_tiles, top.hinge_corner),
    }
    cut = {}
    memo: dict = {}  # what presets ask alike of closed state 1 (``_kept``)
    for name in available():
        mat = load_material(name)
        cut[name] = {kind: cut_minimum(c1, mat, kind, memo).to_dict() for kind in HINGE_KINDS}
    out["cut"] = cut
    if prints is None:
        prints = tuple((name, PRINT_STYLES) for name in available_printers())
    pr: dict = {}
    bounds: dict = {}
    for name, styles in prints or ():
        p = load_printer(name)
        rows = pr.setdefault(p.name, {})
        for style in styles:
            # styles with one plan rule, and presets that differ only in the bed, share a bound
            key = (_rule(style), _plan_key(p, style))
            if key not in bounds:
                bounds[key] = print_bound(pattern, style, p, 1, c1, memo)
            m = bounds[key]
            bed = bed_scale(pattern, style, 1, p, c1)
            m = PrintMinimum(m.min_scale, None if bed is None else floor_sig(bed), m.limit, m.exact)
            rows[style] = m.to_dict()
    out["print"] = pr
    return out


def _rule(style: str) -> PlanRule:  # (a style's module names its rule: planrules.py)
    """The plan rule of ``style`` (``PrintStyle.plan``)."""
    rule = print_style(style).plan
    if rule is None:
        raise FabricationError(
            f"the {style} print style has no plan rule: its smallest scale cannot be found"
        )
    return rule
