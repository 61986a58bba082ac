"""Closed-state measures of a design: its ``--contracted-target`` outlines, tile overlaps and
how closely a contracted state's outline fits its target (mm). :func:`~.design.design_pattern`
runs them on every attempt.
"""

from __future__ import annotations

import re

import numpy as np

from ..design.targets.lookup import Target, load_target
from ..errors import InputError, Param
from ..mechanics.contract import placed_through_hinge
from ..pattern import geometry
from ..pattern.model import Pattern
from ..pattern.overlap import convex, overlap_depths, sat_penetration


def parse_contracted(text: str, size: float | None) -> tuple[int, object]:
    """``STATE:NAME|FILE``, ``STATE:rect`` or ``STATE:rect=RATIO``."""
    m = re.fullmatch(r"\s*([12])\s*:\s*(.+?)\s*", text)
    if not m:
        raise InputError(
            Param("contracted_target"),
            f" expects STATE:NAME|FILE with STATE 1 or 2, got {text!r}",
        )
    state, what = int(m.group(1)), m.group(2)
    r = re.fullmatch(r"rect(?:=(.+))?", what)
    if r:
        ratio = None
        if r.group(1) is not None:
            try:
                ratio = float(r.group(1))
            except ValueError:
                raise InputError(
                    Param("contracted_target", text),
                    f": ratio {r.group(1)!r} is not a number",
                ) from None
            if not (np.isfinite(ratio) and ratio > 0):
                raise InputError(
                    Param("contracted_target", text),
                    ": ratio must be positive",
                )
        return state, ("rect", ratio)
    return state, load_target(what, size)


def overlapping_tiles(
    corners: np.ndarray, tol: float, pattern: Pattern | None = None, state: int | None = None
) -> list[tuple[int, int]]:
    """Pairs of tiles that penetrate each other deeper than ``tol`` (mm).

    The verifier's measure (:func:`fabkiri.pattern.overlap.overlap_depths`): the
    separating-axis penetration depth for convex pairs, intersection area over
    the mean edge otherwise. A length, so it compares with the closure
    tolerance directly; an intersection area does not (a sliver along a shared
    edge of a closed state grows with the edge length, and GEOS snapping adds
    its own: a rigid 64x64 ellipse was rejected for 1.4e-9 mm² slivers whose
    depth was 3.8e-10 tile sizes). A self-intersecting tile is the pair (t, t).
    With ``pattern`` and the closed ``state`` the ``corners`` are of, two convex neighbours found deeper are
    measured again in their own relative pose (``placed_through_hinge``): they touch along the folded gap's
    edges, and the placement's accumulated loop closures alone can read as a depth there.
    """
    crossed = geometry.self_intersecting_tiles(corners)
    valid = np.ones(len(corners), dtype=bool)
    valid[crossed] = False
    out = [(int(t), int(t)) for t in crossed]
    i, j, depth = overlap_depths(corners)
    bad = (depth > tol) & valid[i] & valid[j]
    i, j = i[bad], j[bad]
    if pattern is not None and state is not None and len(i):
        apart = _apart_as_neighbours(pattern, state, i, j, tol)
        i, j = i[~apart], j[~apart]
    return out + list(zip(i.tolist(), j.tolist()))


def _apart_as_neighbours(
    pattern: Pattern, state: int, i: np.ndarray, j: np.ndarray, tol: float
) -> np.ndarray:
    """Which pairs ``(i, j)`` (``i < j``) are convex neighbours that penetrate no deeper than ``tol`` in closed
    state ``state`` with ``j`` placed from ``i`` through their hinge."""
    hinge = np.asarray(pattern.topology.tile_adjacency[i, j]).ravel() - 1  # -1: no hinge between
    x = pattern.corners()
    near = (hinge >= 0) & convex(x[i]) & convex(x[j])
    apart = np.zeros(len(i), dtype=bool)
    if near.any():
        placed = placed_through_hinge(pattern, state, hinge[near], i[near])
        apart[near] = sat_penetration(x[i[near]], placed) <= tol
    return apart


def closed_outline_fit(
    pattern: Pattern, corners: np.ndarray, grid_mm: np.ndarray, target: Target, state: int
) -> dict:
    """Fit of the contracted state's outline (pattern-grid boundary) to its target, in mm.

    The contracted tiles are rigidly aligned (proper Kabsch) to the closed grid
    the solver fitted; the boundary grid vertices are then measured against the
    target arcs.
    """
    from ..design.quad.constraints import ClosedGrid, Stencils

    st = Stencils.from_pattern(pattern)
    g = ClosedGrid.build(st, state, 0)
    V = g.n_vertices
    pos = np.zeros((V, 2))
    cnt = np.zeros(V)
    np.add.at(pos, g.vertex.ravel(), corners.reshape(-1, 2))
    np.add.at(cnt, g.vertex.ravel(), 1.0)
    pos /= cnt[:, None]
    theta, shift = geometry.kabsch(pos, grid_mm)
    pos = geometry.rotate(pos, theta) + shift
    d = target.signed_distance(pos[g.boundary], g.boundary_side)
    return {
        "max_mm": float(np.abs(d).max()),
        "rms_mm": float(np.sqrt(np.mean(d * d))),
        "max_rel_size": float(np.abs(d).max() / target.size),
        "points": int(len(d)),
        "target": target.name,
    }
