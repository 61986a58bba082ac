"""``--min-opening`` for kagome designs: the floor row of :mod:`.opening_rows` as a soft one-sided family
of the kagome fit (``weight · min(g - margin, 0)``, as :func:`fabkiri.design.kagome.fabrication.families` makes the
fabrication rows), and the acceptance test of a candidate (its hole fraction at least the floor)."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from ...pattern.model import Pattern
from ...pattern.opening import opening
from ..core.stencils import Family
from ..quad.fabrication import ccw_polygons
from ..quad.opening_rows import FAMILY, opening_row
from . import fabrication as KF


def families(pattern: Pattern, floor: float | None, weight: float = KF.WEIGHT) -> list[Family]:
    """The floor row over ``pattern``'s nodes (the standard kagome: it orients the hexagonal holes)."""
    holes_of = pattern.topology.hole_nodes
    if not floor or not len(holes_of):
        return []
    tiles = pattern.tiles
    holes = ccw_polygons(holes_of, pattern.nodes)
    margin = KF.MARGIN

    def fn(x):
        g, nodes, grad = opening_row(x, tiles, holes, floor)
        act = g < margin
        return weight * np.where(act, g - margin, 0.0), (nodes, weight * grad * act[:, None, None])

    def res(x):
        return weight * np.minimum(opening_row(x, tiles, holes, floor)[0] - margin, 0.0)

    return [Family(FAMILY, "ineq", fn, 2, meta={"land": KF.LAND}, nv=len(pattern.nodes), res=res)]


def accepting(accept: Callable[[Pattern], bool], floor: float | None) -> Callable[[Pattern], bool]:
    """``accept`` and, with a floor, a hole fraction of at least ``floor``."""
    if not floor:
        return accept
    return lambda p: accept(p) and opening(p, closed={}).hole_fraction >= floor
