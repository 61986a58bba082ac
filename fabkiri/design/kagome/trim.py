"""A kagome lattice cut to the outline: the tiles of an R x C block that lie inside the target.

The fit maps the standard lattice's tips onto the target. A rectangular block must bend its four corners
round a circle or into a heart's point, and the corner tiles fold until their hinge gaps and their shape
reach the floors (docs/kagome.md, "What limits the fit"); the larger the block, the worse (circle 6x11
1.23 %, 9x15 2.83 %, 10x19 4.37 %). Cut to the outline, the standard already has the target's shape, so
the fit only has to smooth the tips' zigzag: the design keeps every tile of the block whose centre, on
the standard deployed lattice, lies inside the target scaled into the block (uniformly, centred), and of
those the largest piece joined by hinges.
"""

from __future__ import annotations

import numpy as np
import shapely
from scipy import sparse
from scipy.sparse.csgraph import connected_components

from ...errors import InputError
from ...pattern.kinds.kagome.lattice import OPEN_DEG, kagome_corners, kagome_topology
from ..targets.curve import Target
from . import aspect as KA

SAMPLES = 2000  # target points of the polygon the tile centres are tested against


def block_for(target: Target, n_tiles: int) -> tuple[int, int]:
    """The R x C block whose cut keeps about ``n_tiles``: the aspect rule's lattice
    (:func:`kagome_aspect.suggest`) for ``n_tiles`` over the share of its bounding box the target fills."""
    return KA.suggest(target, _block_count(target, n_tiles)).tiles


def blocks_for(target: Target, n_tiles: int) -> list[tuple[int, int]]:
    """The blocks of :func:`block_for`'s count in the aspect rule's order (:func:`kagome_aspect.ranked`):
    its choice first, then the lattices next to it."""
    return [fit.tiles for fit in KA.ranked(target, _block_count(target, n_tiles))]


def _block_count(target: Target, n_tiles: int) -> int:
    lo, hi = target.bbox
    fill = abs(target.area) / float(np.prod(hi - lo))
    return int(round(n_tiles / max(fill, 0.05)))


def kept_tiles(rows: int, cols: int, target: Target) -> np.ndarray:
    """Indices (``r * cols + c``) of the R x C block's tiles whose deployed standard centre lies inside
    ``target`` scaled into the block's bounding box (uniformly, centred), the largest piece of them;
    :class:`InputError` when fewer than two tiles are kept."""
    corners = kagome_corners(rows, cols, np.radians(OPEN_DEG))
    centre = corners.mean(1)
    pts = corners.reshape(-1, 2)
    lo, hi = pts.min(0), pts.max(0)
    tlo, thi = target.bbox
    s = float(np.min((hi - lo) / (thi - tlo)))
    poly = shapely.Polygon((target.sample(SAMPLES) - 0.5 * (tlo + thi)) * s + 0.5 * (lo + hi))
    inside = np.flatnonzero(shapely.contains_xy(poly, centre[:, 0], centre[:, 1]))
    keep = _largest_piece(rows, cols, inside)
    if len(keep) < 2:
        raise InputError(
            f"a {rows}x{cols} kagome cut to {target.name!r} keeps {len(keep)} tile(s): use more tiles"
        )
    return keep


def _largest_piece(rows: int, cols: int, keep: np.ndarray) -> np.ndarray:
    """The tiles of ``keep`` in its largest piece joined by hinges (tiles sharing a node)."""
    tiles, _ = kagome_topology(rows, cols)
    sub = tiles[keep]
    t = np.repeat(np.arange(len(keep)), 3)
    inc = sparse.csr_matrix(
        (np.ones(sub.size), (t, sub.ravel())), shape=(len(keep), tiles.max() + 1)
    )
    _, label = connected_components(inc @ inc.T, directed=False)
    return keep[label == np.bincount(label).argmax()] if len(keep) else keep
