"""Deployment paths from closed state 1 through the deployed state to closed state 2 (spec §7).

The path parameter ``t`` runs over [0, 1]: ``t = 0`` is closed state 1, ``t = ½``
the deployed (design) state and ``t = 1`` closed state 2. The three states are
Kabsch-aligned (proper rotation, all tile corners) to the deployed state first.

**Rigid path** (rigid-deployable designs, every hinge sum θ_A + θ_B = π). Every
tile turns rigidly from state 1 by ``ε_T ω``, ``ε_T = ±1`` a checkerboard over
the bipartite tile colouring, with one ω for all tiles:

    Y_T(ω) = Rot(ε_T ω) Y¹_T + τ_T,

the translations ``τ_T`` placed breadth-first so each hinge's two copies meet.
The sign ``ε`` and the deployed angle ω_d come from the tile rotations between
state 1 and the deployed state (their colour classes differ by ``2 ε ω_d``);
ω runs linearly 0 → ω_d on t ∈ [0, ½] and ω_d → π/2 on [½, 1].

**Elastic path** (every other reconfigurable design; a reconstruction [R] of the
paper's Fig. 2C, whose SI procedure is unknown). At each ``t`` some *drivers*
are prescribed between the three states and the spring energy of
:mod:`.energy` is minimised over all node coordinates with the drivers held,
warm-started from a linear extrapolation of the previous two steps. Drivers:

* ``"rotations"`` (default): the rotation of every tile, measured as the Kabsch
  angle of its corners relative to its deployed shape, plus the centroid of the
  nodes. In 2D "the Kabsch angle of tile T is θ" is the *linear* equation
  ``Σ_k cross(Rot(θ) p_k, x_k) = 0`` (``p_k`` its centred deployed corners),
  so the drivers are ``T + 2`` linear constraints ``A x = b(t)`` that remove
  every rigid-body mode and pin each state exactly.

  What they prescribe follows the design's own mechanics. Every hole of a
  pattern that closes in both states is a parallelogram, so turning the
  tiles from the deployed state by a uniform checkerboard ``±α`` keeps every
  hole closed around its loop: a zero-energy mechanism in which each gap angle
  (hole corner or boundary notch) changes by ``±2α``. Each closed state's tile
  rotations are split into a common rotation, the checkerboard amplitude
  ``a`` and a residual ``d_T`` (:func:`mechanism_split`); the amplitude is
  interpolated linearly from the deployed state (λ = 0) to the closed state
  (λ = 1), and the residual enters only after the mechanism's first gap has
  folded flat (λ > ``closing``), linearly up to the closed state
  (:func:`rotation_targets`). So E = 0 along the mechanism-like middle and
  the tiles deform only in two end segments next to the closed states: the
  barriers of Fig. 2C. A rigid-deployable design has no residual and
  ``closing = 1``: the drivers are then its exact rigid path (E = 0).
  Those end segments are often a few hundredths of the path, so extra frames
  are placed inside them (``max(8, steps // 4)`` each).
* ``"tips"``: the free boundary corners (the tips pulled in an experiment)
  interpolated linearly in position; ``4(M+N)`` linear constraints. Linear tip
  motion is not the mechanism, so even a rigid design shows E > 0 all along.

Prescribing the rotation of every tile linearly from its state-1 value to 0
(the first version) spreads the residual over each whole half and gives one
broad bump per half; prescribing only the mean rotation of each colour class
lets the minimiser follow the mechanism but never leave it, so the path ends
on the mechanism beside closed state 2 (0.2 tile sizes away for the
reference pattern), not in it.

Between two frames the drivers advance in sub-steps of at most
``max_increment`` (0.03 rad or 0.03 tile sizes), so a coarse ``steps`` still
follows the same branch.

The constrained minimisation is a Newton method on the exact sparse Hessian
with the KKT system ``[[H + μI, Aᵀ], [A, 0]]`` (sparse LU), a Levenberg-type
shift ``μ`` raised whenever a step fails to lower E. The constraints are linear,
so feasibility is restored exactly once per step and kept afterwards.

**Collisions**: at every frame, every pair of tiles whose interiors overlap by
more than a small area (``1e-9 · L̄²`` by default) is reported, found with a
GEOS STRtree. Self-intersecting (bow-tie) tiles are made valid first and
listed separately, so a caller can state a verdict with or without them.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy import sparse
from scipy.sparse.linalg import splu, spsolve

from ..errors import CheckFailed, InputError
from ..pattern import geometry
from ..pattern.model import Pattern
from ..pattern.residuals import hinge_sums
from .contract import contract_both
from .energy import Springs, springs

DRIVERS = ("rotations", "tips")
CLOSURE_TOL = 1e-9  # relative to the mean tile edge, as in `fabkiri info`
RIGID_TOL_RAD = 1e-9  # hinge sums below this: rigid-deployable
MARKS = {"closed state 1": 0.0, "deployed": 0.5, "closed state 2": 1.0}


# ----------------------------------------------------------------- results


@dataclass(frozen=True)
class Overlap:
    frame: int
    tile_a: int
    tile_b: int
    area: float  # mm²


@dataclass(frozen=True, eq=False)
class CollisionReport:
    """Tile overlaps at every frame of a path."""

    tol_area: float  # mm², overlaps at or below this are contact, not collision
    self_intersecting: list[int]  # tiles whose outline crosses itself in some frame
    overlaps: list[Overlap]

    def involving(self, tiles) -> list[Overlap]:
        s = set(int(t) for t in tiles)
        return [o for o in self.overlaps if o.tile_a in s or o.tile_b in s]

    def collision_free(self, exclude=()) -> bool:
        """No overlap at any frame, ignoring pairs with a tile in ``exclude``."""
        s = set(int(t) for t in exclude)
        return not any(o.tile_a not in s and o.tile_b not in s for o in self.overlaps)

    @property
    def max_area(self) -> float:
        return max((o.area for o in self.overlaps), default=0.0)

    @property
    def frames(self) -> list[int]:
        return sorted({o.frame for o in self.overlaps})

    def pairs(self) -> list[tuple[int, int]]:
        return sorted({(o.tile_a, o.tile_b) for o in self.overlaps})


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
    elastic_segments: list[tuple[float, float]] = field(default_factory=list)  # t-ranges off the mechanism

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

    def summary(self) -> dict:
        marks = self.mark_frames()
        e = self.energy
        out = {
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
            "collision_free_apart_from_self_intersecting_tiles":
                self.collisions.collision_free(self.collisions.self_intersecting),
        }
        if self.omega_deployed is not None:
            out["omega_deployed_rad"] = self.omega_deployed
        if self.solver:
            out["solver"] = dict(self.solver)
        if self.elastic_segments:
            out["elastic_segments_t"] = [list(seg) for seg in self.elastic_segments]
            out["energy_outside_segments_max"] = float(self.energy[~self.in_segments()].max(initial=0.0))
        return out


# ----------------------------------------------------------------- helpers


def path_parameter(steps: int) -> np.ndarray:
    """``steps + 1`` values of t on [0, 1]; ``steps`` is rounded up to even so
    the deployed state (t = ½) is a frame."""
    if int(steps) != steps or steps < 2:
        raise InputError(f"a path needs at least 2 steps, got {steps}")
    half = (int(steps) + 1) // 2
    return np.linspace(0.0, 1.0, 2 * half + 1)


def _piecewise(t: np.ndarray, v1, v0, v2):
    """Linear v1 → v0 on [0, ½], v0 → v2 on [½, 1]; broadcasts over trailing axes."""
    t = np.asarray(t, dtype=float)
    shape = t.shape + (1,) * np.ndim(v0)
    s1 = np.clip(2.0 * t, 0.0, 1.0).reshape(shape)
    s2 = np.clip(2.0 * t - 1.0, 0.0, 1.0).reshape(shape)
    return np.where(t.reshape(shape) <= 0.5, (1 - s1) * v1 + s1 * v0, (1 - s2) * v0 + s2 * v2)


def tile_angles(reference: np.ndarray, corners: np.ndarray) -> np.ndarray:
    """Kabsch rotation angle of each tile from ``reference`` to ``corners`` (``(..., T, 4, 2)``)."""
    return geometry.kabsch_angles(reference, corners)


def _circmean(a: np.ndarray, axis=-1) -> np.ndarray:
    return np.arctan2(np.sin(a).mean(axis=axis), np.cos(a).mean(axis=axis))


def _split_rotation(rho: np.ndarray, color: np.ndarray) -> np.ndarray:
    """Remove the common rotation from tile rotations ``(F, T)``.

    With ``ρ_T = ε_T ω + γ`` and ε opposite on the two colours, γ is the
    circular midpoint of the two colour means.
    """
    if (color == 1).any():
        m0 = _circmean(rho[:, color == 0])
        m1 = _circmean(rho[:, color == 1])
        gamma = m1 + 0.5 * geometry.wrap_angle(m0 - m1)
    else:
        gamma = _circmean(rho)
    return geometry.wrap_angle(rho - gamma[:, None])


def _align(corners: np.ndarray, target: np.ndarray) -> np.ndarray:
    theta, shift = geometry.kabsch(corners, target)
    return geometry.rotate(corners, theta) + shift


def _node_positions(pattern: Pattern, corners: np.ndarray) -> np.ndarray:
    """Per-node positions ``(..., n, 2)`` from per-tile corners (first tile wins)."""
    flat_nodes = pattern.tiles.ravel()[::-1]
    out = np.empty(corners.shape[:-3] + (len(pattern.nodes), 2))
    out[..., flat_nodes, :] = corners.reshape(corners.shape[:-3] + (-1, 2))[..., ::-1, :]
    return out


def closed_states(pattern: Pattern, tol: float = CLOSURE_TOL) -> dict[int, np.ndarray]:
    """Per-tile corners of both closed states, Kabsch-aligned to the deployed state.

    Raises :class:`CheckFailed` (with the closure figures) if a state does not close.
    """
    both = contract_both(pattern)
    size = pattern.tile_size
    for s, c in both.items():
        if c.max_closure > tol * size:
            raise CheckFailed(
                f"the pattern does not close in state {s} (loop closure {c.max_closure / size:.3g} tile "
                f"sizes at hole {c.worst_hole}, tolerance {tol:g}); it has no deployment path"
            )
    deployed = pattern.corners()
    return {s: _align(c.corners, deployed) for s, c in both.items()}


def is_rigid_deployable(pattern: Pattern, tol_rad: float = RIGID_TOL_RAD) -> bool:
    return bool(np.abs(hinge_sums(pattern)).max(initial=0.0) <= tol_rad)


def _hinge_gap(pattern: Pattern, corners: np.ndarray) -> np.ndarray:
    top = pattern.topology
    if top.n_hinges == 0:
        return np.zeros(corners.shape[0])
    A, B = top.hinge_tiles.T
    cA, cB = top.hinge_corner.T
    d = corners[:, A, cA] - corners[:, B, cB]
    return np.hypot(d[..., 0], d[..., 1]).max(axis=1)


def _finish(pattern, kind, driver, t, nodes, corners, sp, states, collision_tol, omega_dep=None, solver=None,
            segments=None):
    top = pattern.topology
    tile_energy = sp.tile_energies(nodes)
    rho = tile_angles(states[1][None], corners)
    marks = {name: int(np.argmin(np.abs(t - tm))) for name, tm in MARKS.items()}
    targets = {"closed state 1": states[1], "deployed": pattern.corners(), "closed state 2": states[2]}
    mismatch = {k: geometry.aligned_distance(corners[marks[k]], targets[k]) for k in MARKS}
    return DeploymentPath(
        kind=kind,
        driver=driver,
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
        omega_deployed=omega_dep,
        solver=solver or {},
        elastic_segments=segments or [],
    )


# ----------------------------------------------------------------- collisions


def _sat_depth(P: np.ndarray, Q: np.ndarray) -> np.ndarray:
    """Penetration depth of convex quads ``P[i]``, ``Q[i]`` (``(N, 4, 2)``): the least overlap
    of their projections over the 8 edge normals; ≤ 0 means separated or touching."""
    def normals(X):
        e = np.roll(X, -1, axis=1) - X
        return np.stack([-e[..., 1], e[..., 0]], -1) / np.maximum(np.hypot(e[..., 0], e[..., 1]), 1e-300)[..., None]

    axes = np.concatenate([normals(P), normals(Q)], axis=1)  # (N, 8, 2)
    pp = np.einsum("nak,nck->nac", axes, P)
    qq = np.einsum("nak,nck->nac", axes, Q)
    overlap = np.minimum(pp.max(-1), qq.max(-1)) - np.maximum(pp.min(-1), qq.min(-1))
    return overlap.min(axis=1)


def collisions(corners: np.ndarray, tile_size: float, tol: float = 1e-9) -> CollisionReport:
    """Overlapping tile pairs at every frame of ``corners`` ``(F, T, 4, 2)``.

    Two tiles collide when their intersection has an area above
    ``tol · tile_size²`` (contact along an edge or at a hinge has zero area).
    Candidate pairs come from a GEOS STRtree (bounding boxes); convex pairs are
    screened by the separating-axis depth (an overlap of area ``A`` between
    tiles of diameter ``D`` is at least ``A / D`` deep), the rest get a GEOS
    overlay, and positive areas are confirmed with snap rounding on a
    ``1e-11 · tile_size`` grid.
    """
    import shapely

    corners = np.asarray(corners, dtype=float)
    tol_area = tol * tile_size**2
    grid = 1e-11 * tile_size
    overlaps: list[Overlap] = []
    bowties: set[int] = set()
    for f, frame in enumerate(corners):
        polys = shapely.polygons(frame)
        bad = np.flatnonzero(~shapely.is_valid(polys))
        if len(bad):
            bowties.update(int(b) for b in bad)
            polys[bad] = shapely.make_valid(polys[bad])
        convex = _convex(frame)
        convex[bad] = False
        tree = shapely.STRtree(polys)
        a, b = tree.query(polys)  # bounding boxes only
        keep = a < b
        a, b = a[keep], b[keep]
        if not len(a):
            continue
        both = convex[a] & convex[b]
        diam = np.maximum(np.ptp(frame[a], axis=1).max(-1), np.ptp(frame[b], axis=1).max(-1))
        depth = _sat_depth(frame[a[both]], frame[b[both]])
        maybe = ~both
        maybe[np.flatnonzero(both)[depth > 0.5 * tol_area / (2.0 * diam[both])]] = True
        a, b = a[maybe], b[maybe]
        if not len(a):
            continue
        area = shapely.area(shapely.intersection(polys[a], polys[b]))
        # the floating overlay of GEOS can return a whole tile for two tiles sharing an edge up to
        # rounding: confirm every positive with the (slower) snap-rounded overlay, whose area error
        # ~perimeter·grid is far below tol_area
        hit = np.flatnonzero(area > tol_area)
        if len(hit):
            area[hit] = shapely.area(shapely.intersection(polys[a[hit]], polys[b[hit]], grid_size=grid))
        for i in np.flatnonzero(area > tol_area):
            overlaps.append(Overlap(frame=f, tile_a=int(a[i]), tile_b=int(b[i]), area=float(area[i])))
    return CollisionReport(tol_area=tol_area, self_intersecting=sorted(bowties), overlaps=overlaps)


def _convex(corners: np.ndarray) -> np.ndarray:
    """``(T,)`` whether each CCW quad is convex (every turn left)."""
    e = np.roll(corners, -1, axis=-2) - corners
    turn = geometry.cross2(e, np.roll(e, -1, axis=-2))
    return (turn > 0).all(axis=-1)


# ----------------------------------------------------------------- rigid path


def rigid_angles(pattern: Pattern, states: dict[int, np.ndarray]) -> tuple[np.ndarray, float]:
    """``(ε_T, ω_d)``: the rotation sign of every tile and the deployed angle."""
    top = pattern.topology
    color = top.tile_color
    rho = tile_angles(states[1], pattern.corners())
    if not (color == 1).any():  # a single tile: nothing folds
        return np.ones(top.n_tiles), 0.0
    diff = float(geometry.wrap_angle(_circmean(rho[color == 0]) - _circmean(rho[color == 1])))
    eps0 = 1.0 if diff >= 0 else -1.0
    eps = np.where(color == 0, eps0, -eps0)
    return eps, abs(diff) / 2.0


def place_rigid(pattern: Pattern, state1: np.ndarray, eps: np.ndarray, omega: np.ndarray) -> np.ndarray:
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
    pattern: Pattern, steps: int = 40, *, tol_rad: float = RIGID_TOL_RAD, collision_tol: float = 1e-9
) -> DeploymentPath:
    """The exact zero-energy path of a rigid-deployable pattern.

    Raises :class:`CheckFailed` if the pattern is not rigid-deployable (hinge
    sums above ``tol_rad``) or does not close in both states.
    """
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
    omega = _piecewise(t, 0.0, omega_d, np.pi / 2)
    placed = place_rigid(pattern, states[1], eps, omega)
    deployed = pattern.corners()
    corners = np.stack([_align(c, deployed) for c in placed])
    nodes = _node_positions(pattern, corners)
    return _finish(pattern, "rigid", None, t, nodes, corners, springs(pattern), states, collision_tol,
                   omega_dep=omega_d)


# ----------------------------------------------------------------- elastic path


@dataclass(frozen=True, eq=False)
class Drivers:
    """Linear driver constraints ``A x = b`` at one ``t`` on the flat node coordinates."""

    name: str
    A: sparse.csr_matrix  # (m, 2n)
    b: np.ndarray  # (m,)


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

    g0 = geometry.signed_angle(d(A, (cA + 3) % 4, h), d(B, (cB + 1) % 4, hb))
    g1 = geometry.signed_angle(d(B, (cB + 3) % 4, hb), d(A, (cA + 1) % 4, h))
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
            m0, m1 = _circmean(th[top.tile_color == 0]), _circmean(th[top.tile_color == 1])
            a = float(geometry.wrap_angle(m0 - m1)) / 2
            gamma = float(m1) + a
        else:
            a, gamma = 0.0, float(_circmean(th))
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

    The segments are ``t ∈ [0, (1 - closing₁)/2]`` and ``[1 - (1 - closing₂)/2, 1]``;
    they are often a few hundredths of the path, narrower than the regular steps.
    """
    out = []
    for s, m in split.items():
        width = 0.5 * (1.0 - m.closing)
        if width <= 1e-9:
            continue
        inner = np.linspace(0.0, width, n + 1)[1:]  # up to and including the segment's mechanism end
        out.append(inner if s == 1 else 1.0 - inner)
    return np.concatenate(out) if out else np.zeros(0)


