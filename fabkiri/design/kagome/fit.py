"""Inverse design of kagome patterns: a reconfigurable kagome whose deployed outline follows a target.

Unknowns are the deployed nodes in normalised units (the standard tile edge is 1). The rows:

* **equalities**: both closed states' edge pairs and rings (:mod:`fabkiri.design.kagome.constraints`), and a mirror
  symmetry of the lattice wherever the target has the same one (:mod:`fabkiri.design.kagome.rows`);
* **fit** (soft): every boundary tip on its own side's arc of the target (B, R, T, L, as the quad solver
  assigns them), and the whole tip polygon against the target (chord midpoints, target samples to their
  nearest chord: a cusp no tip reaches still pulls), as in :mod:`fabkiri.design.targets.families`;
* **inequalities** (soft, one-sided): both gaps at every hinge and every tile's shape quality above a
  floor, so no tile folds over or overlaps its neighbour; the quality is scale free, so the tiles may grow
  and shrink to follow the target; and every boundary fan of a closed state short of a full turn, so a
  row's end tile (on one hinge) does not fold onto the next row's in a closed state.

The solve (:mod:`fabkiri.design.kagome.solve`) moves the fit in the family's tangent space (equality-
constrained Levenberg-Marquardt), then refines the largest misses by Lawson's reweighting of the fit
rows (as :mod:`fabkiri.design.core.refine` does for quads) and keeps the step with the smallest Hausdorff
distance; a last projection takes the equalities to rounding.

The initial guess maps the standard R x C kagome onto the target: its boundary tips spread along the
target by arc length from the bottom of the vertical centre line (so a symmetric lattice lands
symmetrically), the other nodes by a harmonic (Tutte-style) embedding. The target's four arcs are split
midway between the last tip of one side and the first of the next.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, replace

import numpy as np
from scipy import sparse
from scipy.sparse.linalg import spsolve

from ...errors import InputError
from ...pattern.model import Pattern
from ..core.conformance import deployed
from ..core.stencils import Family
from ..targets.curve import Target
from ..targets.families import outline_match, shape_match
from . import constraints as K
from . import pairs as KP
from . import rows as KR
from . import solve as KS

GAP_FLOOR = np.radians(10.0)  # smallest gap at a hinge (the standard's are 120°)
HOLE_GAP_FLOOR = GAP_FLOOR  # the same for a gap that is a hole's corner
CONVEX = np.radians(
    5.0
)  # with convex=True a hole's corner is at most 175° (6x11 free heart: 4.35 -> 11.7 %)
PAIR_MARGIN = 0.01  # with pairs=True: corners of tiles sharing no hinge this far outside each other (tile edges)
QUALITY_FLOOR = 0.35  # smallest tile quality 4√3A/Σℓ² (equilateral 1; 0.35 ≈ a 13° corner)
INEQ_WEIGHT = 100.0
LAWSON_STEPS = 8
FROM_BEST = False  # True: each Lawson step starts from the best design so far (6x11 heart: same best, 7.38 %)
WEIGHT_RANGE = (1e-3, 1e3)  # squared Lawson weights relative to their mean
# lawson_route="damped": each Lawson step multiplies a row's squared weight by the square root of its miss
# over the mean miss; the full ratio overshoots on a lattice cut to the outline, the worst point moving
# from step to step (7x14 heart cut to 59 tiles: 2.42 % -> 0.92 %), but fits the whole block better
# (docs/kagome.md, "Other Lawson routes on a cut lattice")
DAMPED_LAWSON_POWER = 0.5
MIRROR_TOL = 1e-3  # a target this close to mirror symmetric (of its size) gets the lattice's mirror


@dataclass(frozen=True)
class KagomeDesign:
    """A designed kagome pattern (mm) and how the solve went."""

    pattern: Pattern
    max_equality: float  # largest |edge pair| (normalised squared length), |ring| (rad) or |mirror|
    max_tip_distance_mm: float  # largest distance of a boundary tip from the target
    iterations: int
    converged: bool  # the projection onto the equalities reached |r| <= 1e-13
    symmetry: tuple[
        str, ...
    ] = ()  # mirror axes imposed ("y": the vertical centre line, "x": horizontal)
    min_gap_deg: float = 0.0  # smallest gap at a hinge, deployed
    min_quality: float = 0.0  # smallest tile quality 4√3A/Σℓ²
    hausdorff_trace: tuple[
        float, ...
    ] = ()  # the first solve's and each Lawson step's (fractions of the size)
    # every converged, unfolded step as (Hausdorff fraction, deployed nodes in mm), nearest first: the
    # caller may check each (closed-state overlaps are a mechanics question) and keep the first that passes
    candidates: tuple[tuple[float, np.ndarray], ...] = ()


def _bottom_arc(poly: np.ndarray, cx: float) -> np.ndarray:
    """Arc-length fraction of each vertex of the closed CCW polygon, from its lowest crossing of the
    vertical line x = cx."""
    q = np.roll(poly, -1, 0)
    seg = np.linalg.norm(q - poly, axis=1)
    s = np.r_[0.0, np.cumsum(seg)[:-1]]
    cross = (poly[:, 0] - cx) * (q[:, 0] - cx) <= 0
    cross &= poly[:, 0] != q[:, 0]
    t = np.where(cross, (cx - poly[:, 0]) / np.where(cross, q[:, 0] - poly[:, 0], 1.0), 0.0)
    y = np.where(cross, poly[:, 1] + t * (q[:, 1] - poly[:, 1]), np.inf)
    i = int(np.argmin(y))
    zero = s[i] + t[i] * seg[i]
    return np.mod(s - zero, seg.sum()) / seg.sum()


def initial_nodes(standard: Pattern, target: Target, order: np.ndarray, us: int = 8192):
    """The standard kagome mapped onto the target (normalised units) and the target parameter of each
    tip: tips at the arc-length fractions they have along the standard's tip outline, counted from the
    bottom of the vertical centre line on both; every other node harmonic on the tile-edge graph."""
    x = standard.nodes / standard.tile_size
    f_tip = _bottom_arc(x[order], 0.5 * (x[:, 0].min() + x[:, 0].max()))
    u = np.linspace(0.0, 1.0, us, endpoint=False)
    curve = target.point(u)
    lo, hi = target.bbox
    f_curve = _bottom_arc(curve, 0.5 * (lo[0] + hi[0]))
    k = np.argsort(f_curve)
    uu = np.unwrap(2 * np.pi * u[k]) / (2 * np.pi)  # the parameter increases with the fraction
    u_tip = np.mod(np.interp(f_tip, np.r_[f_curve[k], 1.0], np.r_[uu, uu[0] + 1.0]), 1.0)
    placed = target.point(u_tip) / standard.tile_size
    return _harmonic(standard, order, placed), u_tip


def _harmonic(standard: Pattern, fixed: np.ndarray, placed: np.ndarray) -> np.ndarray:
    """Nodes with ``fixed`` at ``placed`` and the others solving L x = 0 on the tile-edge graph."""
    top = standard.topology
    n = top.n_nodes
    e = np.stack([top.tiles, np.roll(top.tiles, -1, 1)], -1).reshape(-1, 2)
    W = sparse.csr_matrix((np.ones(len(e)), (e[:, 0], e[:, 1])), shape=(n, n))
    W = ((W + W.T) > 0).astype(float)
    L = (sparse.diags(np.asarray(W.sum(1)).ravel()) - W).tocsr()
    free = np.setdiff1d(np.arange(n), fixed)
    out = np.zeros((n, 2))
    out[fixed] = placed
    rhs = -L[free][:, fixed] @ placed
    out[free] = np.column_stack([spsolve(L[free][:, free].tocsc(), rhs[:, k]) for k in range(2)])
    return out


def side_split(target: Target, u_tip: np.ndarray, sides: np.ndarray) -> Target:
    """``target`` with its B, R, T, L arcs split midway between the tips of consecutive sides."""
    corners = []
    for a, b in ((3, 0), (0, 1), (1, 2), (2, 3)):  # BL, BR, TR, TL
        i = np.flatnonzero((sides == a) & (np.roll(sides, -1) == b))[0]
        u0, u1 = u_tip[i], u_tip[(i + 1) % len(u_tip)]
        corners.append(np.mod(u0 + 0.5 * np.mod(u1 - u0, 1.0), 1.0))
    return Target(
        target.name, target.kind, target.points, corners=np.array(corners), source=target.source
    )


def mirror_axes(
    standard: Pattern, target: Target, symmetry: bool | str = True
) -> list[tuple[str, np.ndarray]]:
    """The mirrors imposed: every one both the lattice and the target (about its bounding-box centre) have
    (``True``), none (``False``), or the one named (``"x"``: y -> -y, ``"y"``: x -> -x), which both must
    have (:class:`InputError` naming which does not)."""
    if symmetry is False:
        return []
    out = []
    centred = target.centred()
    for axis in ("y", "x") if symmetry is True else (str(symmetry),):
        m = KR.mirror_map(standard, axis)
        fits = centred.mirror_error(axis) <= MIRROR_TOL
        if m is not None and fits:
            out.append((axis, m))
        elif symmetry is not True:
            need = "an odd number of columns" if axis == "y" else "an even number of rows"
            raise InputError(
                f"the kagome lattice has no mirror about the {axis} axis (it needs {need})"
                if m is None
                else f"target {target.name!r} is not symmetric about the {axis} axis"
            )
    return out


def fit_rows(
    standard: Pattern,
    target: Target,
    symmetry: bool | str = True,
    convex: bool = False,
    fab: Sequence[Family] = (),
    pairs: bool = False,
):
    """``(rows, x0, axes)``: every row of the fit of ``standard`` to ``target`` (mm, centred on its
    bounding box), and the initial guess (normalised units). ``fab``: fabrication inequalities in the
    same normalised units (:func:`fabkiri.design.kagome.fabrication.families`), kept beside the others;
    ``pairs``: the non-overlap rows of tiles that share no hinge (:mod:`fabkiri.design.kagome.pairs`)."""
    top = standard.topology
    nv, scale = top.n_nodes, standard.tile_size
    order = KR.tip_order(standard)
    sides = KR.tip_sides(standard, order)
    x0, u_tip = initial_nodes(standard, target, order)
    tgt = side_split(target, u_tip, sides).transformed(1.0 / scale)
    axes = mirror_axes(standard, target, symmetry)
    eq = K.families(standard, (1, 2)) + [KR.symmetry_family(m, a, nv) for a, m in axes]
    fit = [shape_match(order, sides, tgt, nv, "shape"), outline_match(order, tgt, nv)]
    ineq = [
        KR.gap_family(standard, GAP_FLOOR, CONVEX if convex else None, HOLE_GAP_FLOOR),
        KR.quality_family(standard, QUALITY_FLOOR),
        KR.fan_family(standard, GAP_FLOOR),
        *([KP.pair_family(standard, PAIR_MARGIN)] if pairs else []),
        *fab,
    ]
    eq, fit, ineq = ([KS.reusing_structure(f) for f in fams] for fams in (eq, fit, ineq))
    rows = KS.Rows(eq, fit, ineq, {}, INEQ_WEIGHT)
    return rows, x0, tuple(a for a, _ in axes)


def lawson(rows: KS.Rows, x: np.ndarray, power: float = 1.0) -> dict:
    """Next weights of the fit rows: squared weights times the row's miss over the mean miss (to the
    ``power``: below 1 damps the step), normalised to mean 1 and clipped (Lawson's minimax reweighting,
    as design/core/refine.py)."""
    out = {}
    for f in rows.fit:
        miss = np.abs(f.residual(x))
        w2 = np.broadcast_to(rows.weights.get(f.name, 1.0), miss.shape) ** 2
        mean = max(float(miss.mean()), 1e-300)
        w2 = w2 * miss / mean if power == 1.0 else w2 * (miss / mean) ** power
        out[f.name] = np.sqrt(np.clip(w2 / max(float(w2.mean()), 1e-300), *WEIGHT_RANGE))
    return out


def design(  # noqa: PLR0913 (the fit's routes, each a keyword the front door passes)
    standard: Pattern,
    target: Target,
    *,
    symmetry: bool | str = True,
    refine_steps: int = LAWSON_STEPS,
    max_iter: int = 60,
    convex: bool = False,
    fab: Sequence[Family] = (),
    start: np.ndarray | None = None,
    pairs: bool = False,
    lawson_route: str = "full",
    solves: dict | None = None,
) -> KagomeDesign:
    """A reconfigurable kagome on ``standard``'s tiles whose deployed tips follow ``target`` (mm).

    ``standard`` fixes the lattice and the starting tile size (its mm scale); ``target`` is in mm.
    ``symmetry`` imposes every mirror the lattice and the target share; ``refine_steps`` Lawson steps
    follow the first solve. The design returned is the converged one nearest the target (Hausdorff).
    ``convex`` keeps every hole convex, which rules out tiles crossing a hole (deployed overlaps between
    non-adjacent tiles) at a price in fit. ``fab``: fabrication inequalities (normalised by
    ``standard``'s tile size, :mod:`fabkiri.design.kagome.fabrication`); ``start``: deployed nodes (mm) to start
    from instead of the initial guess (a continuation from an earlier design); ``pairs``: rows keeping
    tiles that share no hinge apart (across a hole or a row-end notch, :mod:`fabkiri.design.kagome.pairs`);
    ``lawson_route``: ``"full"`` (each Lawson step by the full miss ratio, from the last step), ``"damped"``
    (by its square root, ``DAMPED_LAWSON_POWER``) or ``"from best"`` (full, from the best design so far).
    ``solves``: the solves of earlier designs with the same rows (lattice, target, mirrors, options), by
    their start and weights; a solve asked again is taken from it (:func:`_solve_once`).
    """
    lo, hi = target.bbox
    shift = 0.5 * (lo + hi)
    centred = target.transformed(1.0, -shift)
    scale = standard.tile_size
    rows, x, axes = fit_rows(standard, centred, symmetry, convex, fab, pairs)
    power = DAMPED_LAWSON_POWER if lawson_route == "damped" else 1.0
    if start is not None:
        x = (np.asarray(start, float) - shift) / scale
    best, trace, its, cands = None, [], 0, []
    for step in range(refine_steps + 1):
        if step:
            rows = replace(rows, weights=lawson(rows, x, power))
        sol = _solve_once(solves, rows, x, max_iter, step > 0)
        its += sol.iterations
        xp, ok, k = KS.project(rows.eq, sol.x)
        its += k
        h = deployed(xp * scale, standard.topology, centred)["hausdorff_rel"] if ok else np.nan
        trace.append(float(h))
        if ok and _no_fold(standard, xp):
            cands.append((float(h), xp * scale + shift))
            if best is None or h < best[0]:
                best = (h, xp)
        x = best[1] if (best is not None and (FROM_BEST or lawson_route == "from best")) else sol.x
    xb = best[1] if best else xp
    out = _result(standard, target, rows, xb, shift, best is not None, axes, its, tuple(trace))
    return replace(out, candidates=tuple(sorted(cands, key=lambda c: c[0])))


def _solve_once(solves: dict | None, rows: KS.Rows, x: np.ndarray, max_iter: int, warm: bool):
    """``KS.solve(rows, x, ...)``, or the same solve of an earlier design with these rows from ``solves``
    (keyed by the start and the Lawson weights, to the bit): the Lawson routes of one lattice begin with the
    same solve, and "from best" repeats the full route's steps while its last step is the best."""
    if solves is None:
        return KS.solve(rows, x, max_iter=max_iter, warm=warm)
    weights = tuple((k, np.asarray(w).tobytes()) for k, w in sorted(rows.weights.items()))
    key = (x.shape, x.tobytes(), weights, max_iter, warm)
    if key not in solves:
        solves[key] = KS.solve(rows, x, max_iter=max_iter, warm=warm)
    return solves[key]


def _no_fold(standard: Pattern, x: np.ndarray) -> bool:
    """Every deployed gap and tile quality positive (the inequalities' hard core)."""
    return bool(
        _min_gap(standard, x) > 0 and KR.tile_quality(x, standard.topology.tiles)[0].min() > 0
    )


def _min_gap(standard: Pattern, x: np.ndarray) -> float:
    g = [
        np.mod(K.fold_gap_angles(standard, s, x)[0] + KR.GAP_WRAP, 2 * np.pi) - KR.GAP_WRAP
        for s in (1, 2)
    ]
    return float(np.concatenate(g).min())


def _result(standard, target, rows, x, shift, converged, axes, its, trace) -> KagomeDesign:
    scale = standard.tile_size
    r = KS.residuals(rows.eq, x)
    nodes = x * scale + shift
    order = KR.tip_order(standard)
    d = np.abs(target.signed_distance(nodes[order]))
    pattern = replace(
        standard,
        nodes=nodes,
        contracted={},
        name=f"kagome {target.name}",
        design={
            "target": target.to_dict(),
            "symmetry": list(axes),
            "solver": "kagome constrained LM + Lawson + projection",
        },
    )
    return KagomeDesign(
        pattern,
        float(np.abs(r).max()),
        float(d.max()),
        its,
        converged,
        axes,
        float(np.degrees(_min_gap(standard, x))),
        float(KR.tile_quality(x, standard.topology.tiles)[0].min()),
        trace,
    )
