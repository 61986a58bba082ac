"""Shape conformance of a design to its targets and the ``--shape-tol`` check.

The measure itself is :mod:`fabkiri.pattern.conformance` (plain polygons); this module turns a
:class:`~fabkiri.design.targets.curve.Target` into its polygon, measures the deployed boundary tips and each
closed-state outline, and judges the result against the shape tolerance (default 2 % of the target's
size, the larger side of its bounding box).
"""

from __future__ import annotations

import copy
import math
import re
from collections.abc import Mapping
from typing import Any

import numpy as np

from ...errors import InputError, Param
from ...pattern import conformance as pc
from ..targets.curve import Target

DEFAULT_SHAPE_TOL = "2%"
# a miss of more than this many mean tip spacings is no chord cut off between tips (a chord of length s
# misses a corner no sharper than a right angle by at most s / 2): a local minimum or a limit of the lattice,
# not its resolution (measured: resolution misses 0.1-0.4 spacings, the leaf SVG's bad basin 7, the heart's
# 32x32 local minimum 2, a U whose lattice skips its hollow 1; docs/design-solver.md, adv54)
LOCAL_MINIMUM_SPACINGS = 0.5
# the largest count per side a trend of misses is extrapolated to (the largest rigid design fabkiri.limits tested)
TREND_MAX_TILES = 128
SPLINE_SAMPLES = (
    4096  # a spline target as a polygon: chord error ~1e-5 of the size for the named shapes
)


def target_polygon(target: Target) -> np.ndarray:
    """The target as a closed polygon in mm: a polyline's own vertices, a spline densely sampled."""
    if target.kind == "polyline":
        return np.asarray(target.points, float)
    return target.sample(max(SPLINE_SAMPLES, 4 * len(target.points)))


def deployed(nodes: np.ndarray, topology, target: Target) -> dict:
    """Conformance of the deployed boundary tips (in boundary order) to ``target``.

    The last answer is kept: the solver's second-opinion test and the design's report measure the same
    nodes against the same target (an 8x8 design spent a tenth of its work measuring twice)."""
    nodes = np.asarray(nodes, float)
    key = (
        nodes.shape,
        nodes.tobytes(),
        topology.tiles.tobytes(),
        target.kind,
        target.size,
        np.asarray(target.points, float).tobytes(),
    )
    last = _LAST_DEPLOYED.get("entry")
    if last is not None and last[0] is target and last[1] == key:
        return copy.deepcopy(last[2])
    order = pc.boundary_tip_order(
        topology.tiles, topology.hole_nodes, topology.hole_tiles, topology.free_nodes
    )
    out = pc.measure(nodes[order], target_polygon(target), target.size)
    out["target"] = target.name
    _LAST_DEPLOYED["entry"] = (
        target,
        key,
        copy.deepcopy(out),
    )  # holds the target: its id is not reused
    return out


_LAST_DEPLOYED: dict = {}


def closed(corners: np.ndarray, target: Target) -> dict:
    """Conformance of a closed state's outline, rigidly placed on ``target`` (closed-state targets fix the
    shape and size, not the placement)."""
    poly = target_polygon(target)
    outline = pc.closed_outline(corners)
    R, t = pc.align_rigid(outline, poly)
    out = pc.measure(outline @ R.T + t, poly, target.size)
    out["target"] = target.name
    out["outline"] = "closed-state tile union, rigidly aligned (centroid, rotation search, ICP)"
    out["placement"] = {"rotation_rad": float(np.arctan2(R[1, 0], R[0, 0])), "shift_mm": t.tolist()}
    return out


def parse_shape_tol(text: str) -> tuple[float, str]:
    """``2%``, ``0.02`` (a fraction) or ``0.5mm``: ``(value, "rel" | "mm")``; InputError otherwise."""
    m = re.fullmatch(r"\s*([0-9]*\.?[0-9]+(?:e[-+]?[0-9]+)?)\s*(%|mm)?\s*", str(text), re.I)
    if not m:
        raise InputError(
            Param("shape_tol"),
            f" expects a percentage of the target size (2%) or a length (0.5mm), got {text!r}",
        )
    v, unit = float(m.group(1)), (m.group(2) or "").lower()
    if unit == "%":
        v, unit = v / 100.0, "rel"
    elif unit == "":
        unit = "rel"
    if not (math.isfinite(v) and v > 0) or (unit == "rel" and v >= 1):
        raise InputError(
            Param("shape_tol"), f" must be positive (and below 100 % of the size), got {text!r}"
        )
    return v, unit


