"""The design front doors' side of the opening figures (:mod:`fabkiri.pattern.opening`): the floor
``--min-opening`` is checked, the figures go in the report, the summary says them and warns when a
design opens little."""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import replace
from typing import Any

import numpy as np

from ..design.core.refine import refine_minimax
from ..design.quad.solve import VIA_RIGID_INIT, DesignRequest, via_rigid_applies
from ..errors import InputError, Param
from ..pattern.model import Pattern
from ..pattern.opening import Opening, opening
from .design_judge import DesignAttempt, _hausdorff, _rank, _shape_met, refinement_attempt

# a floor the solver met (its row >= 0) reads back through the mm figures to about round-off
FLOOR_SLACK = 1e-9


def check_floor(floor: float | None) -> None:
    """InputError unless ``floor`` is None or a hole fraction in (0, 1)."""
    if floor is not None and not (np.isfinite(floor) and 0.0 < floor < 1.0):
        raise InputError(
            Param("min_opening"), f" is a deployed hole fraction in (0, 1) (e.g. 0.3), got {floor}"
        )


def judge(pattern: Pattern, report: dict, floor: float | None) -> list[str]:
    """Put the opening figures in ``report["opening"]`` (with the floor asked) and return the problem of a
    design that opens less than ``floor`` (the solver's row read back on the final pattern)."""
    o = opening(pattern)
    report["opening"] = {**o.to_dict(), **({"min_opening": floor} if floor else {})}
    if floor and o.hole_fraction < floor - FLOOR_SLACK:
        return [
            f"opens {100 * o.hole_fraction:.2f} % (deployed hole fraction), below --min-opening "
            f"{floor:g}"
        ]
    return []


def summary_lines(report: Mapping[str, Any], command: str = "design") -> list[str]:
    """The opening line and, for a design that opens little, the one-line warning (with ``command``'s
    option that asks for more when it was not given)."""
    d = report.get("opening")
    if not d:
        return []
    o = Opening.from_dict(d)
    out = [o.line()]
    warn = o.warning()
    if warn:
        out.append(
            warn
            + ("" if d.get("min_opening") else f"; {command} --min-opening F sets a floor on it")
        )
    return out


def refine_to_floor(
    req: DesignRequest,
    best: DesignAttempt,
    judge: Callable,
    attempts: list[dict],
    say: Callable[[str], None],
):
    """The best design again, when a floor cost it the shape: Lawson's minimax refinement under the floor
    (:func:`fabkiri.design.core.refine.refine_minimax`), in the rigid family where the request may be answered
    by it (its steps are reduced solves). Returns the refined ``_check`` outcome when it ranks better than
    ``best``, else None; the attempt is recorded either way. Measured: star at 150 mm, 16x16, --min-opening
    0.3: 3.09 % -> 1.87 % of the size (rigid family, 10 steps)."""
    if not req.min_opening or req.target is None or not best.valid or _shape_met(best.report):
        return None
    say(
        f"fabkiri: with --min-opening {req.min_opening:g} the design misses the shape (Hausdorff "
        f"{100 * _hausdorff(best.report):.2f} % of the size); refining it under the floor (minimax steps)"
    )
    rigid = via_rigid_applies(replace(req, init=VIA_RIGID_INIT))
    step = replace(req, init=VIA_RIGID_INIT if rigid and not req.rigid else req.init)
    refined, trace, secs = refine_minimax(step, best.pattern.nodes)
    cand = judge(refined) if refined is not None else None
    better = cand is not None and _rank(cand) < _rank(best)
    attempts.append(
        refinement_attempt(
            "minimax refinement under --min-opening",
            cand,
            secs,
            trace,
            better,
            "no refinement step converged",
        )
    )
    return cand if better else None