def rotation_targets(pattern: Pattern, states: dict[int, np.ndarray], t: np.ndarray) -> np.ndarray:
    """``(F, T)`` prescribed tile rotations (relative to the deployed shape) along the path.

    On each half, with λ running from 0 (deployed) to 1 (closed state), the
    common rotation and the checkerboard amplitude are interpolated linearly
    (λγ + ε_T λa: the mechanism) and the residual enters as ``r(λ) d_T``, with
    ``r = 0`` while the mechanism can still move freely (λ ≤ closing) and
    rising linearly to 1 at the closed state.
    """
    t = np.atleast_1d(np.asarray(t, dtype=float))
    split = mechanism_split(pattern, states)
    eps = np.where(pattern.topology.tile_color == 0, 1.0, -1.0)
    out = np.empty((len(t), pattern.n_tiles))
    for k, tk in enumerate(t):
        s = 1 if tk <= 0.5 else 2
        lam = abs(1.0 - 2.0 * tk)
        m = split[s]
        if m.closing >= 1.0 - 1e-12:
            r = lam
        else:
            r = float(np.clip((lam - m.closing) / (1.0 - m.closing), 0.0, 1.0))
        out[k] = lam * (m.gamma + eps * m.amplitude) + r * m.residual
    return out


def rotation_drivers(pattern: Pattern, states: dict[int, np.ndarray], t: np.ndarray) -> list[Drivers]:
    """One driver set per ``t``: tile rotations (:func:`rotation_targets`) and the node centroid."""
    tiles = pattern.tiles
    T, n = len(tiles), len(pattern.nodes)
    deployed = pattern.corners()
    p = deployed - deployed.mean(axis=1, keepdims=True)  # (T, 4, 2)
    targets = rotation_targets(pattern, states, t)
    x = {0: pattern.nodes, **{s: _node_positions(pattern, states[s]) for s in (1, 2)}}
    cen = {s: v.mean(axis=0) for s, v in x.items()}
    rows = np.repeat(np.arange(T), 8)
    cols = np.stack([2 * tiles, 2 * tiles + 1], -1).ravel()  # (T, 4, 2) flattened
    cent_rows = np.concatenate([np.full(n, T), np.full(n, T + 1)])
    cent_cols = np.concatenate([2 * np.arange(n), 2 * np.arange(n) + 1])
    out = []
    for tk, theta in zip(np.atleast_1d(t), targets):
        w = geometry.rotate(p, theta[:, None])  # cross(w, x) = w_x x_y - w_y x_x
        vals = np.stack([-w[..., 1], w[..., 0]], -1).ravel()
        A = sparse.csr_matrix(
            (np.concatenate([vals, np.full(2 * n, 1.0 / n)]),
             (np.concatenate([rows, cent_rows]), np.concatenate([cols, cent_cols]))),
            shape=(T + 2, 2 * n),
        )
        c = _piecewise(tk, cen[1], cen[0], cen[2])
        b = np.concatenate([np.zeros(T), c])
        out.append(Drivers("rotations", A, b))
    return out