def judge(conf: dict, tol: tuple[float, str], tiles: tuple[int, int] | None = None) -> dict:
    """``{"status": "met" | "missed", "tol_mm", "hausdorff_mm", "by_mm", ...}`` of one measured outline.

    A miss estimates a lattice: the Hausdorff distance of a converged design whose tips follow the outline
    is bounded by the tip spacing (a stretch between two tips is cut off as a chord), which scales as
    1 / tiles per side, so the estimate scales the tile count by Hausdorff / tolerance (``bench/shapes.py``
    measures the trend). It is an estimate from one size, worded as one: ``make`` checks it against the
    counts it designed (:func:`tile_trend`), the design against its up-front checks (api/shape_limits.py).
    A miss larger than half the mean tip spacing is no chord cut off: the solve ended in a local minimum,
    or the lattice does not follow the outline, and no tile count is estimated (``local_minimum``).
    """
    value, unit = tol
    tol_mm = value * conf["size_mm"] if unit == "rel" else value
    h = conf["hausdorff_mm"]
    out = {
        "status": "met" if h <= tol_mm else "missed",
        "tol_mm": tol_mm,
        "tol_rel": tol_mm / conf["size_mm"],
        "hausdorff_mm": h,
        "hausdorff_rel": conf["hausdorff_rel"],
        "by_mm": max(0.0, h - tol_mm),
    }
    spacing = conf.get("spacing_mean_mm")
    if out["status"] == "missed" and spacing and h > LOCAL_MINIMUM_SPACINGS * spacing:
        out["local_minimum"] = True
        out["spacings"] = h / spacing
    elif out["status"] == "missed" and tiles is not None:
        f = h / tol_mm
        out["suggested_tiles"] = [int(2 * math.ceil(n * f / 2)) for n in tiles]
    return out


def _local_minimum_note(j: Mapping[str, Any]) -> str:
    """Why (a pocket cut across) and what is left to try: never a guess the design already tried."""
    from ..quad.initial import INITS

    pocket = j.get("pocket")
    note = (
        f"; the outline runs across a pocket of the target {pocket['depth_mm']:.3g} mm deep (deepest at "
        f"({pocket['deepest'][0]:.1f}, {pocket['deepest'][1]:.1f}) mm), covering "
        f"{100 * pocket.get('covered', 1.0):.0f} % of it: the lattice's sides did not follow the outline "
        f"into the hollow"
        if pocket
        else ""
    )
    filled = j.get("pocket_filled")
    if filled:  # api/shape_limits.py: no pocket run across, the deepest one measured
        note += (
            f"; the target has a pocket {filled['depth_mm']:.3g} mm deep (deepest at "
            f"({filled['deepest'][0]:.1f}, {filled['deepest'][1]:.1f}) mm), {100 * filled['covered']:.0f} % of "
            f"which the outline fills (none where it follows the target)"
        )
    strip = (pocket or {}).get("strip")
    if strip:  # corner_split.bent_strip: what make picks for this outline
        r, c = strip["tiles"]
        at = "; ".join(f"({x:.3g}, {y:.3g})" for x, y in strip["corners"])
        note += (
            f"; try it as a bent strip: {r}x{c} tiles with the lattice's corners at {at} mm (centred) "
            f"(`fabkiri make` picks them; `design` takes them as --tiles {r}x{c} and a JSON target's "
            f'"corners")'
        )
    if "tried_inits" not in j:
        return note + " (try another --init)"
    tried = list(dict.fromkeys(j["tried_inits"]))
    guesses = [i for i in tried if i in INITS]
    # the rigid family (the front door's last guess), a refinement
    others = ["the rigid family" if i == "rigid" else i for i in tried if i not in INITS]
    done = ", ".join([f"--init {', '.join(guesses)}"] * bool(guesses) + others)
    left = [i for i in INITS if i not in tried]
    if left:
        return note + f" (tried {done}; not tried: --init {', '.join(left)})"
    return note + f" (every initial guess was tried: {done})"


