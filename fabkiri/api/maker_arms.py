"""A lower bound on the sizes ``make`` designs at: an outline's arms must hold a strip's tiles across.

An outline with arms (a U, a C, a T, an L) is designed, when the lattice misses, as a strip bent along it,
at least :data:`~fabkiri.design.quad.corner_split.MIN_ACROSS` tiles across an arm. When the arm is too
narrow for that many tiles of the process's least width (a print style's own minimum tile,
:func:`.print_tiles.least_tile_mm`, or the cut's thinnest feature), no design at that size was found to
meet (docs/maker-kit.md, sessions 55 and 56), whatever the count. ``make`` therefore designs no count at
such a size: not the size asked (:mod:`.maker_early` goes on to the larger sizes and the options), not a
larger size of its ladder, not an option (:mod:`.maker_design`). The bound is necessary, not sufficient
(strips a little wider than it still missed), so the size where it is first met is never named: only a
size designed there and met is. The arm width is taken from the outline alone (:func:`arm_width_mm`:
the widest disc whose sweep still reaches all but :data:`ARM_SHARE` of the area).
"""

from __future__ import annotations

from dataclasses import dataclass

import shapely
from scipy.optimize import bisect

from ..design.quad.corner_split import MIN_ACROSS
from ..design.quad.fabrication import FabricationLimits
from ..design.targets.curve import Target
from ..errors import FabkiriError
from ..pattern.kinds.tessellation import DEFAULT_KIND
from .design_turn import request_target
from .maker_tiles import min_feature_mm
from .print_tiles import check_micrometre, check_room, check_tiles, least_tile_mm

# the share of the outline's area lying in parts narrower than its arm width: a fifth is an arm (the
# star's points and the boot's toe are smaller shares and do not count)
ARM_SHARE = 0.2
ARM_XTOL = 0.05  # the arm width's precision, in % of the outline's size (bisection)
_memo: dict[tuple, float] = {}


def arm_width_mm(target: Target) -> float:
    """The outline's arm width (mm): the diameter of the widest disc whose sweep inside the outline (its
    morphological opening) leaves out at most :data:`ARM_SHARE` of the area. Memoised by outline shape,
    as a share of its size: make's larger sizes of one outline scale it, not measure it again."""
    size = float(target.size)
    key = (target.name, len(target.dense), round(float(target.area) / size**2, 9))
    if key not in _memo:
        _memo[key] = _arm_width(target) / size
    return _memo[key] * size


def _arm_width(target: Target) -> float:
    poly = shapely.make_valid(shapely.Polygon(target.dense))
    area = poly.area
    size = float(target.size)

    def lost(d: float) -> float:
        kept = poly.buffer(-d / 2).buffer(d / 2).area
        return (area - kept) / area - ARM_SHARE

    if lost(size) <= 0:  # the whole outline is one part: no arm narrower than it
        return size
    return float(bisect(lost, 0.0, size, xtol=ARM_XTOL * size / 100))


@dataclass(frozen=True)
class NarrowArms:
    """An outline whose arms, ``arm_mm`` wide at ``size_mm``, hold fewer than ``across`` tiles
    ``need_mm`` wide (the least a tile of ``fabrication`` can be)."""

    target: str
    size_mm: float
    arm_mm: float
    need_mm: float
    across: int
    fabrication: str

    def reason(self) -> str:
        return (
            f"at {self.size_mm:g} mm the {self.target}'s arms are about {self.arm_mm:.3g} mm wide "
            f"({ARM_SHARE:.0%} of its area lies in narrower parts): {self.across} tiles across (the "
            f"fewest a strip along an arm has) would be {self.arm_mm / self.across:.3g} mm, narrower "
            f"than the {self.need_mm:.3g} mm tile {self.fabrication} needs"
        )

    def warning(self, tiles: tuple[int, int]) -> str:
        """The line of a design at ``tiles`` the user gave (``design --printer/--material``, ``make
        --tiles``): designed as asked, with the figure make skips its own counts by."""
        r, c = tiles
        return (
            f"warning: {self.reason()}; make designs none of its own counts at such a size (none met "
            f"in its surveys, docs/maker-kit.md), so the {r}x{c} tiles given may miss the shape or "
            "not print; they are designed as given"
        )


def narrow_arms(
    target: Target, limits: FabricationLimits, least_mm: float, fabrication: str
) -> NarrowArms | None:
    """``target`` (at its size) when its arms cannot hold :data:`MIN_ACROSS` tiles of the process's least
    width (``least_mm``, a print style's own minimum tile, or the thinnest feature, the larger); None
    when they can."""
    need = max(least_mm, min_feature_mm(limits))
    arm = arm_width_mm(target)
    if arm / MIN_ACROSS >= need:
        return None
    return NarrowArms(target.name, float(target.size), arm, need, MIN_ACROSS, fabrication)


def request_arms(request) -> NarrowArms | None:
    """``design``'s request (a :class:`~.design.PatternRequest` of a quad lattice for a material or a
    printer) when its outline's arms cannot hold a strip's tiles of that process (:func:`narrow_arms`,
    the rule make skips a size by); None when they can, or the request has no such outline or process,
    or is bad input or refused up front (the design refuses it with its own message)."""
    if request.kind != DEFAULT_KIND or request.tiles is None or request.corners is not None:
        return None
    if request.target is None or not (request.printer or request.material):
        return None
    rows, cols = request.tiles
    try:  # the design's own up-front refusals come first: no warning before them (print_tiles)
        target = request_target(request)
        limits, intent = request.fabrication_limits(target)
        if target is None or limits is None:
            return None
        check_micrometre(rows, cols, target)
        check_room(rows, cols, limits, target)
        check_tiles(rows, cols, target, request.printer, intent.get("style"))
        least = least_tile_mm(request.printer, str(intent["style"])) if request.printer else 0.0
    except FabkiriError:
        return None
    return narrow_arms(target, limits, least, limits.source)
