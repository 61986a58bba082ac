"""The lattice laid along a target's mirror axis (issue #37): the design of a turned outline, turned back.

A cut pattern can be laid at any angle, but the quad lattice's rows run along the drawing's x and y axes. Where
the outline has a mirror axis (``targets.axes.mirror_axis_deg``) and neither drawing axis is one (a heart drawn
leaning 20 degrees), :func:`lattice_angle` finds the angle that lays a lattice axis on it, and
:func:`turned_design` designs the outline turned by minus that angle, then turns every node of the design and of
both closed states back: the pattern, its stored target and the report's shape verdict are the user's outline
as given, and the report says ``lattice_angle_deg``. Without ``--lattice-angle`` the turned lattice is a retry
for a design that fails on the drawing's axes, the better kept; ``--symmetry`` about an axis the outline has
only turned is met on the turned lattice. An outline with no mirror axis (the bean) keeps the drawing's axes.
Figures: docs/design-solver.md, "Session 53 (rot53)".
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import replace
from typing import TYPE_CHECKING, Any, cast

import numpy as np

from ..design.core import conformance as conf
from ..design.core.request import MIRROR_TOL
from ..design.quad.inverse_map import with_corners
from ..design.targets.axes import axis_distances, mirror_axis_deg, rotation, turned
from ..design.targets.lookup import Target, load_target
from ..errors import InputError, SolveError
from ..fabricate import fabricability
from ..pattern.model import Pattern
from .design_judge import _rank, _shape_met
from .shape_limits import annotate as annotate_misses

if TYPE_CHECKING:  # design.py imports this module
    from .design import DesignOutcome, PatternRequest

AXIS_DEG = {"x": 0.0, "y": 90.0}
# the report's figures relative to the target's size, rescaled from the turned outline's size to the user's
REL_KEYS = (
    "hausdorff_max_rel",
    "fit_max_rel_size",
    "refinement_hausdorff_rel",
    "refit_hausdorff_rel",
    "hausdorff_rel",
    "tips_only_hausdorff_rel",
    "from_hausdorff_rel",
    "steps_hausdorff_rel",
)


def lattice_angle(request: PatternRequest, target: Target) -> float:
    """The angle (degrees, counter-clockwise) to lay the lattice at for ``request`` on ``target`` (0: the
    drawing's axes).

    ``request.lattice_angle`` where given; else 0 with closed-state targets, given corners or a printer (its bed
    is the drawing's frame), where either drawing axis is a mirror axis (``--symmetry`` about the other one is
    refused as before) or the outline has none within ``MIRROR_TOL``. Else the angle that lays a lattice axis on
    the outline's mirror axis: the requested one under ``--symmetry``; on a square lattice the nearer one; on
    R x C tiles the one whose turned outline's bounding box is nearest the lattice's aspect C / R.
    """
    if request.lattice_angle is not None:
        return float(request.lattice_angle)
    if request.contracted_target or request.corners is not None or request.printer:
        return 0.0
    if (axis_distances(target, list(AXIS_DEG.values()))[1] <= MIRROR_TOL).any():
        return 0.0
    axis, error = mirror_axis_deg(target)
    if error > MIRROR_TOL:
        return 0.0
    axes = [request.symmetry] if request.symmetry in AXIS_DEG else list(AXIS_DEG)
    turns = [(axis - AXIS_DEG[a] + 90.0) % 180.0 - 90.0 for a in axes]  # each in [-90, 90)
    rows, cols = request.tiles or (1, 1)
    if rows == cols:
        return min(turns, key=abs)
    return min(turns, key=lambda t: abs(np.log(_aspect(target, -t) * rows / cols)))


def _aspect(target: Target, degrees: float) -> float:
    """Width over height of the bounding box of ``target``'s points turned by ``degrees``."""
    w, h = np.ptp(target.points @ rotation(degrees), axis=0)
    return float(w / h)


def request_target(request: PatternRequest) -> Target | None:
    """The request's target curve (by name or file, scaled to its size) with its given corners."""
    target = request.target
    if isinstance(target, str):
        target = load_target(target, request.size)
    if target is not None and request.corners is not None:
        target = with_corners(target, np.asarray(request.corners, float))
    return target


def loaded_or_turned(
    request: PatternRequest, design: Callable, notify
) -> tuple[PatternRequest, DesignOutcome | None]:
    """``request`` with its curve loaded once (the front door's designs below take the curve itself), and
    its design where the lattice may leave the drawing's axes (:func:`turned_or_retried`), else None."""
    if (user := request_target(request)) is None:
        return request, None
    request = replace(request, target=user)
    return request, turned_or_retried(request, user, design, notify)


def turned_or_retried(
    request: PatternRequest, user: Target, design: Callable, notify
) -> DesignOutcome | None:
    """``design`` (the front door) of ``request`` where the lattice may leave the drawing's axes, else None (the
    front door designs it on them). Asked (``--lattice-angle``, or ``--symmetry`` about an axis the outline has
    only turned): :func:`turned_design` at once. By default the design on the drawing's axes, and only where it
    fails the outline's mirror axis is sought (a scan of :func:`lattice_angle`, not paid by a design that passes)
    and the turned lattice tried as its retry."""
    if request.lattice_angle is not None or request.symmetry in AXIS_DEG:
        angle = lattice_angle(request, user)
        return turned_design(request, user, angle, design, notify) if angle else None
    first = design(replace(request, lattice_angle=0.0), notify)
    if first.success or not (angle := lattice_angle(request, user)):
        return first
    return turned_design(request, user, angle, design, notify, first)


def turned_design(
    request: PatternRequest,
    user: Target,
    angle: float,
    design: Callable,
    notify,
    first: DesignOutcome | None = None,
) -> DesignOutcome:
    """``design`` (the front door) of ``request`` with the lattice laid at ``angle`` (:func:`_turned`). Where that
    angle was chosen here (no ``request.lattice_angle``) and no ``--symmetry`` asks it, it is a retry: the design on
    the drawing's axes first; where that fails, the turned lattice mirrored about the outline's axis (the reduced
    solve, where the mirrored count is even and no explicit free request forbids it), then unmirrored where that
    fails too; the best kept (``_rank``); ``first``, where given, is the design on the drawing's axes. A design that passes on the drawing's axes is left as it was (turned,
    the rotated heart's 32x32 and 64x64 designs and the rotated drop's 48x48 one fared worse, docs/design-solver.md,
    "Session 53 (rot53)")."""
    if request.lattice_angle is not None or request.symmetry in AXIS_DEG:
        out = _turned(request, user, angle, design, notify)
        out.report["lattice_angle_deg"] = float(angle)
        return out
    tried = [first or design(replace(request, lattice_angle=0.0), notify)]
    if tried[0].success:
        return tried[0]
    note = (
        f"fabkiri: the design on the drawing's axes fails; trying the lattice along the outline's mirror "
        f"axis ({angle:.1f}°)"
    )
    tried[0].messages.append(note)
    if notify is not None:
        notify(note)
    for symmetry in _retries(request, user, angle):
        try:
            out = _turned(replace(request, symmetry=symmetry), user, angle, design, notify)
        except (InputError, SolveError):  # no mirrored lattice or guess: the next retry
            continue
        for a in out.report["attempts"]:
            a["lattice_angle_deg"] = float(angle)
            if symmetry in AXIS_DEG:
                a["mirrored"] = str(symmetry)
        out.report["lattice_angle_deg"] = float(angle)
        if symmetry in AXIS_DEG:
            out.report["mirrored"] = symmetry
            out.report["mirrored_why"] = "the outline's mirror axis, on the lattice turned onto it"
        tried.append(out)
        if out.success:
            break
    kept = min(tried, key=lambda o: _rank(cast(Any, o)))  # the first of equals: the drawing's axes
    report = kept.report
    report["attempts"] = [a for o in tried for a in o.report["attempts"]]
    report["time_s_total"] = float(sum(a["time_s"] for a in report["attempts"]))
    report.setdefault("lattice_angle_deg", 0.0)
    kept.messages[:] = [m for o in tried for m in o.messages]
    return kept


def _retries(request: PatternRequest, user: Target, angle: float) -> list[str | None]:
    """The symmetries of the turned retries: the lattice axis the outline's mirror axis turns onto, where the
    mirror keeps the fold states (an even count of the rows or columns it maps) and the request is not explicitly
    free ("none"); then the request's own."""
    rms = axis_distances(turned(user, -angle)[0], list(AXIS_DEG.values()))[0]
    axis = list(AXIS_DEG)[int(np.argmin(rms))]
    rows, cols = request.tiles or (1, 1)
    even = (rows if axis == "x" else cols) % 2 == 0
    return ([axis] if even and request.symmetry != "none" else []) + [request.symmetry]


def _turned(
    request: PatternRequest, user: Target, angle: float, design: Callable, notify
) -> DesignOutcome:
    """``design`` of ``request``'s target turned by ``-angle``, turned back by ``angle``: every node of the design
    and of its closed states, its stored target, and its shape judged on the user's outline."""
    inner_target, shift = turned(user, -angle)
    tol = conf.parse_shape_tol(request.shape_tol)
    tol_mm = tol[0] * user.size if tol[1] == "rel" else tol[0]
    inner = replace(
        request,
        target=inner_target,
        size=None,
        lattice_angle=0.0,
        shape_tol=f"{tol_mm:.17g}mm",  # the same tolerance in mm: the turned outline's size differs
    )
    out = design(inner, notify)

    def back(p: np.ndarray) -> np.ndarray:
        return (np.asarray(p, float) - shift) @ rotation(angle)

    pattern = out.pattern
    report = out.report
    meta = dict(pattern.design or {})
    meta["target"] = user.to_dict()
    pattern = Pattern(
        nodes=back(pattern.nodes),
        tiles=pattern.tiles,
        contracted={s: back(c) for s, c in pattern.contracted.items()},
        parity=pattern.parity,
        name=pattern.name,
        lattice=pattern.lattice,
        design=meta,
        kind=pattern.kind,
    )
    _in_user_frame(report, pattern, user, tol, inner_target.size / user.size)
    meta["report"] = report
    meta["shape"] = "met" if _shape_met(report) else "missed"
    return replace(out, pattern=pattern, report=report, shape_met=_shape_met(report))


def _in_user_frame(report: dict, pattern: Pattern, user, tol: tuple, ratio: float) -> None:
    """Re-measure ``report``'s deployed outline on the user's outline ``user`` (its shape verdict, pockets and
    fabricability, which a printer's bed makes frame-dependent), and rescale the other figures relative to the
    size by ``ratio`` (the turned outline's size over the user's; the distances in mm are the same)."""
    tiles = (pattern.lattice["rows"], pattern.lattice["cols"]) if pattern.lattice else None
    measured = conf.deployed(pattern.nodes, pattern.topology, user)
    report["conformance"] = {**report.get("conformance", {}), "deployed": measured}
    report["shape"] = {**report.get("shape", {}), "deployed": conf.judge(measured, tol, tiles)}
    for fit in (report.get("fit") or {}).values():
        if "max_mm" in fit:
            fit["max_rel_size"] = fit["max_mm"] / user.size
    for part in [*report.get("attempts", []), report.get("coarse"), report.get("minimax")]:
        if isinstance(part, dict):
            for k in REL_KEYS:
                if k in part:
                    part[k] = _scaled(part[k], ratio)
    annotate_misses(report, report.get("attempts", []), user, pattern)
    report["fabricability"] = fabricability.summary(pattern)


def _scaled(value, ratio: float):
    """``value`` (a figure, a list of them, or None where a step did not run) times ``ratio``."""
    if isinstance(value, list):
        return [_scaled(v, ratio) for v in value]
    return None if value is None else value * ratio
