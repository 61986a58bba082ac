"""The coarse chain of a large rigid-family design whose target has no mirror (issue #37).

A coarse-to-fine start halves the lattice down to a bottom level that starts from rescaled
(``problem.COARSE_MIN``): a 48x48 design from a 24x24 level from a 12x12 one. For a target with no mirror about
either axis through its bounding box's centre (``mirrorless``: the bean of issue #37's table; the heart, star and
drop have one such axis, the ellipse, peanut and circle two) that chain ended the 48x48, 64x64 and 96x96 designs
above the 32x32 design, whose start is rescaled (``BIG_RIGID_INITS``' second guess): the rigid bean 0.238, 0.234
and 0.173 % of the size against 0.148 %. A chain whose bottom is a ``CHAIN_BOTTOM`` level from rescaled with the
outline rows (48 and 64 from 32, 96 from 48 from 32: a lattice ratio of 1.5 where needed, which the rigid family's
resampling takes), its designs finished (``api/design_minimax._rescaled_bottom``), came to 0.063, 0.0402 and
0.0401 % (docs/design-solver.md, "Session 51 (pb51)" and "Session 52 (bean52)"). Only on
the rigid-family refinement (a rigid request, and a free one answered by the rigid family), from ``CHAIN_FROM``
tiles a side, unmirrored: a mirror-symmetric target's chain, issue #36's circles included, is left as it was.
The bottom is kept only where it converged and fits the target closer than the halving chain's own level
(``keep_bottom``, ``DesignProblem._guarded_level``); else the design takes the halving chain (a heart rotated by 20 degrees,
whose bottom converged further than its halving level; docs/design-solver.md, "The guard (bean52, second helper)").
"""

from __future__ import annotations

from ..core.request import MIRROR_TOL, DesignRequest, reduced_applies
from ..targets.lookup import Target

# from this many tiles a side (the smallest lattice whose halved level is under the bottom)
CHAIN_FROM = 48
# the chain's bottom level, designed from rescaled: the 32x32 design's own start
CHAIN_BOTTOM = 32


def mirrorless(target: Target) -> bool:
    """Whether ``target``, centred on its bounding box, is further than ``MIRROR_TOL`` from a mirror about either
    axis (``Target.mirror_error``, the test ``--symmetry`` asks)."""
    centred = target.centred()
    return all(centred.mirror_error(axis) > MIRROR_TOL for axis in ("x", "y"))


def rescaled_bottom(req: DesignRequest) -> bool:
    """Whether ``req``'s coarse chain bottoms at a ``CHAIN_BOTTOM`` level from rescaled (the module's rule); a
    bent strip's chain bottoms at its own fold-free start (``DesignRequest.coarse_bottom``)."""
    return (
        reduced_applies(req)
        and req.solver != "full"
        and not req.symmetry
        and min(req.rows, req.cols) >= CHAIN_FROM
        and req.target is not None
        and req.coarse_bottom == "rescaled"
        and mirrorless(req.target)
    )


def level_of(req: DesignRequest, rows: int, cols: int, init: str) -> tuple[int, int, str, bool]:
    """The coarse level (rows, cols, init, outline rows) of ``req``, whose halved level is ``rows`` x ``cols`` from
    ``init``, tips only: under ``rescaled_bottom``, no smaller than ``CHAIN_BOTTOM`` a side, and where it is that
    size from rescaled with the outline rows (the 32x32 design's own fit: tips only from rescaled, the bean's level
    missed by 3.1 % and cost more than the whole design it started)."""
    if not rescaled_bottom(req):
        return rows, cols, init, False
    rows, cols = max(rows, CHAIN_BOTTOM), max(cols, CHAIN_BOTTOM)
    bottom = min(rows, cols) <= CHAIN_BOTTOM
    return rows, cols, "rescaled" if bottom else init, bottom


def keep_bottom(h_bottom: float, halving_converged: bool, h_halving: float) -> bool:
    """Whether a converged rescaled bottom level (Hausdorff ``h_bottom``) is kept over the halving chain's level
    (``h_halving``, ``halving_converged``): where it fits the target closer or that level did not converge. Else
    the design takes the halving chain: the rescaled bottom was tuned on the bean alone, and a heart rotated by 20 degrees
    lost its 48x48 design from it (docs/design-solver.md, "Session 52 (bean52)")."""
    return not halving_converged or h_bottom < h_halving
