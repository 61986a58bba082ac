"""When a design that passes keeps searching (issue #37: the fit non-increasing with size).

The front door's attempts stop at the first design that passes (``design._attempts``). On an outline the N x N
lattice follows only roughly that first pass ends the search before the last attempts (the pocket, the bent
strips: ``design_strip.py``), which would come closer: the crescent at 32x32 met at 1.34 % of the size from the
coarse guess (1.09 % finished), where its 73x14 strip meets at 0.125 % coarse to fine and its 16x16 design, a
strip, at 0.36 %.
A design that passes but misses by more than ``TILE_SHARE`` of a tile (the size over the lattice's tiles a side,
``expected_fit``) is poor for its size: the guesses left are skipped, the last attempts run after it as after a
miss, and the best design (``_rank``: the closest of those that pass) is kept. On issue #37's table it finds
no last attempt where it fires (docs/design-solver.md, "Session 56 (rise56)"): the same designs.
"""

from __future__ import annotations

from collections.abc import Callable

from ..design.quad.solve import DesignRequest
from ..pattern.opening import OPENS_LITTLE, opening
from .design_judge import DesignAttempt, _fit_miss, _hausdorff, _rank, _shape_met
from .design_pocket import POCKET_INIT, resplit_applies
from .design_strip import STARTS

# a design passing but further from the outline than this share of a tile is poor for its size (issue #37's table
# passes within 0.27 of one before their finishes but the 32x32 and 64x64 hearts' and 48x48 drop's, which have no
# last attempt; the 32x32 crescent 0.43)
TILE_SHARE = 1 / 3
# a valid design whose least-squares fit misses by more than this fraction of the target size is retried
# from the next guess and the closest valid fit kept (ellipse 16x16: rescaled 1.86 %, standard 0.08 %)
RETRY_FIT_ABOVE = 5e-3


def expected_fit(req: DesignRequest) -> float:
    """The share of the size a design on ``req``'s lattice is expected to come within: ``TILE_SHARE`` of a tile,
    the size over its tiles a side."""
    return TILE_SHARE / max(req.rows, req.cols)


def poor_for_size(req: DesignRequest, outcome: DesignAttempt | None) -> bool:
    """Whether ``outcome`` (a ``_check`` outcome on ``req``'s lattice) passes every check and the shape
    tolerance but misses by more than ``expected_fit``, and a last attempt may answer ``req``
    (``resplit_applies``): then the search goes on past it."""
    return (
        outcome is not None
        and bool(outcome.valid)
        and _shape_met(outcome.report)
        and resplit_applies(req)
        and _hausdorff(outcome.report) > expected_fit(req)
    )


def replaces(
    outcome: DesignAttempt, best: DesignAttempt | None, passed: DesignAttempt | None
) -> bool:
    """Whether ``outcome`` is kept over ``best`` (``_rank``). After ``passed``, a design poor for its size, not
    where it opens little (holes under ``OPENS_LITTLE`` of the deployed sheet) and ``passed`` did not: a closer
    fit is no gain to a maker whose sheet barely opens (the T at 48x48: 0.89 % opening 15 %, its strip 0.18 %
    opening 2.5 %)."""
    if best is None:
        return True
    if _rank(outcome) >= _rank(best):
        return False
    return passed is None or not (
        opening(outcome.pattern).hole_fraction
        < OPENS_LITTLE
        <= opening(passed.pattern).hole_fraction
    )


def last_note(
    req: DesignRequest, passed: DesignAttempt | None, attempts: list[dict], what: str
) -> str:
    """What the front door says as it tries ``what``, a last attempt, after ``attempts``: after a miss, or after
    ``passed``, a design that passes but is poor for its size (``poor_for_size``; said at its first last
    attempt: where none applies the search ends unsaid)."""
    if passed is None:
        return f"fabkiri: every guess misses; trying {what}"
    if any(a["init"] in (POCKET_INIT, *STARTS) for a in attempts):
        return f"fabkiri: trying {what}"
    return (
        f"fabkiri: the design meets the shape but misses by {_hausdorff(passed.report):.2%} of the size, more "
        f"than {TILE_SHARE:.2g} of a tile ({expected_fit(req):.2%}) on {req.rows}x{req.cols} tiles; trying "
        f"{what} too, the closest kept"
    )


def with_why(note: dict, why: str | None) -> dict:
    """A strip attempt's report ``note`` (``design_strip.strip_note``) with its ``why`` replaced where ``why``
    is given."""
    if not note or why is None:
        return note
    return {"strip": {**note["strip"], "why": why}}


def strip_why(req: DesignRequest, passed: DesignAttempt | None) -> str | None:
    """The report's ``strip.why`` for a strip kept over ``passed``, a design on the lattice asked that passed
    but was poor for its size (None where no such design came before)."""
    if passed is None:
        return None
    return (
        f"the design on the {req.rows}x{req.cols} lattice met the shape at "
        f"{_hausdorff(passed.report):.2%} of the size, more than {TILE_SHARE:.2g} of a tile; a strip bent along "
        "the outline, its ends at four of its corners, came closer"
    )


def attempt_record(
    init: str, outcome: DesignAttempt, tiles: tuple[int, int], asked: tuple[int, int]
) -> dict:
    """The attempt record of the front door's design from ``init`` (its ``_check`` outcome), with the ``tiles``
    it used where they are not the ``asked`` ones (a bent strip)."""
    return {
        "init": init,
        "status": outcome.report["status"],
        "problems": outcome.problems,
        "time_s": outcome.report["time_s"],
        "fit_max_rel_size": _fit_miss(outcome.report),
        "hausdorff_max_rel": _hausdorff(outcome.report),
        "shape": "met" if _shape_met(outcome.report) else "missed",
        **({"tiles": list(tiles)} if tiles != asked else {}),
    }


def retry_note(
    init: str, inits: list[str], outcome: DesignAttempt, say: Callable[[str], None]
) -> None:
    """The note after a guess that did not end the attempts (the last attempts announce themselves)."""
    miss = _fit_miss(outcome.report)
    if outcome.valid and init in inits[:-1]:
        why = (
            f"misses the target by {miss:.2%} of its size"
            if miss > RETRY_FIT_ABOVE
            else f"misses the shape tolerance (Hausdorff {_hausdorff(outcome.report):.2%} of the size)"
        )
        say(f"fabkiri: design from the {init} guess {why}; trying the next guess too")
    elif len(inits) > 1 and init in inits[:-1]:
        say(f"fabkiri: design from the {init} guess failed ({outcome.problems[0]}); retrying")
