"""The rigid deployment path of a rigid-deployable design (docs/algorithm.md#rigid-path).

**Rigid path** (rigid-deployable designs, every hinge sum θ_A + θ_B = π). Every
tile turns rigidly from state 1 by ``ε_T ω``, ``ε_T = ±1`` a checkerboard over
the bipartite tile colouring, with one ω for all tiles:

    Y_T(ω) = Rot(ε_T ω) Y¹_T + τ_T,

the translations ``τ_T`` placed breadth-first so each hinge's two copies meet.
The sign ``ε`` and the deployed angle ω_d come from the tile rotations between
state 1 and the deployed state (their colour classes differ by ``2 ε ω_d``);
"""

from __future__ import annotations

import numpy as np

from ..errors import CheckFailed
from ..pattern import geometry
from ..pattern.kinds.tessellation import tessellation
from ..pattern.model import Pattern
from ..pattern.residuals import hinge_sums
from .energy import springs
from .path import (
    RIGID_TOL_RAD,
    DeploymentPath,
    Frames,
    align,
    circmean,
    closed_states,
    finish_path,
    node_positions,
    path_parameter,
    piecewise,
    tile_angles,
)


def rigid_angles(pattern: Pattern, states: dict[int, np.ndarray]) -> tuple[np.ndarray, float]:
    """``(ε_T, ω_d)``: the rotation sign of every tile and the deployed angle."""
    top = pattern.topology
    color = top.tile_color
    rho = tile_angles(states[1], pattern.corners())
    if not (color == 1).any():  # a single tile: nothing folds
        return np.ones(top.n_tiles), 0.0
    diff = float(geometry.wrap_angle(circmean(rho[color == 0]) - circmean(rho[color == 1])))
    eps0 = 1.0 if diff >= 0 else -1.0
    eps = np.where(color == 0, eps0, -eps0)
    return eps, abs(diff) / 2.0


def place_rigid(
    pattern: Pattern, state1: np.ndarray, eps: np.ndarray, omega: np.ndarray
) -> np.ndarray:
    """Per-tile corners ``(F, T, 4, 2)`` of ``Y_T(ω) = Rot(ε_T ω) Y¹_T + τ_T`` for every ω.

    Translations are found breadth-first from the tile nearest the centre, one
    vectorised step per BFS level over all ω at once.
    """
    top = pattern.topology
    omega = np.atleast_1d(np.asarray(omega, dtype=float))
    phi = omega[:, None] * eps[None, :]  # (F, T)
    centre = state1.mean(axis=1)
    local = state1 - centre.mean(axis=0)
    rotated = geometry.rotate(local[None], phi[:, :, None])  # (F, T, 4, 2)
    T = top.n_tiles
    tau = np.zeros((len(omega), T, 2))
    root = int(np.argmin(np.linalg.norm(centre - centre.mean(0), axis=1)))
    tree = top.spanning_tree(root)
    corner = top.hinge_corner[tree.hinges]
    c_parent = np.where(tree.parent_is_a, corner[:, 0], corner[:, 1])
    c_child = np.where(tree.parent_is_a, corner[:, 1], corner[:, 0])
    for sel in tree.levels():
        p, c = tree.parents[sel], tree.children[sel]
        tau[:, c] = rotated[:, p, c_parent[sel]] + tau[:, p] - rotated[:, c, c_child[sel]]
    return rotated + tau[:, :, None, :] + centre.mean(axis=0)


def rigid_path(
    pattern: Pattern,
    steps: int = 40,
    *,
    tol_rad: float = RIGID_TOL_RAD,
    collision_tol: float = 1e-9,
) -> DeploymentPath:
    """The exact zero-energy path of a rigid-deployable pattern.

    Raises :class:`CheckFailed` if the pattern is not rigid-deployable (hinge
    sums above ``tol_rad``) or does not close in both states.
    """
    if not tessellation(pattern.kind).rigid_family:
        raise CheckFailed(
            f"the rigid path is the quad hinge-sum family's; a {pattern.kind} pattern deploys on the "
            f"elastic path"
        )
    hs = np.abs(hinge_sums(pattern))
    if hs.max(initial=0.0) > tol_rad:
        h = int(np.argmax(hs))
        raise CheckFailed(
            f"the pattern is not rigid-deployable: |θA+θB-π| = {hs[h]:.3e} rad at hinge {h} "
            f"(node {int(pattern.topology.hinge_node[h])}), tolerance {tol_rad:g}; use the elastic path"
        )
    states = closed_states(pattern)
    eps, omega_d = rigid_angles(pattern, states)
    t = path_parameter(steps)
    omega = piecewise(t, 0.0, omega_d, np.pi / 2)
    placed = place_rigid(pattern, states[1], eps, omega)
    deployed = pattern.corners()
    corners = np.stack([align(c, deployed) for c in placed])
    nodes = node_positions(pattern, corners)
    frames = Frames("rigid", None, t, nodes, corners, omega_deployed=omega_d)
    return finish_path(pattern, frames, springs(pattern), states, collision_tol)