def describe_miss(label: str, j: Mapping[str, Any], conf: Mapping[str, Any]) -> str:
    """One line for a missed shape tolerance. ``j["trend"]`` (``[[rows, cols, hausdorff_rel], ...]``, the
    designs ``make`` ran of this outline at other counts) words the tile count from their measured trend."""
    x, y = conf["worst"]["at"]
    line = (
        f"shape missed ({label}): Hausdorff {j['hausdorff_mm']:.3g} mm ({100 * j['hausdorff_rel']:.2f} % of "
        f"the size) > tolerance {j['tol_mm']:.3g} mm ({100 * j['tol_rel']:.2f} %), by {j['by_mm']:.3g} mm, "
        f"worst at ({x:.1f}, {y:.1f}) mm"
    )
    if j.get("local_minimum"):
        line += (
            f"; that is {j['spacings']:.2g} tip spacings, more than the half spacing a chord cut off between "
            f"tips misses by: a local minimum or a limit of the lattice, which more tiles alone may not fix"
            + _local_minimum_note(j)
        )
    if len({(r, c) for r, c, _ in j.get("trend") or ()}) >= 2:
        return line + "; " + trend_words(tile_trend(j["trend"], j["tol_rel"]))
    if "estimate_withheld" in j:  # api/shape_limits.py: more tiles are no remedy at this size
        line += f"; no tile count is estimated: {j['estimate_withheld']['why']}"
    elif "suggested_tiles" in j:
        r, c = j["suggested_tiles"]
        line += (
            f"; about {r}x{c} tiles if the miss falls as 1/tiles per side (a chord cut off between tips), "
            f"an estimate from this one size, not designed"
        )
    return line


def tile_trend(points, tol_rel: float) -> dict[str, Any]:
    """The trend of the misses of designs at several counts (``[[rows, cols, hausdorff_rel], ...]``, the
    best at each count): ``rate``, the fitted p of Hausdorff ~ tiles per side^-p (least squares in logs);
    ``tiles``, the count that rate reaches the tolerance at (at most 1/tiles: a faster measured rate is
    not extrapolated), None where the misses do not fall or it lies past :data:`TREND_MAX_TILES`."""
    best: dict[tuple[int, int], float] = {}
    for r, c, h in points:
        best[(int(r), int(c))] = min(float(h), best.get((int(r), int(c)), math.inf))
    counts = sorted(best, key=lambda t: t[0] * t[1])
    n = np.sqrt([r * c for r, c in counts])
    h = np.array([best[t] for t in counts])
    rate = float(-np.polyfit(np.log(n), np.log(h), 1)[0])
    out: dict[str, Any] = {
        "designed": [[r, c, best[(r, c)]] for r, c in counts],
        "rate": rate,
        "tiles": None,
    }
    if rate > 0:
        r, c = counts[-1]  # from the largest count designed
        f = (h[-1] / tol_rel) ** (1.0 / min(rate, 1.0))
        want = [int(2 * math.ceil(k * f / 2)) for k in (r, c)]
        if max(want) <= TREND_MAX_TILES:
            out["tiles"] = want
    return out


def trend_words(trend: Mapping[str, Any]) -> str:
    """What :func:`tile_trend` measured, as a clause: the counts designed and what their trend says."""
    seen = ", ".join(f"{r}x{c} {100 * h:.2f} %" for r, c, h in trend["designed"])
    p = trend["rate"]
    if p <= 0:
        return (
            f"the misses did not fall with tiles ({seen}): no tile count is estimated to reach it"
        )
    how = "at least as fast as" if p >= 1 else f"slower than (as tiles^-{p:.2g})"
    if trend["tiles"] is None:
        return (
            f"the misses fell {how} 1/tiles per side ({seen}), too slowly for any count up to "
            f"{TREND_MAX_TILES}x{TREND_MAX_TILES} to reach it at that rate"
        )
    r, c = trend["tiles"]
    rate = "1/tiles per side" if p >= 1 else "that rate"
    return (
        f"the misses fell {how} 1/tiles per side ({seen}): about {r}x{c} tiles at {rate}, "
        f"an estimate from these designs, not designed"
    )
