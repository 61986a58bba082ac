"""The mirrored design of a rigid request whose target is mirror-symmetric (issue #37).

A rigid request without a symmetry, on an elongated or non-convex target symmetric about both axes, is also
designed mirrored (``--symmetry``: the reduced solve over half the seeds). The mirrored designs are a subset
of the unmirrored ones, but the unmirrored route's LM can stop in a worse local minimum (rigid 48x48 peanut).
Both designs run to the end (guesses, finish, refinements) and the closer valid rigid-deployable one is kept;
the kept mirrored design's report says ``mirrored`` (the axis) and why. Figures: docs/design-solver.md,
"Session 51 (mir51)".
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import replace

from shapely.geometry import Polygon

from ..design.core.request import MIRROR_TOL
from ..errors import InputError, SolveError
from ..pattern.residuals import RIGID_TOL_RAD
from .design_judge import _hausdorff

# elongated: the bounding box's longer side this many times the shorter; non-convex: the area below this share
# of the convex hull's (the peanut 2:1 and non-convex, the 2:1 ellipse; the circle is neither)
ELONGATED = 1.2
CONVEX_SHARE = 0.98


def mirror_axis(request, req) -> str | None:
    """The axis to mirror a rigid request's design about, or None where the policy does not apply: an explicit
    symmetry, guess or solver, a closed-state target, fabrication rows, a target neither elongated nor non-convex
    (``_elongated_or_non_convex``) or not symmetric about both axes, or no even count of mirrored rows or columns.
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
    # one axis only (heart, star): their mirrored designs were mostly further, at up to the unmirrored
    # design's cost again; symmetric about both, the mirrored design about x
    t = req.target
    poly = Polygon(t.points)
    centroid = poly.centroid  # off either axis: not symmetric about both (before the dearer test)
    off_centre = max(abs(centroid.x), abs(centroid.y)) > MIRROR_TOL * t.size
    if off_centre or not _elongated_or_non_convex(t, poly):
        return None
    if any(t.mirror_error(a) > MIRROR_TOL for a in ("x", "y")):
        return None
    # the mirror keeps the fold states only with an even count of the rows it maps (constraints.symmetry)
    return "x" if req.rows % 2 == 0 else "y" if req.cols % 2 == 0 else None


def _elongated_or_non_convex(target, poly: Polygon) -> bool:
    """Elongated or non-convex: where the rigid family's LM stops in worse local minima (``quad/routes.py``). A
    round convex target (the circle of issue #36's speed rows) keeps its one route: its mirrored design was
    closer at 64x64 but much dearer (docs/design-solver.md, mir51)."""
    lo, hi = target.bbox
    span = hi - lo
    if span.max() >= ELONGATED * span.min():
        return True
    return bool(poly.area < CONVEX_SHARE * poly.convex_hull.area)


def _rigid_valid(outcome) -> bool:
    """Valid and rigid-deployable (the hinge sums of the rigid family)."""
    hinge = outcome.report.get("checks", {}).get("hinge_sum_max_rad")
    return bool(outcome.valid and hinge is not None and hinge <= RIGID_TOL_RAD)


def keep_closer(request, axis: str, design: Callable, notify: Callable[[str], None] | None):
    """``design`` (the front door) of ``request`` mirrored about ``axis`` and unmirrored (an explicit
    ``symmetry="none"``): the mirrored outcome where it is valid, rigid-deployable and closer, else the
    unmirrored one. The kept report lists both designs' attempts (the mirrored ones marked) and their time."""
    own = design(replace(request, symmetry="none"), notify)
    try:
        mirrored = design(replace(request, symmetry=axis), notify)
    except (InputError, SolveError):  # no mirrored lattice or guess: the unmirrored design stands
        return own
    m_h, h = _hausdorff(mirrored.report), _hausdorff(own.report)
    for a in mirrored.report["attempts"]:
        a["mirrored"] = axis
    kept = mirrored if _rigid_valid(mirrored) and (not own.valid or m_h < h) else own
    other = own if kept is mirrored else mirrored
    report = kept.report
    report["attempts"] = mirrored.report["attempts"] + own.report["attempts"]
    report["time_s_total"] = float(sum(a["time_s"] for a in report["attempts"]))
    if kept is mirrored:
        report["mirrored"] = axis
        report["mirrored_why"] = (
            f"closer than the unmirrored design (Hausdorff {m_h:.3%} vs {h:.3%} of the size)"
            if own.valid
            else "the unmirrored design is not valid"
        )
    kept.messages[:0] = other.messages
    return kept
