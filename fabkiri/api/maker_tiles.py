"""How many tiles ``make`` designs with when ``--tiles`` is not given.

The thinnest feature a process can make (a tile's width for the web, a strip's seam, two hinges
apart) is fixed in mm, while a tile's width falls as the tile count grows: more tiles follow the
outline better, fewer stay wide enough to cut or print. :func:`choose_tiles` takes the largest
standard count whose estimated tile width at the target's size stays :data:`COMFORT` times above
that feature, no more than :data:`MAX_AUTO` a side (the design time grows fast with the count),
and says why in one sentence.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from ..design.quad.corner_split import bent_strip
from ..design.quad.fabrication import FabricationLimits, smallest_size
from ..design.targets.curve import Target
from .print_tiles import tile_width_mm

STANDARD_TILES = (16, 12, 8, 6, 4)  # N x N, largest first
# a fabrication-aware 16x16 design costs many times a 12x12 one (issue 32)
MAX_AUTO = 12
# the estimated tile width must be this many times the process's thinnest feature: tiles vary in size
# across a design (thinner where the outline turns), so the mean width needs room above the minimum
COMFORT = 2.0
# after a shape miss, a retry may have thinner tiles than the first choice: the design's fabrication rows
# still hold every tile to the feature; the comfort only guessed which count is likely to fit
RETRY_COMFORT = 1.5
_strips: dict[tuple, object] = {}  # bent_strip by outline and count (_bent_strip)


@dataclass(frozen=True)
class TilesChoice:
    """The tiles ``make`` designs with and why: the estimated tile width, the feature it is measured against."""

    tiles: tuple[int, int]
    reason: str
    tile_width_mm: float  # estimated mean tile width at the chosen count
    feature_mm: float  # the process's thinnest feature (mm)
    given: bool = False  # the user named the tiles
    # the target's split parameters BL, BR, TR, TL when make re-split it (None: the target's own)
    corners: tuple[float, float, float, float] | None = None
    asked: tuple[int, int] | None = None  # the N x N make chose before a re-split (None: ``tiles``)

    @property
    def count(self) -> tuple[int, int]:
        """The N x N make chose (or the user named), before any re-split into a strip."""
        return self.asked or self.tiles


def min_feature_mm(limits: FabricationLimits) -> float:
    """The thinnest feature the process needs of a tile (mm): its width (with the shrink), the seam a
    printed strip runs along, or the distance between two of its hinges."""
    return float(max(limits.required_width_mm(), limits.hinge_edge_mm, limits.hinge_spacing_mm))


def resplit(target: Target, choice: TilesChoice) -> TilesChoice:
    """``choice`` with the lattice's corners and rows x columns of ``corner_split.bent_strip`` (an L, a
    crescent: an outline whose own split folds the start). Not for tiles the user named (``--tiles``):
    those keep the target's corners (a JSON target's ``"corners"`` sets them)."""
    rows, cols = choice.tiles
    strip = _bent_strip(target, rows, cols)
    if strip is None:
        return choice
    split, tiles, d, d0 = strip
    pts = "; ".join(f"({x:.3g}, {y:.3g})" for x, y in split.corner_points())
    why = (
        f"{choice.reason}; the lattice's corners at {pts} mm and {tiles[0]}x{tiles[1]} tiles: its start "
        f"bends round the outline's pocket (distortion {d:.2f}, against {d0:.2f} on the "
        f"outline's own split at {rows}x{cols}, where the start folds tiles)"
    )
    c = tuple(float(v) for v in split.corners)
    return replace(
        choice, tiles=tiles, reason=why, corners=(c[0], c[1], c[2], c[3]), asked=(rows, cols)
    )


def _bent_strip(target: Target, rows: int, cols: int):
    """``corner_split.bent_strip``, memoised by outline (its points at its size) and count: make asks
    each setting of its options for its count at one size, mostly the same few counts (the hand at
    120 mm on prusa-mk4: 26 splits of 4 counts, docs/maker-kit.md)."""
    key = (target.name, np.asarray(target.dense, float).tobytes(), rows, cols)
    if key not in _strips:
        _strips[key] = bent_strip(target, rows, cols)
    return _strips[key]


def choose_tiles(
    target: Target, limits: FabricationLimits, process: str, least_mm: float = 0.0
) -> TilesChoice:
    """The largest N x N of :data:`STANDARD_TILES` (at most :data:`MAX_AUTO`) whose estimated tile width
    is at least :data:`COMFORT` times the process's thinnest feature and at least ``least_mm`` (a print
    style's own minimum tile, :func:`.print_tiles.least_tile_mm`); when none is, the fewest (the
    widest tiles), the design's own feasibility check (``smallest_size``) saying whether even they
    could fit (if not, the design refuses, naming the smallest size that could work), and make's
    up-front check whether they are as wide as ``least_mm``."""
    feature = min_feature_mm(limits)
    counts = [n for n in STANDARD_TILES if n <= MAX_AUTO]
    size = f"{target.size:.4g} mm"
    floor = (
        f"{COMFORT:g}x the {feature:.3g} mm {process} needs"
        if COMFORT * feature >= least_mm
        else f"the {least_mm:.3g} mm tile {process} needs (print's own minimum)"
    )
    for n in counts:
        w = tile_width_mm(target, n * n)
        if w >= COMFORT * feature and w >= least_mm:
            bigger = next((m for m in reversed(counts) if m > n), None)
            why = (
                f"the largest of {', '.join(f'{m}x{m}' for m in counts)} whose tiles (about {w:.3g} mm wide at "
                f"{size}) stay at least {floor}"
                + (
                    f" ({bigger}x{bigger} would give {tile_width_mm(target, bigger * bigger):.3g} mm)"
                    if bigger
                    else f"; capped at {MAX_AUTO}x{MAX_AUTO} for design time"
                )
            )
            return resplit(target, TilesChoice((n, n), why, w, feature))
    n = counts[-1]  # the widest tiles there are
    w = tile_width_mm(target, n * n)
    least = smallest_size(target.size, abs(target.area), n * n, limits)  # the design's own check
    why = (
        f"no count keeps tiles at least {floor} at {size}; "
        f"{n}x{n} keeps them widest (about {w:.3g} mm)"
        if least is None
        else f"even {n}x{n} tiles cannot be {feature:.3g} mm wide inside {size} (the smallest size "
        f"that could work is --size {least:.4g})"
    )
    return resplit(target, TilesChoice((n, n), why, w, feature))


def denser_tiles(
    target: Target, limits: FabricationLimits, first: TilesChoice, least_mm: float = 0.0
) -> TilesChoice | None:
    """After a far miss at ``first`` (tiles make chose): the next count of :data:`STANDARD_TILES` up (at most
    :data:`MAX_AUTO`) whose tiles stay :data:`RETRY_COMFORT` times the process's thinnest feature and at
    least ``least_mm``, re-split as :func:`choose_tiles` would; None when there is none. A pocket or an arm
    the lattice did not follow needs more tiles across it, not a neighbouring count (the T at 100 mm for
    card-0.3: the 4x4 strip missed 3.5x the tolerance, 6x6 met)."""
    feature = min_feature_mm(limits)
    n = first.count[0] * first.count[1]
    more = [k for k in STANDARD_TILES if n < k * k and k <= MAX_AUTO]
    if not more:
        return None
    m = min(more)
    w = tile_width_mm(target, m * m)
    if w < RETRY_COMFORT * feature or w < least_mm:
        return None  # more tiles are only narrower
    why = (
        f"more tiles across the outline's arms: tiles about {w:.3g} mm wide, at least "
        f"{RETRY_COMFORT:g}x the {feature:.3g} mm {limits.source} needs"
    )
    return resplit(target, TilesChoice((m, m), why, w, feature))


def fewer_tiles(target: Target, limits: FabricationLimits, first: TilesChoice) -> list[TilesChoice]:
    """After a near miss at ``first`` (tiles make chose) with no larger count wide enough to retry: the next
    count of :data:`STANDARD_TILES` down (at least 4x4), re-split as :func:`choose_tiles` would; wider tiles
    leave the fabrication rows room (the boot at 100 mm on prusa-mk4: 6x6 missed 2.34 %, 4x4 met). Empty
    where ``first`` is the fewest."""
    n = first.count[0] * first.count[1]
    fewer = [k for k in STANDARD_TILES if k * k < n]
    if not fewer:
        return []
    m = max(fewer)
    w = tile_width_mm(target, m * m)
    why = f"fewer, wider tiles (about {w:.3g} mm): room for the {limits.source} limits"
    return [resplit(target, TilesChoice((m, m), why, w, min_feature_mm(limits)))]


def given_tiles(tiles: tuple[int, int], target: Target, limits: FabricationLimits) -> TilesChoice:
    """The tiles the user named, with the same figures for the summary."""
    w = tile_width_mm(target, tiles[0] * tiles[1])
    return TilesChoice(tiles, "as given (--tiles)", w, min_feature_mm(limits), given=True)


def retry_tiles(
    target: Target, limits: FabricationLimits, first: TilesChoice, least_mm: float = 0.0
) -> list[TilesChoice]:
    """The tile counts worth a second design when ``first`` missed the shape, likeliest first: the
    outline's aspect (rows over columns as its height over its width) at about ``first``'s count when
    the outline is far from square, then one and two more tiles a side; each keeps its estimated
    tile width :data:`RETRY_COMFORT` times the process's thinnest feature and at least ``least_mm`` (a
    print style's own minimum tile: narrower, make refuses the count up front), and none repeats
    ``first``."""
    feature = min_feature_mm(limits)
    (lo, hi) = target.bbox
    aspect = float((hi[1] - lo[1]) / (hi[0] - lo[0]))  # height over width: rows over columns
    rows, cols = first.tiles
    shapes: list[tuple[int, int]] = []
    if not 0.8 <= aspect <= 1.25 and first.corners is None:  # a re-split strip has its own shape
        r = max(2, round(np.sqrt(rows * cols * aspect)))  # at least first's count: fewer fit less
        shapes.append((r, max(2, -(-rows * cols // r))))
    shapes += [(rows + k, cols + k) for k in (1, 2)]
    out: list[TilesChoice] = []
    for shape in dict.fromkeys(shapes):  # in order, once each
        w = tile_width_mm(target, shape[0] * shape[1])
        if shape == first.tiles or w < RETRY_COMFORT * feature or w < least_mm:
            continue
        how = "the outline's aspect" if shape[0] != shape[1] and rows == cols else "more tiles"
        why = (
            f"{how}: tiles about {w:.3g} mm wide, at least {RETRY_COMFORT:g}x the {feature:.3g} mm "
            f"{limits.source} needs"
        )
        out.append(TilesChoice(shape, why, w, feature, corners=first.corners))
    return out
