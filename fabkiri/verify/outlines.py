"""Closed-state outline targets (``design --contracted-target``): does each closed state have the outline asked for?

The design section records, per closed state, either a target curve
(``contracted_targets[s]``, in mm, at the area of the tiles) or a rectangle
(``options.contracted[s] = {"rectangle": true, "ratio": r | null}``). The
closed state computed from the tiles (never the solver's own grid) is checked
against it:

* curve: measured by :func:`fabkiri.verify.outlines.target_checks` (outline shape);
* rectangle: the outline's corners on the minimum rotated rectangle, the
  aspect ratio when one was asked, and, when none was, a degenerate strip
  (aspect beyond ``DEGENERATE_ASPECT`` times the lattice's own) is reported as
  a failure rather than passed as "a rectangle".
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np
import shapely

from ..pattern.model import Pattern
from .report import Check, measured

if TYPE_CHECKING:  # pattern_checks imports this module
    from .pattern_checks import Tolerances

DEGENERATE_ASPECT = (
    4.0  # an unasked aspect this many times the lattice's rows:cols is a collapsed strip
)


def outline_corners(Y: np.ndarray, eps: float) -> tuple[np.ndarray, Any]:
    """The corners of a closed state's outline (exterior of the tile union) and the union."""
    from .geom import tiles_union

    union = tiles_union(Y, eps)
    part = max(getattr(union, "geoms", [union]), key=lambda g: g.area)
    return np.asarray(part.exterior.coords)[:-1], part


def _rectangle_checks(
    pattern: Pattern, s: int, Y: np.ndarray, ratio: float | None, tol: Tolerances
) -> list[Check]:
    pts, union = outline_corners(Y, max(tol.length, 1e-12 * tol.tile_size))
    rect = union.minimum_rotated_rectangle
    off = shapely.distance(shapely.points(pts), rect.exterior)
    c = np.asarray(rect.exterior.coords)[:4]
    sides = np.linalg.norm(np.roll(c, -1, axis=0) - c, axis=1)[:2]
    long, short = float(sides.max()), float(sides.min())
    aspect = long / max(short, 1e-300)
    g = f"state {s}"
    out = [
        measured(
            f"{g}: outline is a rectangle",
            float(off.max(initial=0.0)),
            tol.length,
            "mm",
            group=g,
            detail=f"outline corners off the minimum rotated rectangle ({long:.4g} x {short:.4g} mm)",
        )
    ]
    if ratio is not None:
        want = max(float(ratio), 1.0 / float(ratio))
        out.append(
            measured(
                f"{g}: outline aspect ratio",
                abs(long - want * short),
                tol.length,
                "mm",
                group=g,
                detail=f"{long:.4g} x {short:.4g} mm is {aspect:.4g}:1, asked {want:.4g}:1 "
                f"(long side minus asked ratio times the short side)",
            )
        )
    else:
        lat = pattern.lattice or {}
        m, n = int(lat.get("rows") or 1), int(lat.get("cols") or 1)
        limit = DEGENERATE_ASPECT * max(m / n, n / m)
        out.append(
            measured(
                f"{g}: outline not degenerate",
                aspect,
                limit,
                "ratio",
                group=g,
                detail=f"{long:.4g} x {short:.4g} mm is {aspect:.3g}:1 with no aspect asked; a "
                f"{m}x{n} lattice closing to more than {limit:.3g}:1 is a collapsed strip "
                f"(ask for one with rect=W/H)",
            )
        )
    return out


def contracted_outline_checks(
    pattern: Pattern, states: dict[int, np.ndarray], tol: Tolerances
) -> list[Check]:
    """Checks of every closed-state outline target the design recorded (none if it recorded none)."""
    d = pattern.design or {}
    asked = (d.get("options") or {}).get("contracted") or {}
    curves = d.get("contracted_targets") or {}
    out: list[Check] = []
    if not isinstance(asked, dict):
        return out
    for key, spec in sorted(asked.items()):
        try:
            s = int(key)
        except (TypeError, ValueError):
            continue
        if s not in states:
            continue
        if isinstance(curves.get(str(s)), dict) and curves[str(s)].get("points"):
            continue  # a target curve: target_checks measures the outline's shape against it
        if isinstance(spec, dict) and spec.get("rectangle"):
            r = spec.get("ratio")
            out.extend(_rectangle_checks(pattern, s, states[s], float(r) if r else None, tol))
    return out


def target_checks(
    pattern: Pattern, states: dict[int, np.ndarray] | None = None, shape_tol: str | tuple = "2%"
) -> list[Check]:
    """The outline against every stored target curve, over the whole outline (Hausdorff distance of the
    boundary-tip polygon, or of each closed state's outline, to the target), checked against ``shape_tol``
    (a share of the target's size or a length, ``design --shape-tol``) — never against a figure the
    design claims about itself."""
    from ..design.core import conformance as conf
    from ..design.targets.lookup import target_from_dict
    from ..errors import InputError

    d = pattern.design or {}
    closed_states: dict[int, np.ndarray] = states or {}
    tol = conf.parse_shape_tol(shape_tol) if isinstance(shape_tol, str) else shape_tol
    jobs: list[
        tuple[str, str, int | None, dict]
    ] = []  # (check name, group, state or None, target spec)
    if isinstance(d.get("target"), dict):
        jobs.append(("target shape", "deployed", None, d["target"]))
    for s, tgt in sorted((d.get("contracted_targets") or {}).items()):
        if isinstance(tgt, dict) and int(s) in closed_states:
            jobs.append((f"state {s}: outline shape", f"state {s}", int(s), tgt))
    out = []
    for name, _group, s, spec in jobs:
        try:
            target = target_from_dict(spec, name)
        except InputError as exc:
            out.append(
                Check(
                    name,
                    ok=False,
                    value=float("nan"),
                    tol=0.0,
                    unit="mm",
                    group="design",
                    detail=f"the stored target cannot be rebuilt: {exc}",
                )
            )
            continue
        c = (
            conf.deployed(pattern.nodes, pattern.topology, target)
            if s is None
            else conf.closed(closed_states[s], target)
        )
        j = conf.judge(c, tol)
        x, y = c["worst"]["at"]
        out.append(
            measured(
                name,
                c["hausdorff_mm"],
                j["tol_mm"],
                "mm",
                group="design",
                worst=f"({x:.1f}, {y:.1f}) mm on the {c['worst']['on']}",
                detail=(
                    f"Hausdorff {100 * c['hausdorff_rel']:.3g} % of the target size "
                    f"{c['size_mm']:.4g} mm (tolerance {100 * j['tol_rel']:.3g} %); 1-IoU "
                    f"{c['one_minus_iou']:.3g}; mean distance {c['mean_outline_to_target_mm']:.3g} /"
                    f" {c['mean_target_to_outline_mm']:.3g} mm; spacing min/mean "
                    f"{c['spacing_min_mm']:.3g}/{c['spacing_mean_mm']:.3g} mm over {c['points']} "
                    f"{'boundary tips' if s is None else 'outline vertices'} vs the "
                    f"{target.kind} target {target.name!r}"
                ),
            )
        )
    return out
