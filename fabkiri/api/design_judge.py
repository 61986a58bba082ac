"""How the design front door judges an attempt: contract, check, measure the shape, and rank.

:func:`_check` turns a solver result into a :class:`DesignAttempt`; :func:`_rank` orders attempts, best
first.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import TYPE_CHECKING, Any

import numpy as np

from .. import limits
from ..design.core import conformance as conf
from ..design.targets.lookup import Target
from ..fabricate import design_limits
from ..mechanics.contract import contract
from ..pattern.model import Pattern
from .closed_states import closed_outline_fit, overlapping_tiles
from .design_report import DesignAttempt

if TYPE_CHECKING:  # design.py imports this module
    from .design import PatternRequest

CLOSURE_TOL = 1e-9  # loop closure relative to the mean tile edge


def _shape_met(report: Mapping[str, Any]) -> bool:
    return all(j["status"] == "met" for j in (report.get("shape") or {}).values())


def _hausdorff(report: Mapping[str, Any]) -> float:
    """Worst Hausdorff distance of any outline relative to its target's size."""
    return max(
        (c["hausdorff_rel"] for c in (report.get("conformance") or {}).values()), default=0.0
    )


def _fit_miss(report: Mapping[str, Any]) -> float:
    """Worst fit of the tips (deployed or closed-state outline) to any target relative to its size (the soft
    outline rows never reach zero: ``_hausdorff`` judges the whole outline)."""
    return max(
        (
            float(f.get("max_rel_size", 0.0))
            for f in (report.get("fit") or {}).values()
            if not f.get("soft")
        ),
        default=0.0,
    )


def _rank(outcome: DesignAttempt) -> tuple:
    """Order of preference among attempts: valid first, then (for a printer) closed state 1 within its bed, then
    fewer problems, then the shape tolerance met, then the smaller Hausdorff distance, then the closer fit of
    the tips (the heart 8x8 for prusa-mk4: the refined design, 3.27 %, was 227 mm tall on the 210 mm bed)."""
    return (
        not outcome.valid,
        not outcome.report.get("checks", {}).get("fits_bed", True),
        len(outcome.problems),
        not _shape_met(outcome.report),
        _hausdorff(outcome.report),
        _fit_miss(outcome.report),
    )


def refinement_attempt(
    init: str, cand, secs: float, trace: list, kept: bool, none_why: str
) -> dict:
    """The attempt record of a refinement (its best ``_check`` outcome ``cand``, or None with ``none_why``)."""
    return {
        "init": init,
        "status": cand.report["status"] if cand else "unconverged",
        "problems": cand.problems if cand else [none_why],
        "time_s": secs,
        "hausdorff_max_rel": _hausdorff(cand.report) if cand else float("nan"),
        "shape": "met" if cand and _shape_met(cand.report) else "missed",
        "refinement_hausdorff_rel": trace,
        "kept": kept,
    }


def _check(
    result, contracted, request: PatternRequest, target: Target | None, shape_tol: tuple
) -> DesignAttempt:
    """Contract, check closure, overlaps, squeezed tiles and outlines: the judged :class:`DesignAttempt`."""
    pattern = result.pattern
    report = dict(result.report)
    size = pattern.tile_size
    checks: dict[str, object] = {}
    contracted_states = {}
    problems = []
    for s in (1, 2):
        c = contract(pattern, s)
        contracted_states[s] = c.corners
        rel = c.max_closure / size
        checks[f"closure_{s}_rel"] = rel
        if not rel <= CLOSURE_TOL:
            problems.append(f"state {s} does not close (loop closure {rel:.2e} tile sizes)")
    problems += _overlaps_and_slivers(pattern, contracted_states, checks)
    if (
        request.printer
    ):  # in the state `print` makes: a design that does not fit the bed ranks below one that does
        state = (((pattern.design or {}).get("options") or {}).get("fabrication") or {}).get(
            "state", 1
        )
        checks["fits_bed"] = design_limits.fits_bed(contracted_states[state], request.printer)
    if request.rigid or request.holes == "parallelogram":
        from ..pattern.residuals import hinge_sums

        checks["hinge_sum_max_rad"] = float(np.abs(hinge_sums(pattern)).max())
    closed_fit = {}
    for s, spec in contracted.items():
        if isinstance(spec, Target):
            closed_fit[str(s)] = closed_outline_fit(
                pattern, contracted_states[s], result.closed_grids[s], result.closed_targets[s], s
            )
    if closed_fit:
        report["closed_outline_fit"] = closed_fit
    report["conformance"], report["shape"] = _conformance(
        pattern, result, contracted_states, target, shape_tol
    )
    report["checks"] = checks
    valid = result.converged and not problems
    if not result.converged:
        problems.insert(
            0,
            f"solver did not reach the tolerance (max equality residual "
            f"{report['max_equality_residual']:.2e} > {request.tol:g})",
        )
    if problems:
        report["status"] = "unconverged"
        report["problems"] = problems
    return DesignAttempt(pattern, report, problems, valid, contracted_states)


def _overlaps_and_slivers(pattern: Pattern, contracted_states: dict, checks: dict) -> list[str]:
    """The overlapping tile pairs of each state (counted in ``checks``) and a tile squeezed to an edge no file
    reader takes (``limits.sliver``: the drop's point at 96x96 tiles, squeezed by the finish's steps), each an
    invalid design's problem."""
    problems, size = [], pattern.tile_size
    for label, corners, state in [
        ("deployed", pattern.corners(), None),
        *[(f"state {s}", contracted_states[s], s) for s in (1, 2)],
    ]:
        ov = overlapping_tiles(corners, CLOSURE_TOL * size, pattern, state)
        checks[f"overlaps_{label.replace(' ', '_')}"] = len(ov)
        if ov:
            where = "the deployed state" if label == "deployed" else label
            problems.append(f"{len(ov)} overlapping tile pairs in {where} (first {ov[0]})")
    if squeezed := limits.sliver(pattern.nodes, pattern.tiles, contracted_states):
        problems.append(squeezed)
    return problems


def _conformance(
    pattern: Pattern, result, contracted_states: dict, target: Target | None, shape_tol: tuple
) -> tuple[dict, dict]:
    """Conformance of the deployed tips and of each closed-state outline with a target curve, and each
    judged against ``--shape-tol``."""
    measured = {}
    tiles = (pattern.lattice["rows"], pattern.lattice["cols"]) if pattern.lattice else None
    if target is not None:
        measured["deployed"] = conf.deployed(pattern.nodes, pattern.topology, target)
    for s, tgt in sorted(result.closed_targets.items()):
        measured[f"state_{s}"] = conf.closed(contracted_states[s], tgt)
    return measured, {k: conf.judge(c, shape_tol, tiles) for k, c in measured.items()}
