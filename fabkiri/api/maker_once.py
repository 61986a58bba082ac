"""One design of ``make`` (:func:`design_once`): the design front door at a plan's tiles, its figures, its
step line and the lines kept below it; and :func:`name_lattice`, the tiles a bent strip's design used.
:mod:`.maker_design` runs it once, or again at other counts after a shape miss."""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import replace
from pathlib import Path
from typing import Any, NamedTuple

from .design_report import DesignReport
from .maker_result import MakeResult

Progress = Callable[[str], None]


class StepRun(NamedTuple):
    """What one step of ``make`` did: whether it passed, its exit code, its one-line figures, its files
    (by name in the run's folder) and the lines it adds below them."""

    ok: bool
    exit_code: int
    figures: str
    files: dict[str, Any]
    details: list[str]


def name_lattice(result: MakeResult) -> None:
    """Where the design kept is a bent strip's (the design step's own, ``design_strip.py``), ``result.tiles``
    names that lattice, the count make chose (or the user named) kept as ``asked``: the summary's first
    line and ``make.json`` say the tiles made, not the tiles first asked."""
    report = ((result.pattern.design or {}) if result.pattern else {}).get("report") or {}
    strip = report.get("strip")
    if not strip or tuple(strip["tiles"]) == result.tiles.tiles:
        return
    r, c = (int(v) for v in strip["tiles"])
    asked = "x".join(map(str, result.tiles.tiles))
    result.tiles = replace(
        result.tiles,
        tiles=(r, c),
        asked=result.tiles.count,
        reason=f"{asked} asked ({result.tiles.reason}); the design bent the lattice into a strip of "
        f"{r}x{c} tiles along the outline, every design on the {asked} lattice having missed",
    )


def design_once(result: MakeResult, plan, say: Progress) -> StepRun:
    from .design import PatternRequest, design_pattern

    request = PatternRequest(
        tiles=plan.tiles.tiles,
        target=plan.target,
        size=plan.size,
        material=plan.material,
        hinge=plan.hinge if plan.material else None,
        printer=plan.printer,
        style=plan.style if plan.printer else None,
        shape_tol=plan.shape_tol,
        min_opening=plan.min_opening,
        corners=plan.tiles.corners,
    )
    outcome = design_pattern(request, notify=say)
    name = f"{plan.stem}.json"
    files = {str(Path(k).name): v for k, v in outcome.files(name).items()}
    result.pattern = outcome.pattern
    report = outcome.report
    result.figures = _figures(report)
    # the failure, and the lattice a bent strip used in place of the tiles make chose (design_strip.py)
    keep = ("fabkiri: design failed", "the lattice is")
    details = [line for line in outcome.summary(name) if line.startswith(keep)]
    details = opening_lines(report) + details
    return StepRun(
        outcome.success, outcome.exit_code, _line(outcome.status, result.figures), files, details
    )


def _figures(report: DesignReport) -> dict[str, Any]:
    """Hausdorff of the deployed outline (share of the size) and its tolerance; the deployment amount
    (``report["opening"]``, from the ``opening`` work) when the design reports it."""
    out: dict[str, Any] = {}
    c = (report.get("conformance") or {}).get("deployed")
    if c:
        out["hausdorff_rel"] = float(c["hausdorff_rel"])
        out["hausdorff_mm"] = float(c["hausdorff_mm"])
        out["shape_tol_rel"] = float(report["shape"]["deployed"]["tol_rel"])
    fr = report.get("fabrication") or {}
    out["rows_active"] = sum((fr.get("active") or {}).values()) if fr else 0
    if isinstance(report.get("opening"), dict):  # the seam: shown as reported
        out["opening"] = report["opening"]
    return out


def _line(status: str, figures: dict[str, Any]) -> str:
    """The design step's one line, from its :func:`_figures`."""
    shape = (
        f"Hausdorff {100 * figures['hausdorff_rel']:.2f} % of the size "
        f"(tol {100 * figures['shape_tol_rel']:.2g} %), "
        if "hausdorff_rel" in figures
        else ""
    )
    said = "" if status == "ok" else f"{status}, "
    return f"{said}{shape}{figures['rows_active']} fabrication rows active"


def opening_lines(report: Mapping[str, Any]) -> list[str]:
    """How much the design opens and, below 10 %, the warning (as design says them, naming make's option)."""
    from .design_opening import summary_lines

    return summary_lines(report, "make")
