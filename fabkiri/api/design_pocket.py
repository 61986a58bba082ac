"""The first attempt for an outline with a deep pocket that the own split cannot take (an L or a boot
given N x N tiles), tried when every other guess missed: the lattice split with a corner in the pocket
(``design/quad/pocket_split.py``), started coarse to fine; the non-rigid request answered by the rigid family
from that start."""

from __future__ import annotations

from dataclasses import replace

from ..design.quad.pocket_split import SHIFTS, pocket_split
from ..design.quad.solve import VIA_RIGID_INIT, DesignRequest

POCKET_INIT = "pocket"  # the attempts' name among the guesses (report ``attempts``)
POCKET_TRIES = len(SHIFTS)


def resplit_applies(req: DesignRequest) -> bool:
    """Whether a last attempt on a re-split outline (a pocket's here, a bent strip's in ``design_strip.py``)
    may answer ``req``: a target, and no symmetry, closed-state targets, fabrication rows, parallelogram
    holes or other solver than auto (each of those is designed on the split it asked for)."""
    return not (
        req.target is None
        or req.symmetry
        or req.contracted
        or req.fabrication is not None
        or req.holes != "rhombus"
        or req.solver != "auto"
    )


def pocket_request(req: DesignRequest, attempts: list[dict] | None = None) -> DesignRequest | None:
    """The next pocket attempt's request for ``req`` (a front-door request without ``--init`` or corners)
    after the front door's ``attempts`` so far (one per shift of ``SHIFTS``, the next only after one that met
    the shape but failed a check), or None where it does not apply: a symmetry, closed-state targets,
    fabrication rows, parallelogram holes, another solver than auto, or no pocket split (``pocket_split``)."""
    if not resplit_applies(req) or req.target is None:
        return None
    attempts = attempts or []
    k = sum(a["init"] == POCKET_INIT for a in attempts)
    if k and attempts[-1].get("shape") != "met":
        return None  # the shifts are for overlaps at the corner of a fit that met, not for a miss
    split = pocket_split(req.target, req.rows, req.cols, SHIFTS[k])
    if split is None:
        return None
    if req.rigid:
        return replace(req, target=split, init="coarse")
    return replace(req, target=split, init=VIA_RIGID_INIT, via_rigid_init="coarse")
