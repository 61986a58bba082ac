"""Design residuals (edge pairs, rings, hinge sums) and the rigid deployment path, when claimed."""

from __future__ import annotations

import numpy as np

from ..mechanics.rigid_path import place_rigid, rigid_angles
from ..pattern import geometry
from ..pattern.kinds.tessellation import tessellation
from ..pattern.model import Pattern
from ..pattern.residuals import hinge_sums, state_residuals
from ..pattern.topology import STATES
from . import geom
from .compactness import state_check_id
from .report import Check, measured
from .tolerances import DEFAULT_PATH_STEPS, Tolerances, angle_check, largest, worst_at


def rigid_claimed(pattern: Pattern) -> bool:
    """Whether the pattern claims rigid deployability.

    A design report may say so (``rigid``, ``rigid_deployable`` or
    ``options.rigid``); an undesigned standard lattice is rigid-deployable.
    """
    d = pattern.design or {}
    for src in (d, d.get("options") or {}, d.get("constraints") or {}):
        if isinstance(src, dict):
            for key in ("rigid_deployable", "rigid"):
                if key in src and src[key] is not None:
                    return bool(src[key])
    lat = pattern.lattice or {}
    return not d and lat.get("kind") == "quad"


def _parallelograms(pattern: Pattern, tol: Tolerances) -> tuple[np.ndarray, bool]:
    """Per hole, how far it is from a parallelogram (mm), and whether every hole is a rhombus.

    Parallelogram holes are a quad fact (docs/algorithm.md#parallelogram-holes); other kinds' holes
    get ``inf`` (their fold pairs must be equal).
    """
    top = pattern.topology
    x = pattern.nodes
    quad_holes = top.n_holes and top.hole_nodes.shape[1] == 4
    if not quad_holes:
        return np.full(top.n_holes, np.inf), True
    hole_len = np.linalg.norm(x[np.roll(top.hole_nodes, -1, 1)] - x[top.hole_nodes], axis=-1)
    para = np.maximum(
        np.abs(hole_len[:, 0] - hole_len[:, 2]), np.abs(hole_len[:, 1] - hole_len[:, 3])
    )
    rhombus = bool((para <= tol.length).all()) and bool(
        (np.abs(hole_len - hole_len[:, :1]) <= tol.length).all()
    )
    return para, rhombus


def residual_checks(pattern: Pattern, tol: Tolerances, claimed: bool) -> list[Check]:
    """Edge pairs and rings per closed state; hinge sums when rigid deployability is claimed."""
    top = pattern.topology
    out = []
    para, rhombus = _parallelograms(pattern, tol)
    for s in STATES:
        g = f"state {s}"
        r = state_residuals(pattern, s)
        fold = top.fold(s)
        # a hole's fold pair may differ when the hole is a parallelogram
        # (docs/algorithm.md#parallelogram-holes)
        res = r.edge_pairs.copy()
        gap_face = top.gap_face[np.arange(top.n_hinges), fold.fold_gap]
        in_hole = gap_face >= 0
        res[in_hole] = np.minimum(res[in_hole], para[gap_face[in_hole]])
        detail = "equal fold-pair lengths, or opposite hole sides equal (parallelogram)"
        notch = ~in_hole
        if not rhombus and notch.any() and res[notch].max() > tol.length:
            # with parallelogram holes a notch may close as a T-junction on the
            # outline; whether it closes is the 'folded gaps closed' check
            detail += (
                f"; notch pairs differ by up to {res[notch].max():.3g} mm (T-junctions on the outline, "
                f"not counted)"
            )
            res[notch] = 0.0
        out.append(
            measured(
                f"{g}: edge pairs",
                largest(res),
                tol.length,
                "mm",
                worst=worst_at("hinge", res),
                group="design",
                detail=detail,
                id=state_check_id(s, "edge-pairs"),
            )
        )
        rings = np.abs(r.rings)
        wrapped = r.wrapped_tiles.tolist()
        out.append(
            angle_check(
                f"{g}: rings",
                rings,
                tol.tile_size,
                tol,
                "hole",
                group="design",
                id=state_check_id(s, "rings"),
                detail=f"wrapped by 2π because of tiles {wrapped}" if wrapped else "",
            )
        )
    if not claimed and not tessellation(pattern.kind).rigid_family:
        return out  # θA+θB = π is the quad rigid family's test; nothing to report for other kinds
    hs = np.abs(hinge_sums(pattern))
    out.append(
        angle_check(
            "hinge sums",
            hs,
            tol.tile_size,
            tol,
            "hinge",
            group="design",
            applies=claimed,
            detail="" if claimed else "rigid deployability not claimed; measured for information",
        )
    )
    return out


# ----------------------------------------------------------------- rigid path


def rigid_path(
    pattern: Pattern, Y1: np.ndarray, omegas: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Tile corners along the rigid path from state 1, and hinge mismatch per step.

    The path: docs/algorithm.md#rigid-path.

    Tiles turn by ±ω (checkerboard, sign from the deployed state); translations
    are placed breadth-first so each tree hinge's two copies coincide; the
    mismatch of every hinge is then measured. Returns ``(S, T, 4, 2)`` and ``(S,)``.
    """
    eps, _ = rigid_angles(pattern, {1: Y1})
    corners = place_rigid(pattern, Y1, eps, np.asarray(omegas, dtype=float))
    top = pattern.topology
    A, B = top.hinge_tiles.T
    cA, cB = top.hinge_corner.T
    mismatch = np.linalg.norm(corners[:, A, cA] - corners[:, B, cB], axis=-1).max(
        axis=1, initial=0.0
    )
    return corners, mismatch


def rigid_path_checks(
    pattern: Pattern,
    Y1: np.ndarray,
    Y2: np.ndarray,
    tol: Tolerances,
    steps: int = DEFAULT_PATH_STEPS,
) -> list[Check]:
    omegas = np.linspace(0.0, np.pi / 2, steps + 1)
    corners, mismatch = rigid_path(pattern, Y1, omegas)
    out = [
        measured(
            "rigid path: hinge closure",
            largest(mismatch),
            tol.length,
            "mm",
            worst=f"ω = {np.degrees(omegas[int(np.argmax(mismatch))]):.4g}°",
            group="rigid path",
            detail=f"{len(omegas)} samples of ω on [0, 90°]",
        )
    ]
    is_convex = geom.convex(Y1)
    depth = np.zeros(len(omegas))
    pairs: list[tuple[int, int] | None] = [None] * len(omegas)  # the deepest pair per sample
    for s in range(len(omegas)):
        depth[s], pairs[s] = geom.max_overlap_depth(corners[s], is_convex)
    k = int(np.argmax(depth))
    pk = pairs[k]
    out.append(
        measured(
            "rigid path: no overlap",
            largest(depth),
            tol.length,
            "mm",
            worst=(f"tiles {pk[0]}/{pk[1]} at ω = {np.degrees(omegas[k]):.4g}°" if pk else None),
            group="rigid path",
            detail="largest penetration depth between any two tiles",
        )
    )
    end = geometry.aligned_distance(corners[-1], Y2)
    out.append(
        measured(
            "rigid path: ends in state 2",
            end,
            tol.length * np.sqrt(len(Y1)),
            "mm",
            group="rigid path",
            detail="aligned distance of the ω = 90° frame to state 2",
        )
    )
    return out