def tip_drivers(pattern: Pattern, states: dict[int, np.ndarray], t: np.ndarray) -> list[Drivers]:
    """One driver set per ``t``: the free boundary corners, linearly interpolated."""
    free = pattern.topology.free_nodes
    n = len(pattern.nodes)
    if len(free) < 2:
        raise InputError("the tips driver needs at least two free corners")
    x = {0: pattern.nodes, **{s: _node_positions(pattern, states[s]) for s in (1, 2)}}
    dof = np.stack([2 * free, 2 * free + 1], -1).ravel()
    A = sparse.csr_matrix((np.ones(len(dof)), (np.arange(len(dof)), dof)), shape=(len(dof), 2 * n))
    out = []
    for tk in np.atleast_1d(t):
        b = _piecewise(tk, x[1][free], x[0][free], x[2][free]).ravel()
        out.append(Drivers("tips", A, b))
    return out


@dataclass
class MinimiseStats:
    iterations: int = 0  # linear solves
    factorizations: int = 0
    rejected: int = 0
    max_iterations_hit: int = 0


def minimise(sp: Springs, x0: np.ndarray, A: sparse.csr_matrix, b: np.ndarray, *, step_tol: float,
             max_iter: int = 60, stats: MinimiseStats | None = None, zero_energy: float = 1e-26) -> np.ndarray:
    """Minimise the spring energy subject to ``A x = b`` from ``x0`` (flat).

    Newton steps on the KKT system ``[[H + μI, Aᵀ], [A, 0]]`` with the exact
    Hessian (sparse LU). A shift ``μ`` is added (and raised tenfold) whenever a
    step does not lower E, and relaxed after successful steps. Once steps are
    small the last factorization is reused (chord steps) while each step
    shrinks at least tenfold, which saves most factorizations near convergence.
    Stops when the largest coordinate change is below ``step_tol`` (mm), or at
    once if the (projected) start already has ``E <= zero_energy``.
    """
    stats = stats if stats is not None else MinimiseStats()
    x = np.asarray(x0, dtype=float).ravel().copy()
    m, n2 = A.shape
    r = b - A @ x
    if np.abs(r).max(initial=0.0) > 0:  # least-norm projection onto the drivers
        x += A.T @ spsolve((A @ A.T).tocsc(), r)
    E = sp.energy(x)
    if E <= zero_energy:  # E >= 0: a feasible point at rounding-level energy is a global minimiser
        return x
    mu = 0.0
    size = float(np.mean(sp.rest))
    scale = 1.0 / size**2
    chord_limit = 1e-2 * size
    At = A.T.tocsr()
    zeros = np.zeros(m)
    eye = sparse.identity(n2, format="csr")
    lu, fresh, last_step = None, False, np.inf
    for _ in range(max_iter):
        g = sp.gradient(x)
        if lu is None:
            H = sp.hessian(x)
            if mu:
                H = H + mu * eye
            K = sparse.bmat([[H, At], [A, None]], format="csc")
            try:
                lu = splu(K)
            except RuntimeError:  # exactly singular: shift and retry
                mu = max(10.0 * mu, 1e-6 * scale)
                stats.rejected += 1
                continue
            fresh = True
            stats.factorizations += 1
        with np.errstate(all="ignore"):
            dx = lu.solve(np.concatenate([-g, zeros]))[:n2]
        stats.iterations += 1
        if not np.isfinite(dx).all():
            if fresh:
                mu = max(10.0 * mu, 1e-6 * scale)
                stats.rejected += 1
            lu = None
            continue
        x_new = x + dx
        E_new = sp.energy(x_new)
        step = float(np.abs(dx).max(initial=0.0))
        lowers = E_new <= E * (1 + 1e-12) + 1e-30
        if lowers and (fresh or step <= 0.1 * last_step):
            x, E = x_new, E_new
            if step <= step_tol:
                return x
            if fresh:
                mu = 0.0 if mu < 1e-6 * scale else 0.1 * mu
            if step > chord_limit or mu:
                lu = None
            fresh, last_step = False, step
        elif fresh:
            stats.rejected += 1
            if step <= step_tol:  # no progress possible at rounding level
                return x
            mu = max(10.0 * mu, 1e-6 * scale)
            lu = None
        else:  # the chord step stalled: refactor at the current point
            lu = None
    stats.max_iterations_hit += 1
    return x


