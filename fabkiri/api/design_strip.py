"""The last attempts for an outline the N x N lattice cannot follow, tried when every guess and the pocket
attempts (``design_pocket.py``) missed: the lattice as a strip bent along the outline (a U, a horseshoe;
``design/quad/strip_split.py``), about as many tiles as asked in other rows and columns, started from the
fold-free map of the strip onto the outline; the non-rigid request answered by the rigid family from it."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import replace
from functools import lru_cache
from typing import Any

import numpy as np

from ..design.quad.inverse_map import with_corners
from ..design.quad.solve import VIA_RIGID_INIT, DesignRequest
from ..design.quad.strip_split import strip_splits
from ..design.targets.curve import Target
from .design_pocket import POCKET_INIT, POCKET_TRIES, pocket_request, resplit_applies

LAST_INIT = "last"  # the front door's slot for these attempts, named by the one it runs
STRIP_INIT = "strip"  # the attempts' name among the guesses (report ``attempts``)
STRIP_TRIES = 3  # the least distorted splits tried in turn, the next only after a failed one
LAST_TRIES = POCKET_TRIES + STRIP_TRIES


# one scoring of the splits for a design's attempts (a Target hashes by identity)
@lru_cache(maxsize=4)
def _splits(target: Target, rows: int, cols: int) -> tuple:
    return tuple(strip_splits(target, rows, cols)[:STRIP_TRIES])


def strip_request(req: DesignRequest, attempts: list[dict]) -> DesignRequest | None:
    """The next strip attempt's request for ``req`` after the front door's ``attempts`` so far, or None where
    it does not apply (as ``pocket_request``: a symmetry, closed-state targets, fabrication rows,
    parallelogram holes, another solver than auto) or no split is left."""
    if not resplit_applies(req) or req.target is None:
        return None
    k = sum(a["init"] == STRIP_INIT for a in attempts)
    splits = _splits(req.target, req.rows, req.cols)
    if k >= len(splits):
        return None
    split, (rows, cols) = splits[k]
    return _on_strip(replace(req, target=split, rows=rows, cols=cols))


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
    sub = strip_request(req, attempts)
    if sub is None or sub.target is None:
        return None
    corners = "; ".join(f"({x:.3g}, {y:.3g})" for x, y in sub.target.corner_points())
    return (
        STRIP_INIT,
        sub,
        f"the lattice as a strip bent along the outline: {sub.rows}x{sub.cols} tiles for the "
        f"{req.rows}x{req.cols} asked, its corners at {corners} mm",
    )


def strip_note(init: str, sub: DesignRequest, req: DesignRequest) -> dict:
    """The report's ``strip`` for a strip attempt's design (empty for any other): the lattice used, the one
    asked, its corners on the outline and why."""
    if init != STRIP_INIT or sub.target is None:
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
    return _on_strip(replace(req, target=split, rows=st["tiles"][0], cols=st["tiles"][1]))


def _on_strip(sub: DesignRequest) -> DesignRequest:
    if sub.rigid:
        return replace(sub, init="conformal")  # on a re-split target: the fold-free start
    return replace(sub, init=VIA_RIGID_INIT, via_rigid_init="conformal")
