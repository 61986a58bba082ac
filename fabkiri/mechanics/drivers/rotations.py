"""The ``rotations`` driver: the quad design's own zero-energy mechanism, then its residual.

Every hole of a quad pattern that closes in both states is a parallelogram, so turning the tiles
from the deployed state by a uniform checkerboard ``±α`` keeps every hole closed: a zero-energy
mechanism in which each gap angle changes by ``±2α``. The driver prescribes every tile's rotation
(:func:`.drivers.angle_drivers`): the checkerboard amplitude interpolated linearly, the residual of
each closed state entering only after the mechanism's first gap has folded flat
(:func:`mechanism_split`, :func:`rotation_targets`), so E = 0 along the middle of the path and the
barriers sit in two end segments next to the closed states (see :mod:`.elastic`).

The residual enters a little before that gap folds (:data:`LEAD`): entering exactly there, the gap
would stay folded flat (0 rad) all the way to the closed state, where it is flat again, and the
relaxed springs would push it a few 1e-8 rad (a 16x16 star) or more through zero: hinged tiles
overlapping along the whole segment. Leaving the mechanism earlier, every gap of the rigidly turned
tiles stays open until the closed state, and the contact term of :mod:`.contact`
(:attr:`Rotations.contact_weight`) holds the sprung gaps above a part of it.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ...pattern import geometry
from ...pattern.model import Pattern
from ..path import circmean, node_positions, piecewise, tile_angles
from ..rigid_path import place_rigid
from .registry import Drivers, PathDriver, Plan, angle_drivers, node_centroids, register_driver

LEAD = 0.1  # the residual enters at (1 - LEAD) of the mechanism's travel to its first folded gap


@dataclass(frozen=True)
class MechanismSplit:
    """A closed state's tile rotations relative to the deployed shape, split as
    ``θ_T = γ + ε_T a + d_T``: a common rotation γ, the uniform checkerboard
    amplitude ``a`` (the design's zero-energy mechanism) and a residual ``d_T``
    (zero for rigid-deployable designs). ``closing`` is the fraction of ``a``
    the mechanism can travel from the deployed state before its first gap (a
    hole corner or a boundary notch) folds flat (1 for rigid-deployable designs)."""

    gamma: float
    amplitude: float
    residual: np.ndarray  # (T,)
    closing: float

    @property
    def leaves(self) -> float:
        """λ where the path leaves the mechanism (the residual starts entering): :data:`LEAD` of
        the way before its first gap folds flat, 1 for a rigid-deployable design."""
        return 1.0 if self.closing >= 1.0 - 1e-12 else (1.0 - LEAD) * self.closing


def gap_angles(pattern: Pattern, corners: np.ndarray) -> np.ndarray:
    """``(..., H, 2)`` the two gap angles at every hinge, in [0, 2π), from per-tile corners.

    Gap 0 turns counter-clockwise from A's edge to ``prev_A`` onto B's edge to
    ``next_B``; gap 1 from B's edge to ``prev_B`` onto A's edge to ``next_A``
    (the topology's convention). Holes are interior gaps, notches exterior ones.
    """
    top = pattern.topology
    A, B = top.hinge_tiles.T
    cA, cB = top.hinge_corner.T
    h = corners[..., A, cA, :]
    hb = corners[..., B, cB, :]

    def d(tile, corner, base):
        return corners[..., tile, corner, :] - base

    n = corners.shape[-2]  # corners per tile
    g0 = geometry.signed_angle(d(A, (cA + n - 1) % n, h), d(B, (cB + 1) % n, hb))
    g1 = geometry.signed_angle(d(B, (cB + n - 1) % n, hb), d(A, (cA + 1) % n, h))
    return np.mod(np.stack([g0, g1], -1), geometry.TWO_PI)


def mechanism_split(pattern: Pattern, states: dict[int, np.ndarray]) -> dict[int, MechanismSplit]:
    """Split both closed states' rotations into mechanism and residual (see :class:`MechanismSplit`).

    Every hole of a pattern that closes in both states is a parallelogram, so
    turning the tiles by ``±α`` in a checkerboard from the deployed state keeps
    every hole closed around its loop: a zero-energy mechanism in which every
    gap angle (hole corners and boundary notches) changes by ``±2α``. It ends
    when the first gap angle reaches 0 (beyond, two tiles would overlap).
    """
    top = pattern.topology
    deployed = pattern.corners()
    eps = np.where(top.tile_color == 0, 1.0, -1.0)
    out = {}
    for s in (1, 2):
        th = tile_angles(deployed, states[s])
        if (top.tile_color == 1).any():
            m0, m1 = circmean(th[top.tile_color == 0]), circmean(th[top.tile_color == 1])
            a = float(geometry.wrap_angle(m0 - m1)) / 2
            gamma = float(m1) + a
        else:
            a, gamma = 0.0, float(circmean(th))
        d = geometry.wrap_angle(th - gamma - eps * a)
        closing = 1.0
        if top.n_hinges and a != 0.0:
            # gap angles (holes and boundary notches) are linear in α along the mechanism
            lam = np.array([0.0, 1e-3])
            ang = gap_angles(pattern, place_rigid(pattern, deployed, eps, lam * a))  # (2, H, 2)
            slope = (ang[1] - ang[0]) / lam[1]
            shrinking = slope < 0
            if shrinking.any():
                closing = float(min(1.0, (ang[0][shrinking] / -slope[shrinking]).min()))
        out[s] = MechanismSplit(gamma=gamma, amplitude=a, residual=d, closing=closing)
    return out


def barrier_frames(split: dict[int, MechanismSplit], n: int) -> np.ndarray:
    """Extra path parameters inside the elastic end segments, where the barriers are.

    The segments are ``t ∈ [0, (1 - leaves₁)/2]`` and ``[1 - (1 - leaves₂)/2, 1]``;
    they are often a few hundredths of the path, narrower than the regular steps.
    """
    out = []
    for s, m in split.items():
        width = 0.5 * (1.0 - m.leaves)
        if width <= 1e-9:
            continue
        inner = np.linspace(0.0, width, n + 1)[
            1:
        ]  # up to and including the segment's mechanism end
        out.append(inner if s == 1 else 1.0 - inner)
    return np.concatenate(out) if out else np.zeros(0)


def rotation_targets(pattern: Pattern, states: dict[int, np.ndarray], t: np.ndarray) -> np.ndarray:
    """``(F, T)`` prescribed tile rotations (relative to the deployed shape) along the path.

    On each half, with λ running from 0 (deployed) to 1 (closed state), the
    common rotation and the checkerboard amplitude are interpolated linearly
    (λγ + ε_T λa: the mechanism) and the residual enters as ``r(λ) d_T``, with
    ``r = 0`` while the mechanism can still move freely (λ ≤ leaves, a little before its
    first gap folds) and rising linearly to 1 at the closed state.
    """
    t = np.atleast_1d(np.asarray(t, dtype=float))
    split = mechanism_split(pattern, states)
    eps = np.where(pattern.topology.tile_color == 0, 1.0, -1.0)
    out = np.empty((len(t), pattern.n_tiles))
    for k, tk in enumerate(t):
        s = 1 if tk <= 0.5 else 2
        lam = abs(1.0 - 2.0 * tk)
        m = split[s]
        if m.leaves >= 1.0:
            r = lam
        else:
            r = float(np.clip((lam - m.leaves) / (1.0 - m.leaves), 0.0, 1.0))
        out[k] = lam * (m.gamma + eps * m.amplitude) + r * m.residual
    return out


def _mechanism_guess(
    pattern: Pattern, states: dict[int, np.ndarray], split: dict[int, MechanismSplit]
):
    """``t -> flat nodes`` of the zero-energy mechanism meeting the rotation drivers, or None
    where the drivers have left it (inside the elastic end segments)."""
    deployed = pattern.corners()
    eps = np.where(pattern.topology.tile_color == 0, 1.0, -1.0)
    cen = {
        0: pattern.nodes.mean(0),
        **{s: node_positions(pattern, states[s]).mean(0) for s in (1, 2)},
    }

    def guess(tk: float):
        s = 1 if tk <= 0.5 else 2
        lam = abs(1.0 - 2.0 * tk)
        m = split[s]
        if lam > m.leaves:
            return None
        placed = geometry.rotate(
            place_rigid(pattern, deployed, eps, np.array([lam * m.amplitude]))[0], lam * m.gamma
        )
        x = node_positions(pattern, placed)
        return (x + (piecewise(tk, cen[1], cen[0], cen[2]) - x.mean(0))).ravel()

    return guess


def rotation_drivers(
    pattern: Pattern, states: dict[int, np.ndarray], t: np.ndarray
) -> list[Drivers]:
    """One driver set per ``t``: tile rotations (:func:`rotation_targets`) and the node centroid."""
    t = np.atleast_1d(t)
    return angle_drivers(
        pattern, t, rotation_targets(pattern, states, t), node_centroids(pattern, states, t)
    )


class Rotations(PathDriver):
    """Every tile's rotation, following the design's checkerboard mechanism until it must leave
    it; extra frames inside the two end segments where it does (``max(8, steps // 4)`` each)."""

    name = "rotations"
    help = "every tile's rotation along the design's zero-energy checkerboard mechanism"
    contact_weight = 0.1  # the homotopy's: relative shortfall³ of a gap below its clearance
    contact_kappa = 0.5

    def plan(self, pattern, states, t, steps):
        split = mechanism_split(pattern, states)
        t = np.union1d(t, barrier_frames(split, max(8, int(steps) // 4)))
        w1, w2 = (0.5 * (1.0 - split[s].leaves) for s in (1, 2))
        segments = [seg for seg, w in (((0.0, w1), w1), ((1.0 - w2, 1.0), w2)) if w > 1e-9]
        return Plan(t, segments, _mechanism_guess(pattern, states, split))

    def values(self, pattern, states, t):
        return rotation_targets(pattern, states, t)

    def constraints(self, pattern, states, t):
        return rotation_drivers(pattern, states, t)


ROTATIONS = register_driver(Rotations())