def _driver_increments(pattern: Pattern, states: dict[int, np.ndarray], t: np.ndarray, driver: str) -> np.ndarray:
    """Largest driver change over each interval of ``t``: radians (rotations) or tile sizes (tips)."""
    if driver == "rotations":
        vals = rotation_targets(pattern, states, t)  # (F, T)
    else:
        free = pattern.topology.free_nodes
        x = {0: pattern.nodes[free], **{s: _node_positions(pattern, states[s])[free] for s in (1, 2)}}
        vals = _piecewise(t, x[1], x[0], x[2]).reshape(len(t), -1) / pattern.tile_size
    return np.abs(np.diff(vals, axis=0)).max(axis=1, initial=0.0)


def _mechanism_guess(pattern: Pattern, states: dict[int, np.ndarray], split: dict[int, MechanismSplit]):
    """``t -> flat nodes`` of the zero-energy mechanism meeting the rotation drivers, or None
    where the drivers have left it (inside the elastic end segments)."""
    deployed = pattern.corners()
    eps = np.where(pattern.topology.tile_color == 0, 1.0, -1.0)
    cen = {0: pattern.nodes.mean(0), **{s: _node_positions(pattern, states[s]).mean(0) for s in (1, 2)}}

    def guess(tk: float):
        s = 1 if tk <= 0.5 else 2
        lam = abs(1.0 - 2.0 * tk)
        m = split[s]
        if lam > m.closing:
            return None
        placed = geometry.rotate(place_rigid(pattern, deployed, eps, np.array([lam * m.amplitude]))[0],
                                 lam * m.gamma)
        x = _node_positions(pattern, placed)
        return (x + (_piecewise(tk, cen[1], cen[0], cen[2]) - x.mean(0))).ravel()

    return guess


