"""The kagome lattice's aspect against the outline's: which R x C suits a target.

The standard R x C kagome (R rows of C triangles, :mod:`fabkiri.pattern.kinds.kagome.lattice`) deploys to a box C tile
edges wide and √3·R high, so its aspect is C / (√3 R): an 8x8 lattice is 0.58 wide for 1 high. The fit
maps the lattice's four sides onto the target's four arcs; a lattice much taller or wider than the target
must squeeze its tiles on two sides and stretch them on the other two, which the tile-quality floor and
the family's stiffness resist (docs/kagome.md: 8x8 circle 6.1 %, 6x11 1.23 %; 6x11 ellipse 2:1 9.6 %,
5x19 0.94 %). So the design takes R x C from the target when none is given, and a lattice whose aspect
misses the target's by more than ``ASPECT_TOL`` is worth one line with a better one.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ...pattern.kinds.kagome.lattice import standard_kagome
from ..targets.curve import Target

DEFAULT_TILES = (
    66  # a 6x11 lattice: the size whose fit docs/kagome.md measured best (circle 1.23 %)
)
ASPECT_TOL = (
    0.15  # a lattice whose aspect is off the target's by more than this fraction gets a suggestion
)
# a lattice a little wider than the target fits better than one a little narrower (measured at 120 mm;
# lattice / target aspect: circle 6x11 (1.06) 1.23 %, 6x10 (0.96) 2.84 %; ellipse 2:1 4x14 (1.01) 1.32 %,
# 4x15 (1.08) 1.55 %, 4x13 (0.94) 2.25 %): the corner tiles shrink, the design rounds inwards
WIDER = 1.04
COUNT_SLACK = 0.25  # a suggestion keeps the tile count within this fraction of the asked one
MAX_TILES = 12 * 21  # fabkiri.limits' largest kagome design


@dataclass(frozen=True)
class AspectFit:
    """How a lattice's aspect (width / height, deployed standard) matches the target's."""

    tiles: tuple[int, int]  # rows, cols
    lattice: float  # the standard lattice's aspect
    target: float  # the target's bounding-box aspect

    @property
    def miss(self) -> float:
        """How far apart the aspects are, as a fraction (0: equal; 1: one twice the other)."""
        return float(np.exp(abs(np.log(self.lattice / self.target))) - 1.0)


def lattice_aspect(rows: int, cols: int) -> float:
    """Width / height of the standard R x C kagome, deployed (ψ = 60°), read from its nodes."""
    w, h = np.ptp(standard_kagome(rows, cols, tile_size=1.0).nodes, axis=0)
    return float(w / h)


def target_aspect(target: Target) -> float:
    lo, hi = target.bbox
    w, h = hi - lo
    return float(w / h)


def aspect_fit(rows: int, cols: int, target: Target) -> AspectFit:
    return AspectFit((rows, cols), lattice_aspect(rows, cols), target_aspect(target))


def suggest(target: Target, n_tiles: int = DEFAULT_TILES) -> AspectFit:
    """The R x C (R, C >= 2, at most ``MAX_TILES`` tiles) with about ``n_tiles`` tiles whose aspect is
    nearest ``WIDER`` times the target's; among equally near ones the tile count nearest ``n_tiles``."""
    fits = ranked(target, n_tiles)
    if fits:
        return fits[0]
    # no lattice of about that count: the nearest at the default count, else the smallest lattice
    if _count(n_tiles) != DEFAULT_TILES:
        return suggest(target, DEFAULT_TILES)
    return aspect_fit(2, 2, target)


def _count(n_tiles: int) -> int:
    """The tile count the rule looks around: ``n_tiles`` clamped to 4 .. ``MAX_TILES``."""
    return min(max(int(n_tiles), 4), MAX_TILES)


def ranked(target: Target, n_tiles: int = DEFAULT_TILES) -> list[AspectFit]:
    """Every R x C of about ``n_tiles`` tiles (within ``COUNT_SLACK``) whose aspect brackets ``WIDER``
    times the target's, in the order :func:`suggest` prefers them (its choice first, then the next ones:
    the lattices to try when the first misses)."""
    aspect = target_aspect(target)
    want = WIDER * aspect
    n = _count(n_tiles)
    lo, hi = max(4, int(np.floor(n * (1 - COUNT_SLACK)))), int(np.ceil(n * (1 + COUNT_SLACK)))
    keys: list[tuple] = []
    for rows in range(2, n // 2 + 1):
        # aspect C / (√3 R): the columns that bracket the wanted one, checked on the lattice itself
        c0 = int(np.floor(want * np.sqrt(3.0) * rows))
        for cols in {max(c0, 2), max(c0 + 1, 2)}:
            if not lo <= rows * cols <= min(hi, MAX_TILES):
                continue
            lattice = lattice_aspect(rows, cols)
            miss = abs(np.log(lattice / want))
            keys.append((round(miss, 3), abs(rows * cols - n), rows, cols, lattice))
    return [AspectFit((r, c), lat, aspect) for *_, r, c, lat in sorted(keys)]


def _off_wanted(fit: AspectFit) -> float:
    return abs(float(np.log(fit.lattice / (WIDER * fit.target))))


def advice(rows: int, cols: int, target: Target) -> str | None:
    """One line when R x C does not suit the target's aspect and a lattice of about as many tiles suits
    it better; None when it suits (within ``ASPECT_TOL``) or nothing suits better."""
    given, better = aspect_fit(rows, cols, target), suggest(target, rows * cols)
    if given.miss <= ASPECT_TOL or _off_wanted(better) >= _off_wanted(given):
        return None
    r, c = better.tiles
    return (
        f"warning: a {rows}x{cols} kagome is {given.lattice:.2f} wide for 1 high but {target.name!r} is "
        f"{given.target:.2f}: try --tiles {r}x{c} ({better.lattice:.2f}; R rows of C triangles are "
        f"C / (1.73 R) wide for 1 high)"
    )
