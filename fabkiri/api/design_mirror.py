"""The mirrored design of a rigid request whose target is mirror-symmetric (issue #37).

A rigid request without ``--symmetry`` on a target symmetric about both axes is also designed mirrored
(the reduced solve over half the seeds): the mirrored family is a subset of the unmirrored one, but the
unmirrored route's LM often stops in a worse local minimum (rigid 48x48 peanut). The mirrored design runs
first; where it is valid, rigid-deployable and within ``MIRRORED_ENOUGH`` of the size, it is kept and the
unmirrored route is skipped; otherwise the unmirrored route runs and the closer valid design is kept. The
kept design's report says ``mirrored`` (the axis) and why. Figures: docs/design-solver.md, "Session 51
(mir51)".
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import replace

from shapely.geometry import MultiPoint

from ..design.core.request import MIRROR_TOL
from ..errors import InputError, SolveError
from ..mechanics.path import RIGID_TOL_RAD
from .design_judge import _hausdorff

# a mirrored design within this share of the target's size ends the search (the unmirrored route is not run)
MIRRORED_ENOUGH = 5e-4
# elongated: the bounding box's longer side this many times the shorter; non-convex: the area below this share
# of the convex hull's (the peanut 2:1 and non-convex, the 2:1 ellipse; the circle is neither)
ELONGATED = 1.2
CONVEX_SHARE = 0.98


def mirror_axis(request, req) -> str | None:
    """The axis to mirror a rigid request's design about, or None where the policy does not apply: an explicit
    symmetry, guess or solver, a closed-state target, fabrication rows or a target not symmetric about both axes.
    """
    if (
        not request.rigid
        or request.symmetry
        or request.init
        or request.solver != "auto"
        or req.holes != "rhombus"
        or req.contracted
        or req.fabrication is not None
        or req.min_opening
        or req.target is None
    ):
        return None
    # one axis only (heart, star): their mirrored designs were further in 9 of the table's 10 cells, at up to
    # the unmirrored design's cost again; symmetric about both, the mirrored design about x
    both = all(req.target.mirror_error(a) <= MIRROR_TOL for a in ("x", "y"))
    if not (both and _stalls(req.target)):
        return None
    # the mirror keeps the fold states only with an even count of the rows it maps (constraints.symmetry)
    return "x" if req.rows % 2 == 0 else "y" if req.cols % 2 == 0 else None


def _stalls(target) -> bool:
    """Elongated or non-convex: where the rigid family's LM stops in worse local minima (``quad/routes.py``). A
    round convex target (the circle of issue #36's speed rows) keeps its one route: at 64x64 its mirrored design
    was closer but cost three times as much."""
    lo, hi = target.bbox
    span = hi - lo
    hull = MultiPoint(target.points).convex_hull.area
    return bool(span.max() >= ELONGATED * span.min() or abs(target.area) < CONVEX_SHARE * hull)


def _rigid_valid(outcome) -> bool:
    """Valid and rigid-deployable (the hinge sums of the rigid family)."""
    hinge = outcome.report.get("checks", {}).get("hinge_sum_max_rad")
    return bool(outcome.valid and hinge is not None and hinge <= RIGID_TOL_RAD)


def with_mirrored(
    request, req, target, contracted, shape_tol, say: Callable[[str], None], attempts_of: Callable
):
    """``attempts_of``'s ``(best, attempts)``, with the mirrored design tried first where :func:`mirror_axis`
    applies; the mirrored attempts are recorded with ``"mirrored": axis``. Where the mirrored design is kept,
    ``req.symmetry`` is set to its axis: the steps after the guesses (the minimax finish) refine it as the
    mirrored request they would refine for ``--symmetry``."""
    axis = mirror_axis(request, req)
    if axis is None:
        return attempts_of(request, req, target, contracted, shape_tol, say)
    try:
        mirrored, m_attempts = attempts_of(
            replace(request, symmetry=axis),
            replace(req, symmetry=axis),
            target,
            contracted,
            shape_tol,
            say,
        )
    except (InputError, SolveError) as exc:
        say(f"fabkiri: no design mirrored about {axis} ({exc}); the unmirrored design only")
        return attempts_of(request, req, target, contracted, shape_tol, say)
    for a in m_attempts:
        a["mirrored"] = axis
    m_ok, m_h = _rigid_valid(mirrored), _hausdorff(mirrored.report)
    if m_ok and m_h <= MIRRORED_ENOUGH:
        req.symmetry = axis
        return mirrored, m_attempts
    say(
        f"fabkiri: the design mirrored about {axis} (the target is symmetric) "
        f"{'is' if m_ok else 'is not'} valid, Hausdorff {m_h:.3%} of the size; trying the unmirrored design too"
    )
    best, attempts = attempts_of(request, req, target, contracted, shape_tol, say)
    if m_ok and (not best.valid or m_h < _hausdorff(best.report)):
        best, req.symmetry = mirrored, axis
    return best, m_attempts + attempts


def mirror_note(req, request, attempts: list[dict]) -> dict:
    """The report's ``mirrored`` (axis) and ``mirrored_why`` where the kept design is the mirrored one of a request
    without ``--symmetry`` (read off the attempts: a later finish replaces the report), else {}."""
    if not req.symmetry or request.symmetry:
        return {}
    own = [
        a["hausdorff_max_rel"] for a in attempts if "mirrored" not in a and "hausdorff_max_rel" in a
    ]
    why = (
        f"closer than the unmirrored design (Hausdorff {min(own):.3%} of the size)"
        if own
        else f"within {MIRRORED_ENOUGH:.2%} of the size, the unmirrored design not tried"
    )
    return {"mirrored": req.symmetry, "mirrored_why": why}
