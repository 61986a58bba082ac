"""The narrowest tile a print style takes, and the up-front refusal of tiles narrower than it (issue 32).

In the strip styles a tile carries a strip at each of its hinge corners, and two strips on one face keep
the radial clearance; with pins, two pivots keep two ears apart. Below some tile width no design can
meet that, and a print-aware design at such a count paid a whole continuation before it said so
(16x16 heart at 200 mm on prusa-mk4: "the limits cost the shape").

:func:`least_tile_mm` is print's own minimum tile for a preset and style: its closed-form bound
(:func:`fabkiri.fabricate.fabricability.print_bound`, the one ``--scale auto`` starts from) on the
standard pattern with unit tiles, whose smallest scale is then its tile edge in mm (8.70 mm for
prusa-mk4 tiles-and-strips, 7.40 mm pinned). It is the same on every standard count and in either closed
state (tests), so it is a property of the preset and the style. :func:`narrow_tiles` compares it with the
width ``make`` estimates for the tiles of an outline (:func:`tile_width_mm`: square tiles
covering half of it, as the standard pattern's do deployed at 45°): ``make`` and ``design --printer``
refuse such a request before any design (exit 1, as a design that misses), naming the counts and size
at which the tiles are that wide by the estimate, said to be unchecked (``make`` names a size only once it
designed it there, :mod:`.maker_early`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from ..design.quad.fabrication import FabricationLimits, smallest_size
from ..design.targets.lookup import Target
from ..errors import CheckFailed, InputError, Param
from ..fabricate import fabricability as fb
from ..fabricate.print.printers import load_printer
from ..limits import MIN_LENGTH_MM
from ..pattern.kinds.quad.lattice import standard_pattern
from ..pattern.thinness import pal_bound

# a deployed rotating-squares pattern's tiles cover about this share of its outline (the rest is holes)
TILE_COVER = 0.5
# the standard pattern the bound is taken on: 4x4 has corner, edge and inner tiles (every count from
# 2x2 to 64x64 gives the same bound, tests)
STANDARD = (4, 4)
SIZE_STEP_MM = 10.0  # a size the refusal names is rounded up to this (as make's larger sizes)
MAX_SIDE = 128  # the largest count a side the refusal names (fabkiri.limits caps designs there too)
_memo: dict[tuple, float] = {}


def least_tile_mm(printer: str, style: str) -> float:
    """print's own minimum tile edge (mm) for ``printer`` in ``style``: :func:`~fb.print_bound` on the
    standard pattern with unit tiles, the smaller of its two closed states (the printed state is chosen
    after the design, to fit the bed); 0 when the bound says no scale works (the refusal is print's)."""
    pr = load_printer(printer)
    key = fb.plan_family(pr, style)
    if key not in _memo:
        unit = standard_pattern(*STANDARD, tile_size=1.0)
        scales = [fb.print_bound(unit, style, pr, state).min_scale for state in (1, 2)]
        _memo[key] = min((s for s in scales if s is not None), default=0.0)
    return _memo[key]


@dataclass(frozen=True)
class NarrowTiles:
    """Tiles too narrow for a print style: the count asked, their estimated width and the width the style
    needs (mm), at ``size_mm``; ``widest`` the largest N (N x N) whose tiles are that wide at this size (0:
    none), ``size_for`` the size (mm) from which the asked count's are."""

    tiles: tuple[int, int]
    width_mm: float
    need_mm: float
    size_mm: float
    target: str
    fabrication: str  # "prusa-mk4 tiles-and-strips"
    widest: int
    size_for: float

    def reason(self) -> str:
        r, c = self.tiles
        count = f"at {self.size_mm:g} mm no count of 2x2 or more"
        if self.widest >= 2:
            count = f"at {self.size_mm:g} mm up to {self.widest}x{self.widest} tiles"
        return (
            f"{r}x{c} tiles of a {self.size_mm:g} mm {self.target} would be about {self.width_mm:.3g} mm "
            f"wide (square tiles covering half its area), narrower than the {self.need_mm:.3g} mm tile "
            f"{self.fabrication} needs (print's own minimum on the standard pattern: a tile carries a strip "
            f"or a pin at each hinge corner, kept apart); {count} are that wide, and {r}x{c} would be "
            f"from about {self.size_for:g} mm (the same estimate; no size was checked); not designed"
        )


def tile_width_mm(target: Target, n_tiles: int) -> float:
    """Mean width of ``n_tiles`` square tiles covering :data:`TILE_COVER` of the target's area (mm): the width
    ``make`` chooses its tile count by and ``narrow_tiles`` refuses below a style's least."""
    return float(math.sqrt(TILE_COVER * abs(target.area) / n_tiles))


def narrow_tiles(
    target: Target, tiles: tuple[int, int], printer: str, style: str, fabrication: str = ""
) -> NarrowTiles | None:
    """The refusal of ``tiles`` for ``target`` printed on ``printer`` in ``style`` when their estimated
    width is below :func:`least_tile_mm`; None when they are wide enough."""
    need = least_tile_mm(printer, style)
    n = tiles[0] * tiles[1]
    width = tile_width_mm(target, n)
    if need <= 0 or width >= need:
        return None
    return NarrowTiles(
        tiles=tiles,
        width_mm=width,
        need_mm=need,
        size_mm=float(target.size),
        target=target.name,
        fabrication=fabrication or f"{printer} {style}",
        widest=widest_count(target, need),
        size_for=size_for(target.size, width, need),
    )


def widest_count(target: Target, need_mm: float) -> int:
    """The largest N whose N x N tiles are estimated at least ``need_mm`` wide (0: not even 2x2)."""
    n = int(math.sqrt(abs(target.area) * 0.5) / need_mm) if need_mm > 0 else MAX_SIDE
    while n >= 2 and tile_width_mm(target, n * n) < need_mm:  # round-off at the boundary
        n -= 1
    return min(n, MAX_SIDE) if n >= 2 else 0


def size_for(size: float, width_mm: float, need_mm: float) -> float:
    """The size, rounded up to :data:`SIZE_STEP_MM`, at which tiles ``width_mm`` wide at ``size`` are
    ``need_mm`` wide (the estimate is linear in the size)."""
    return float(math.ceil(size * need_mm / width_mm / SIZE_STEP_MM) * SIZE_STEP_MM)


def check_tiles(
    rows: int, cols: int, target: Target, printer: str | None, style: str | None
) -> None:
    """``design --printer``'s up-front refusal (:class:`CheckFailed`, exit 1, as a design that misses)
    of tiles too narrow for the print style; nothing for a cut or tiles wide enough."""
    if printer and style:
        narrow = narrow_tiles(target, (rows, cols), printer, style)
        if narrow is not None:
            raise CheckFailed(narrow.reason())


def check_micrometre(rows: int, cols: int, target: Target | None) -> None:
    """InputError when ``rows`` x ``cols`` tiles of ``target`` (:func:`tile_width_mm`) would be narrower than
    the micrometre every reader asks of a tile edge (:data:`fabkiri.limits.MIN_LENGTH_MM`)."""
    if target is not None and tile_width_mm(target, rows * cols) < MIN_LENGTH_MM:
        raise InputError(
            f"{rows}x{cols} tiles of a {target.size:.3g} mm target would be under {MIN_LENGTH_MM:g} mm: "
            "give a larger ",
            Param("size"),
            " or fewer tiles",
        )


def check_room(rows: int, cols: int, fab_limits: FabricationLimits, target: Target) -> None:
    """InputError when ``rows`` x ``cols`` tiles wide enough for ``fab_limits`` cannot fit inside the target."""
    least = smallest_size(target.size, abs(target.area), rows * cols, fab_limits)
    if least is not None:
        raise InputError(
            f"{rows}x{cols} tiles each at least {fab_limits.required_width_mm():.3g} mm wide ({fab_limits.source}) "
            f"cannot fit a {target.size:.4g} mm {target.name}: they cover at least "
            f"{pal_bound(rows * cols, fab_limits.required_width_mm()):.4g} mm² (Pál) but the target has "
            f"{abs(target.area):.4g} mm²; the smallest size that could work is ",
            Param("size", least, ".4g"),
        )
