"""Closedness of one closed state: loop closure, congruent tiles, closed holes and folded gaps.

:func:`closed_state_checks` also runs the compactness checks (:mod:`.compactness`); every check
carries a stable id from :func:`state_check_id`.
"""

from __future__ import annotations

import numpy as np

from ..pattern import geometry
from ..pattern.model import Pattern
from ..pattern.topology import FoldRule
from . import geom
from .compactness import compactness_checks, state_check_id
from .report import Check, measured
from .tolerances import Tolerances, angle_check, largest, worst_at


def _corner_index(tiles: np.ndarray, t: np.ndarray, n: np.ndarray) -> np.ndarray:
    return (tiles[t] == n[..., None]).argmax(axis=-1)


def _hole_outline(pattern: Pattern, Y: np.ndarray) -> np.ndarray:
    """``(K, 2m, 2)``: each hole walked along its ``m`` tile edges, in state ``Y``."""
    top = pattern.topology
    K = top.n_holes
    t = top.hole_tiles  # edge c -> c+1 belongs to hole_tiles[:, c]
    n0 = top.hole_nodes
    n1 = np.roll(top.hole_nodes, -1, axis=1)
    p0 = Y[t, _corner_index(top.tiles, t, n0)]
    p1 = Y[t, _corner_index(top.tiles, t, n1)]
    return np.stack([p0, p1], axis=2).reshape(K, 2 * n0.shape[1], 2)


def closed_state_checks(
    pattern: Pattern,
    Y: np.ndarray,
    state: int | str,
    tol: Tolerances,
    closure: np.ndarray | None = None,
) -> list[Check]:
    """Closedness and compactness of one closed state ``Y`` (T, n, 2)."""
    g = f"state {state}"
    out = []
    if closure is not None:
        out.append(
            measured(
                f"{g}: loop closure",
                largest(closure),
                tol.length,
                "mm",
                worst=worst_at("hole", closure),
                group=g,
                id=state_check_id(state, "loop-closure"),
            )
        )
    out.extend(_congruence_checks(pattern, Y, state, tol, g))
    out.append(_holes_closed(pattern, Y, state, tol, g))
    # every folded gap (hole fold corner or boundary notch) closed
    if isinstance(state, int) or str(state).isdigit():
        fold = pattern.topology.fold(int(state))
        out.append(_folded_gaps(pattern, Y, fold, tol, g, state))
    out.extend(compactness_checks(Y, tol, g, _blame(pattern), state=state))
    return out


def _congruence_checks(
    pattern: Pattern, Y: np.ndarray, state: int | str, tol: Tolerances, g: str
) -> list[Check]:
    """Tiles of ``Y`` congruent with the deployed tiles: edge lengths and rigid fit, then corner angles."""
    X = pattern.corners()
    dl = np.abs(geometry.edge_lengths(Y) - geometry.edge_lengths(X)).max(axis=1)
    da = np.abs(geometry.wrap_angle(geometry.corner_angles(Y) - geometry.corner_angles(X))).max(
        axis=1
    )
    _, fit = geom.tile_kabsch(X, Y)
    mirrored = np.flatnonzero(
        np.sign(geometry.signed_areas(Y)) != np.sign(geometry.signed_areas(X))
    )
    cong = np.maximum(dl, fit)
    cong[mirrored] = np.inf
    return [
        measured(
            f"{g}: tiles congruent (lengths)",
            largest(cong),
            tol.length,
            "mm",
            worst=worst_at("tile", cong),
            group=g,
            detail=f"mirrored tiles {mirrored.tolist()}"
            if len(mirrored)
            else "per-corner edge-length change and per-tile rigid-fit residual",
            id=state_check_id(state, "congruent-lengths"),
        ),
        angle_check(
            f"{g}: tiles congruent (angles)",
            da,
            geometry.edge_lengths(X).mean(axis=1),
            tol,
            "tile",
            group=g,
            id=state_check_id(state, "congruent-angles"),
        ),
    ]


def _holes_closed(
    pattern: Pattern, Y: np.ndarray, state: int | str, tol: Tolerances, g: str
) -> Check:
    """Holes of zero area, measured as an equivalent width 2|A|/perimeter (mm)."""
    if pattern.topology.n_holes:
        outline = _hole_outline(pattern, Y)
        hole_area = np.abs(geometry.signed_areas(outline))
        perim = np.linalg.norm(np.roll(outline, -1, axis=1) - outline, axis=-1).sum(axis=1)
        hole_width = 2 * hole_area / np.maximum(perim, 1e-300)
    else:
        hole_area = hole_width = np.zeros(0)
    return measured(
        f"{g}: holes closed",
        largest(hole_width),
        tol.length,
        "mm",
        worst=worst_at("hole", hole_width),
        group=g,
        detail=f"equivalent width 2|area|/perimeter; largest |area| {largest(hole_area):.3g} mm²",
        id=state_check_id(state, "holes-closed"),
    )


def _blame(pattern: Pattern) -> dict[int, int]:
    """Self-intersecting tiles and the tiles hinged to them -> the crossed tile."""
    crossed = geometry.self_intersecting_tiles(pattern.corners())
    out: dict[int, int] = {}
    for t in crossed.tolist():
        out[t] = t
        ht = pattern.topology.hinge_tiles
        for n in ht[(ht == t).any(1)].ravel().tolist():
            out.setdefault(n, t)
    return out


def _folded_gaps(
    pattern: Pattern, Y: np.ndarray, fold: FoldRule, tol: Tolerances, g: str, state: int | str
) -> Check:
    top = pattern.topology
    A, B = top.hinge_tiles.T
    cA, cB = top.hinge_corner.T
    eA, eB = fold.fold_corner_ends.T
    hA, hB = Y[A, cA], Y[B, cB]
    a, b = Y[A, eA], Y[B, eB]
    split = np.linalg.norm(hA - hB, axis=1)  # the hinge's two copies
    coincide = np.linalg.norm(a - b, axis=1)
    la, lb = np.linalg.norm(a - hA, axis=1), np.linalg.norm(b - hB, axis=1)
    a_short = la <= lb
    short_end = np.where(a_short[:, None], a, b)
    long_h = np.where(a_short[:, None], hB, hA)
    long_end = np.where(a_short[:, None], b, a)
    collinear = geom.point_segment_distance(short_end, long_h, long_end)
    gap = np.maximum(split, np.minimum(coincide, collinear))
    tjunction = int(((coincide > tol.length) & (collinear <= tol.length)).sum())
    kind = (
        f"{tjunction} folded gaps close as T-junctions (parallelogram holes)"
        if tjunction
        else "every folded gap closes with coincident endpoints (rhombus holes)"
    )
    return measured(
        f"{g}: folded gaps closed",
        largest(gap),
        tol.length,
        "mm",
        worst=worst_at("hinge", gap),
        group=g,
        detail=kind,
        id=state_check_id(state, "folded-gaps"),
    )
