"""The last attempts for an outline the N x N lattice cannot follow, tried when every guess and the pocket
attempts (``design_pocket.py``) missed: the lattice as a strip bent along the outline (a U, a horseshoe;
``design/quad/strip_split.py``), about as many tiles as asked in other rows and columns, started from the
fold-free map of the strip onto the outline; the non-rigid request answered by the rigid family from it. On the
front door's big lattices (from 32x32 asked, where its own rigid guesses start coarse to fine) a split whose
fold-free start misses is tried again coarse to fine, the chain's bottom level from that start: from it the long
fine strip converged with the outline's corners cut off (a local minimum), where its halved level met."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import replace
from functools import lru_cache
from typing import Any

import numpy as np

from ..design.quad.corner_split import MIN_ACROSS
from ..design.quad.inverse_map import with_corners
from ..design.quad.solve import VIA_RIGID_INIT, DesignRequest
from ..design.quad.strip_split import strip_splits
from ..design.targets.curve import Target
from .design_pocket import POCKET_INIT, POCKET_TRIES, pocket_request, resplit_applies

LAST_INIT = "last"  # the front door's slot for these attempts, named by the one it runs
STRIP_INIT = "strip"  # the attempts' name among the guesses (report ``attempts``)
STRIP_COARSE_INIT = "strip coarse"  # the same split again, coarse to fine from its fold-free start
STRIP_TRIES = 3  # the least distorted splits tried in turn, the next only after a failed one
LAST_TRIES = POCKET_TRIES + 2 * STRIP_TRIES
STARTS = {STRIP_INIT: "conformal", STRIP_COARSE_INIT: "coarse"}  # each attempt's start on the strip


# one scoring of the splits for a design's attempts (a Target hashes by identity)
@lru_cache(maxsize=4)
def _splits(target: Target, rows: int, cols: int) -> tuple:
    return tuple(strip_splits(target, rows, cols, STRIP_TRIES)[:STRIP_TRIES])


def strip_request(
    req: DesignRequest, attempts: list[dict], big: bool
) -> tuple[str, DesignRequest] | None:
    """The next strip attempt ``(its name, its request)`` for ``req`` after the front door's ``attempts`` so far, or
    None where it does not apply (as ``pocket_request``: a symmetry, closed-state targets, fabrication rows,
    parallelogram holes, another solver than auto) or no split is left. Each split from its fold-free start, then
    where ``big`` (the lattice asked is one the front door designs coarse to fine) and the strip halves to a level
    at least ``MIN_ACROSS`` across, coarse to fine from that start."""
    if not resplit_applies(req) or req.target is None:
        return None
    plan = [
        (split, rc, init)
        for split, rc in _splits(req.target, req.rows, req.cols)
        for init in STARTS
        if init == STRIP_INIT or (big and min(rc) // 2 >= MIN_ACROSS)
    ]
    k = sum(a["init"] in STARTS for a in attempts)
    if k >= len(plan):
        return None
    split, (rows, cols), init = plan[k]
    return init, _on_strip(replace(req, target=split, rows=rows, cols=cols), STARTS[init])


def last_request(
    req: DesignRequest, attempts: list[dict], pocket: bool
) -> tuple[str, DesignRequest, str] | None:
    """The next last attempt after ``attempts``: ``(its name, its request, what it tries)``; the pocket
    attempts first (where ``pocket``: below the front door's big lattices), then the bent strips; None when
    none is left."""
    tried = [a["init"] for a in attempts]
    if pocket and STRIP_INIT not in tried and tried.count(POCKET_INIT) < POCKET_TRIES:
        sub = pocket_request(req, attempts)
        if sub is not None:
            return POCKET_INIT, sub, "a lattice corner in the outline's pocket"
    found = strip_request(req, attempts, not pocket)
    if found is None:
        return None
    init, sub = found
    if sub.target is None:
        return None
    corners = "; ".join(f"({x:.3g}, {y:.3g})" for x, y in sub.target.corner_points())
    how = ", coarse to fine" if init == STRIP_COARSE_INIT else ""
    return (
        init,
        sub,
        f"the lattice as a strip bent along the outline{how}: {sub.rows}x{sub.cols} tiles for the "
        f"{req.rows}x{req.cols} asked, its corners at {corners} mm",
    )


def strip_note(init: str, sub: DesignRequest, req: DesignRequest) -> dict:
    """The report's ``strip`` for a strip attempt's design (empty for any other): the lattice used, the one
    asked, its corners on the outline and why."""
    if init not in STARTS or sub.target is None:
        return {}
    corners = np.round(sub.target.corner_points(), 3).tolist()
    why = (
        f"every design on the {req.rows}x{req.cols} lattice missed (its sides ran across the outline's hollow); "
        f"a strip of {sub.rows}x{sub.cols} tiles bends along the outline, its ends at four of its corners"
    )
    return {
        "strip": {
            "tiles": [sub.rows, sub.cols],
            "asked": [req.rows, req.cols],
            "corners": [float(u) for u in sub.target.corners],
            "corners_mm": corners,
            "start": STARTS[init],
            "why": why,
        }
    }


def strip_of(report: Mapping[str, Any]) -> dict:
    """``{"strip": ...}`` of a design's ``report`` where it is a bent strip's, else empty: what a design refined
    or continued from it (minimax, the fabrication continuation) keeps, its lattice being the strip's."""
    return {"strip": report["strip"]} if report.get("strip") else {}


def strip_design(req: DesignRequest, best) -> DesignRequest:
    """``req`` as the strip attempt asked it where ``best`` (a ``_check`` outcome) is a strip's design (its
    report's ``strip``): the finishes after the attempts refine that lattice, not the one asked; else ``req``."""
    st = best.report.get("strip") if best is not None else None
    if not st or req.target is None:
        return req
    split = with_corners(req.target, np.asarray(st["corners"], float))
    strip = replace(req, target=split, rows=st["tiles"][0], cols=st["tiles"][1])
    return _on_strip(strip, st.get("start", "conformal"))


def _on_strip(sub: DesignRequest, start: str) -> DesignRequest:
    """``sub`` on a re-split target from ``start``: the fold-free start (conformal), or coarse to fine from it."""
    sub = replace(sub, coarse_bottom="conformal")
    if sub.rigid:
        return replace(sub, init=start)
    return replace(sub, init=VIA_RIGID_INIT, via_rigid_init=start)
