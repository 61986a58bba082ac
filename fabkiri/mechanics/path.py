"""Deployment paths: the result object, the path parameter and what the rigid and elastic paths share.

The path parameter ``t`` runs over [0, 1]: ``t = 0`` is closed state 1, ``t = ½``
the deployed (design) state and ``t = 1`` closed state 2 (:data:`MARKS`).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, NotRequired, TypedDict

import numpy as np

from ..errors import CheckFailed, InputError
from ..pattern import geometry
from ..pattern.kinds.tessellation import tessellation
from ..pattern.lattice_counts import topology_count
from ..pattern.model import Pattern
from ..pattern.residuals import RIGID_TOL_RAD, hinge_sums
from .collisions import CollisionReport, collisions
from .contract import contract_both

CLOSURE_TOL = 1e-9  # relative to the mean tile edge, as in `fabkiri info`
MARKS = {"closed state 1": 0.0, "deployed": 0.5, "closed state 2": 1.0}


class DeployReport(TypedDict):
    """``deploy.json``: a path's figures (:meth:`DeploymentPath.summary`) and what ``fabkiri.api.deploy``
    adds (the deepest overlap, the pattern's fingerprint, a tube's radius along the path); the JSON Schema
    ``fabkiri/api/deploy.schema.json`` states the same."""

    path: str  # "rigid" or "elastic"
    driver: str | None  # the elastic driver, None for the rigid path
    frames: int
    tile_size_mm: float
    energy_max: float
    t_at_energy_max: float
    energy_at_states: dict[str, float]  # by MARKS name
    state_mismatch_mm: dict[str, float]  # by MARKS name
    hinge_gap_max_mm: float
    rotation_spread_max_rad: float
    rotation_end_rad: float
    self_intersecting_tiles: list[int]
    overlaps: int
    overlap_max_area_mm2: float
    overlap_pairs: list[list[int]]
    overlap_frames: list[int]
    collision_free: bool
    collision_free_apart_from_self_intersecting_tiles: bool
    omega_deployed_rad: NotRequired[float]  # the rigid path
    solver: NotRequired[dict[str, Any]]  # an elastic driver's figures
    elastic_segments_t: NotRequired[list[list[float]]]
    energy_outside_segments_max: NotRequired[float]
    overlap_max_depth_mm: NotRequired[float]  # added by the deploy front door
    pattern_fingerprint: NotRequired[dict[str, Any]]  # added by the deploy front door
    tube: NotRequired[dict[str, Any]]  # a periodic pattern's tube along the path


@dataclass(frozen=True, eq=False)
class DeploymentPath:
    """A sampled deployment path and what was measured along it.

    Arrays have one row per frame ``f``; ``corners[f]`` are the per-tile corners
    (for the rigid path each tile is placed by itself; for the elastic path
    they are ``nodes[f][tiles]``).
    """

    kind: str  # "rigid" | "elastic"
    driver: str | None  # elastic driver, None for the rigid path
    t: np.ndarray  # (F,)
    nodes: np.ndarray  # (F, n, 2) mm
    corners: np.ndarray  # (F, T, 4, 2) mm
    energy: np.ndarray  # (F,)
    tile_energy: np.ndarray  # (F, T)
    rotation: np.ndarray  # (F, T) signed rotation from state 1, common rotation removed
    hinge_gap: np.ndarray  # (F,) largest distance between a hinge's two copies, mm
    state_mismatch: dict[str, float]  # aligned distance of the marked frames to the states, mm
    collisions: CollisionReport
    tile_size: float
    omega_deployed: float | None = None  # ω of the deployed state (rigid path)
    solver: dict = field(default_factory=dict)
    elastic_segments: list[tuple[float, float]] = field(
        default_factory=list
    )  # t-ranges off the mechanism

    @property
    def n_frames(self) -> int:
        return len(self.t)

    @property
    def max_tile_energy(self) -> np.ndarray:
        return self.tile_energy.max(axis=1)

    @property
    def centres(self) -> np.ndarray:
        """``(F, T, 2)`` tile centres (trajectories)."""
        return self.corners.mean(axis=2)

    @property
    def rotation_magnitude(self) -> np.ndarray:
        """``(F,)`` mean |rotation| of the tiles from state 1."""
        return np.abs(self.rotation).mean(axis=1)

    @property
    def rotation_spread(self) -> np.ndarray:
        """``(F,)`` max - min of |rotation| over the tiles: 0 for a uniform checkerboard."""
        a = np.abs(self.rotation)
        return a.max(axis=1) - a.min(axis=1)

    def in_segments(self) -> np.ndarray:
        """``(F,)`` whether each frame lies strictly inside an elastic end segment."""
        inside = np.zeros(self.n_frames, dtype=bool)
        for a, b in self.elastic_segments:
            inside |= (self.t > a) & (self.t < b)
        return inside

    def mark_frames(self) -> dict[str, int]:
        return {name: int(np.argmin(np.abs(self.t - t))) for name, t in MARKS.items()}

    def summary(self) -> DeployReport:
        marks = self.mark_frames()
        e = self.energy
        out: DeployReport = {
            "path": self.kind,
            "driver": self.driver,
            "frames": self.n_frames,
            "tile_size_mm": self.tile_size,
            "energy_max": float(e.max()),
            "t_at_energy_max": float(self.t[int(np.argmax(e))]),
            "energy_at_states": {k: float(e[f]) for k, f in marks.items()},
            "state_mismatch_mm": dict(self.state_mismatch),
            "hinge_gap_max_mm": float(self.hinge_gap.max()),
            "rotation_spread_max_rad": float(self.rotation_spread.max()),
            "rotation_end_rad": float(self.rotation_magnitude[-1]),
            "self_intersecting_tiles": list(self.collisions.self_intersecting),
            "overlaps": len(self.collisions.overlaps),
            "overlap_max_area_mm2": self.collisions.max_area,
            "overlap_pairs": [list(p) for p in self.collisions.pairs()],
            "overlap_frames": self.collisions.frames,
            "collision_free": self.collisions.collision_free(),
            "collision_free_apart_from_self_intersecting_tiles": self.collisions.collision_free(
                self.collisions.self_intersecting
            ),
        }
        if self.omega_deployed is not None:
            out["omega_deployed_rad"] = self.omega_deployed
        if self.solver:
            out["solver"] = dict(self.solver)
        if self.elastic_segments:
            out["elastic_segments_t"] = [list(seg) for seg in self.elastic_segments]
            out["energy_outside_segments_max"] = float(
                self.energy[~self.in_segments()].max(initial=0.0)
            )
        return out


def path_parameter(steps: int) -> np.ndarray:
    """``steps + 1`` values of t on [0, 1]; ``steps`` is rounded up to even so
    the deployed state (t = ½) is a frame."""
    if int(steps) != steps or steps < 2:
        raise InputError(f"a path needs at least 2 steps, got {steps}")
    half = (int(steps) + 1) // 2
    return np.linspace(0.0, 1.0, 2 * half + 1)


def piecewise(t: np.ndarray | float, v1, v0, v2):
    """Linear v1 → v0 on [0, ½], v0 → v2 on [½, 1]; broadcasts over trailing axes."""
    t = np.asarray(t, dtype=float)
    shape = t.shape + (1,) * np.ndim(v0)
    s1 = np.clip(2.0 * t, 0.0, 1.0).reshape(shape)
    s2 = np.clip(2.0 * t - 1.0, 0.0, 1.0).reshape(shape)
    return np.where(t.reshape(shape) <= 0.5, (1 - s1) * v1 + s1 * v0, (1 - s2) * v0 + s2 * v2)


def tile_angles(reference: np.ndarray, corners: np.ndarray) -> np.ndarray:
    """Kabsch rotation angle of each tile from ``reference`` to ``corners`` (``(..., T, 4, 2)``)."""
    return geometry.kabsch_angles(reference, corners)


def circmean(a: np.ndarray, axis=-1) -> np.ndarray:
    return np.arctan2(np.sin(a).mean(axis=axis), np.cos(a).mean(axis=axis))


def _split_rotation(rho: np.ndarray, color: np.ndarray) -> np.ndarray:
    """Remove the common rotation from tile rotations ``(F, T)``.

    With ``ρ_T = ε_T ω + γ`` and ε opposite on the two colours, γ is the
    circular midpoint of the two colour means.
    """
    if (color == 1).any():
        m0 = circmean(rho[:, color == 0])
        m1 = circmean(rho[:, color == 1])
        gamma = m1 + 0.5 * geometry.wrap_angle(m0 - m1)
    else:
        gamma = circmean(rho)
    return geometry.wrap_angle(rho - gamma[:, None])


def align(corners: np.ndarray, target: np.ndarray) -> np.ndarray:
    theta, shift = geometry.kabsch(corners, target)
    return geometry.rotate(corners, theta) + shift


def node_positions(pattern: Pattern, corners: np.ndarray) -> np.ndarray:
    """Per-node positions ``(..., n, 2)`` from per-tile corners (first tile wins)."""
    flat_nodes = pattern.tiles.ravel()[::-1]
    out = np.empty(corners.shape[:-3] + (len(pattern.nodes), 2))
    out[..., flat_nodes, :] = corners.reshape(corners.shape[:-3] + (-1, 2))[..., ::-1, :]
    return out


def closed_states(pattern: Pattern, tol: float = CLOSURE_TOL) -> dict[int, np.ndarray]:
    """Per-tile corners of both closed states, Kabsch-aligned to the deployed state.

    Raises :class:`CheckFailed` (with the closure figures) if a state does not close, or if the tiles
    form no lattice (a closed state with a gap: ``verify``'s topology check).
    """
    problem = topology_count(pattern).problem()
    if problem:
        raise CheckFailed(f"{problem}; it has no deployment path")
    both = contract_both(pattern)
    size = pattern.tile_size
    for s, c in both.items():
        if c.max_closure > tol * size:
            raise CheckFailed(
                f"the pattern does not close in state {s} (loop closure {c.max_closure / size:.3g} tile "
                f"sizes at hole {c.worst_hole}, tolerance {tol:g}); it has no deployment path"
            )
    deployed = pattern.corners()
    return {s: align(c.corners, deployed) for s, c in both.items()}


def is_rigid_deployable(pattern: Pattern, tol_rad: float = RIGID_TOL_RAD) -> bool:
    """Whether the pattern is in its kind's closed-form rigid family (quads: hinge sums π)."""
    if not tessellation(pattern.kind).rigid_family:
        return False
    return bool(np.abs(hinge_sums(pattern)).max(initial=0.0) <= tol_rad)


def _hinge_gap(pattern: Pattern, corners: np.ndarray) -> np.ndarray:
    top = pattern.topology
    if top.n_hinges == 0:
        return np.zeros(corners.shape[0])
    A, B = top.hinge_tiles.T
    cA, cB = top.hinge_corner.T
    d = corners[:, A, cA] - corners[:, B, cB]
    return np.hypot(d[..., 0], d[..., 1]).max(axis=1)


@dataclass(frozen=True, eq=False)
class Frames:
    """A sampled path before it is measured: how it was made (``kind``, the elastic ``driver``, the rigid
    path's deployed ω, the solver's figures, the elastic segments) and ``t``, nodes, corners per frame."""

    kind: str
    driver: str | None
    t: np.ndarray
    nodes: np.ndarray
    corners: np.ndarray
    omega_deployed: float | None = None
    solver: dict | None = None
    segments: list | None = None


def finish_path(pattern, frames: Frames, sp, states, collision_tol) -> DeploymentPath:
    """The :class:`DeploymentPath` of ``frames``: energies, rotations, hinge gaps, mismatches, collisions."""
    t, nodes, corners = frames.t, frames.nodes, frames.corners
    top = pattern.topology
    tile_energy = sp.tile_energies(nodes)
    rho = tile_angles(states[1][None], corners)
    marks = {name: int(np.argmin(np.abs(t - tm))) for name, tm in MARKS.items()}
    targets = {
        "closed state 1": states[1],
        "deployed": pattern.corners(),
        "closed state 2": states[2],
    }
    mismatch = {k: geometry.aligned_distance(corners[marks[k]], targets[k]) for k in MARKS}
    return DeploymentPath(
        kind=frames.kind,
        driver=frames.driver,
        t=t,
        nodes=nodes,
        corners=corners,
        energy=tile_energy.sum(axis=1),
        tile_energy=tile_energy,
        rotation=_split_rotation(rho, top.tile_color),
        hinge_gap=_hinge_gap(pattern, corners),
        state_mismatch=mismatch,
        collisions=collisions(corners, pattern.tile_size, collision_tol),
        tile_size=pattern.tile_size,
        omega_deployed=frames.omega_deployed,
        solver=frames.solver or {},
        elastic_segments=frames.segments or [],
    )