def elastic_path(
    pattern: Pattern, steps: int = 40, *, driver: str = "rotations", collision_tol: float = 1e-9,
    step_tol: float = 1e-11, max_increment: float = 0.03,
) -> DeploymentPath:
    """The driven quasi-static path (see the module docstring for the drivers).

    Between two output frames the drivers advance in internal sub-steps of at
    most ``max_increment`` (radians of tile rotation, or tile sizes of tip
    motion), so a coarse ``steps`` does not make the continuation jump onto
    another branch. ``step_tol`` (relative to the mean tile edge) ends each
    Newton solve.
    """
    if driver not in DRIVERS:
        raise InputError(f"driver must be one of {', '.join(DRIVERS)}, not {driver!r}")
    states = closed_states(pattern)
    t = path_parameter(steps)
    segments = []
    mechanism = None
    if driver == "rotations":
        split = mechanism_split(pattern, states)
        t = np.union1d(t, barrier_frames(split, max(8, int(steps) // 4)))
        w1, w2 = (0.5 * (1.0 - split[s].closing) for s in (1, 2))
        segments = [seg for seg, w in (((0.0, w1), w1), ((1.0 - w2, 1.0), w2)) if w > 1e-9]
        mechanism = _mechanism_guess(pattern, states, split)
    n_sub = np.maximum(1, np.ceil(_driver_increments(pattern, states, t, driver) / max_increment)).astype(int)
    fine = np.concatenate([np.linspace(a, b, k, endpoint=False) for a, b, k in zip(t[:-1], t[1:], n_sub)] + [t[-1:]])
    keep = np.concatenate([[0], np.cumsum(n_sub)])  # output frames within the fine grid
    sp = springs(pattern)
    make = rotation_drivers if driver == "rotations" else tip_drivers
    drivers = make(pattern, states, fine)
    x1 = _node_positions(pattern, states[1]).ravel()
    tol = step_tol * pattern.tile_size
    zero = 1e-24 * sp.n_springs  # rms relative strain 1e-12: rounding level
    stats = MinimiseStats()
    sols = []
    prev = prev2 = None
    for tk, drv in zip(fine, drivers):
        exact = mechanism(tk) if mechanism is not None else None
        if exact is not None:  # on the mechanism the minimiser is known in closed form
            guess = exact
        elif prev is None:
            guess = x1
        elif prev2 is None:
            guess = prev
        else:
            guess = 2.0 * prev - prev2  # secant predictor
        x = minimise(sp, guess, drv.A, drv.b, step_tol=tol, stats=stats, zero_energy=zero)
        sols.append(x)
        prev2, prev = prev, x
    nodes = np.stack(sols)[keep].reshape(len(t), -1, 2)
    corners = nodes[:, pattern.tiles]
    solver = {"solves": len(fine), "linear_solves": stats.iterations, "factorizations": stats.factorizations,
              "rejected_steps": stats.rejected, "unconverged_steps": stats.max_iterations_hit,
              "step_tol_rel": step_tol, "max_increment": max_increment}
    return _finish(pattern, "elastic", driver, t, nodes, corners, sp, states, collision_tol, solver=solver,
                   segments=segments)


def deployment_path(pattern: Pattern, steps: int = 40, *, path: str = "auto", driver: str = "rotations",
                    collision_tol: float = 1e-9) -> DeploymentPath:
    """``path="auto"``: the rigid path if the pattern is rigid-deployable, else the elastic one."""
    if path not in ("auto", "rigid", "elastic"):
        raise InputError(f"path must be auto, rigid or elastic, not {path!r}")
    if path == "rigid" or (path == "auto" and is_rigid_deployable(pattern)):
        return rigid_path(pattern, steps, collision_tol=collision_tol)
    return elastic_path(pattern, steps, driver=driver, collision_tol=collision_tol)
