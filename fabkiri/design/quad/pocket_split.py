"""A lattice corner in a deep pocket: the split for an outline whose own split leaves a pocket's inner
corner in the middle of a lattice side (an L or a boot given N x N tiles).

The own split (rays from the bounding box's centre to its corners) puts one lattice corner on the wall of
an L's pocket and its reflex corner, with a convex one, in the middle of a side; the pattern's harmonic
map onto that split folds tiles, and the rescaled and standard guesses run the side across the pocket.
Here that lattice corner moves to the middle of the pocket's inward turn (the reflex corner of an L, the
floor of a U's gap): the two sides meeting there go into the pocket from either end, and the coarse to
fine start (its 8x8 level from the rescaled guess) follows them in. Which tip lands nearest the corner
decides whether the closed states overlap there (the boot at 16x16: pass or not within a tip spacing), so
the front door tries the middle and, while a design meets the shape but overlaps, half a tip spacing either
side (:data:`SHIFTS`).
"""

from __future__ import annotations

import numpy as np
import shapely

from ..targets.curve import Target
from ..targets.pockets import pockets
from .corner_split import default_folds, with_corners

SAMPLES = 4096  # curve samples the inward turn is summed over
# tip spacings from the turn's middle, tried in turn (``api/design_pocket.py``)
SHIFTS = (0.0, -0.5, 0.5)
ON_POCKET = 1e-3  # of the size: a sample or split point this near the pocket lies on its wall


def inward_turn_middle(target: Target, pocket: shapely.Polygon) -> float:
    """The curve parameter where half of the outline's inward turning along ``pocket``'s wall is done."""
    u = np.linspace(0.0, 1.0, SAMPLES, endpoint=False)
    p = target.point(u)
    a, b = p - np.roll(p, 1, 0), np.roll(p, -1, 0) - p
    turn = np.arctan2(a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0], (a * b).sum(1))  # CCW: inward < 0
    on = shapely.distance(shapely.points(p), pocket) < ON_POCKET * target.size
    inward = np.where(on, np.clip(-turn, 0.0, None), 0.0)
    # from the pocket's first wall sample so that a wall through u = 0 is summed in one run
    start = int(np.argmax(on & ~np.roll(on, 1))) if not on.all() else 0
    order = np.roll(np.arange(SAMPLES), -start)
    run = np.cumsum(inward[order])
    return float(u[order[int(np.searchsorted(run, 0.5 * run[-1]))]])


def pocket_split(target: Target, rows: int, cols: int, shift: float = 0.0) -> Target | None:
    """``target`` with the one own split corner on its deepest pocket's wall moved to the middle of the
    pocket's inward turn (and ``shift`` mean tip spacings along the outline from there), where the pattern's
    harmonic map onto the own split folds tiles; else None."""
    found = pockets(target)
    if not found or not default_folds(target, rows, cols):
        return None
    wall = found[0].polygon
    corners = np.asarray(target.corners, float)
    d = shapely.distance(shapely.points(target.point(corners)), wall)
    on = np.flatnonzero(d < ON_POCKET * target.size)
    if len(on) != 1:
        return None
    c = corners.copy()
    c[on[0]] = inward_turn_middle(target, wall) + shift / (2 * (rows + cols))  # tips on the outline
    c = np.mod(c - c[0], 1.0) + c[0]  # CCW from BL, as Target expects
    if not np.all(np.diff(c) > 0):
        return None  # the turn's middle lies past a neighbouring corner: no split of this kind
    return with_corners(target, c)
