"""The elastic deployment path of a reconfigurable design that is not rigid-deployable (spec §7).


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
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import sparse
from scipy.sparse.linalg import splu, spsolve

from ..errors import InputError
from ..pattern import geometry
from ..pattern.model import Pattern
from .energy import Springs, springs
from .path import (
    DRIVERS,
    DeploymentPath,
    circmean,
    closed_states,
    finish_path,
    node_positions,
    path_parameter,
    piecewise,
    tile_angles,
)
from .rigid_path import place_rigid


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

    The segments are ``t ∈ [0, (1 - closing₁)/2]`` and ``[1 - (1 - closing₂)/2, 1]``;
    they are often a few hundredths of the path, narrower than the regular steps.
    """
    out = []
    for s, m in split.items():
        width = 0.5 * (1.0 - m.closing)
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


def rotation_drivers(
    pattern: Pattern, states: dict[int, np.ndarray], t: np.ndarray
) -> list[Drivers]:
    """One driver set per ``t``: tile rotations (:func:`rotation_targets`) and the node centroid."""
    tiles = pattern.tiles
    T, n = len(tiles), len(pattern.nodes)
    deployed = pattern.corners()
    p = deployed - deployed.mean(axis=1, keepdims=True)  # (T, k, 2), k corners per tile
    targets = rotation_targets(pattern, states, t)
    x = {0: pattern.nodes, **{s: node_positions(pattern, states[s]) for s in (1, 2)}}
    cen = {s: v.mean(axis=0) for s, v in x.items()}
    rows = np.repeat(np.arange(T), 2 * tiles.shape[1])
    cols = np.stack([2 * tiles, 2 * tiles + 1], -1).ravel()  # (T, k, 2) flattened
    cent_rows = np.concatenate([np.full(n, T), np.full(n, T + 1)])
    cent_cols = np.concatenate([2 * np.arange(n), 2 * np.arange(n) + 1])
    out = []
    for tk, theta in zip(np.atleast_1d(t), targets):
        w = geometry.rotate(p, theta[:, None])  # cross(w, x) = w_x x_y - w_y x_x
        vals = np.stack([-w[..., 1], w[..., 0]], -1).ravel()
        A = sparse.csr_matrix(
            (
                np.concatenate([vals, np.full(2 * n, 1.0 / n)]),
                (np.concatenate([rows, cent_rows]), np.concatenate([cols, cent_cols])),
            ),
            shape=(T + 2, 2 * n),
        )
        c = piecewise(tk, cen[1], cen[0], cen[2])
        b = np.concatenate([np.zeros(T), c])
        out.append(Drivers("rotations", A, b))
    return out


def tip_drivers(pattern: Pattern, states: dict[int, np.ndarray], t: np.ndarray) -> list[Drivers]:
    """One driver set per ``t``: the free boundary corners, linearly interpolated."""
    free = pattern.topology.free_nodes
    n = len(pattern.nodes)
    if len(free) < 2:
        raise InputError("the tips driver needs at least two free corners")
    x = {0: pattern.nodes, **{s: node_positions(pattern, states[s]) for s in (1, 2)}}
    dof = np.stack([2 * free, 2 * free + 1], -1).ravel()
    A = sparse.csr_matrix((np.ones(len(dof)), (np.arange(len(dof)), dof)), shape=(len(dof), 2 * n))
    out = []
    for tk in np.atleast_1d(t):
        b = piecewise(tk, x[1][free], x[0][free], x[2][free]).ravel()
        out.append(Drivers("tips", A, b))
    return out


@dataclass
class MinimiseStats:
    iterations: int = 0  # linear solves
    factorizations: int = 0
    rejected: int = 0
    max_iterations_hit: int = 0


def minimise(
    sp: Springs,
    x0: np.ndarray,
    A: sparse.csr_matrix,
    b: np.ndarray,
    *,
    step_tol: float,
    max_iter: int = 60,
    stats: MinimiseStats | None = None,
    zero_energy: float = 1e-26,
) -> np.ndarray:
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
    _project(x, A, b)
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
            lu = _kkt_lu(sp, x, mu, A, At, eye)
            if lu is None:  # exactly singular: shift and retry
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


def _project(x: np.ndarray, A: sparse.csr_matrix, b: np.ndarray) -> None:
    """Move ``x`` (in place) by the least-norm step onto ``A x = b``, if it is off it."""
    r = b - A @ x
    if np.abs(r).max(initial=0.0) > 0:
        x += A.T @ spsolve((A @ A.T).tocsc(), r)


def _kkt_lu(sp: Springs, x: np.ndarray, mu: float, A: sparse.csr_matrix, At: sparse.csr_matrix, eye):
    """Sparse LU of the KKT matrix ``[[H + μI, Aᵀ], [A, 0]]`` at ``x``, or None if it is exactly singular."""
    H = sp.hessian(x)
    if mu:
        H = H + mu * eye
    K = sparse.bmat([[H, At], [A, None]], format="csc")
    try:
        return splu(K)
    except RuntimeError:
        return None


def _driver_increments(
    pattern: Pattern, states: dict[int, np.ndarray], t: np.ndarray, driver: str
) -> np.ndarray:
    """Largest driver change over each interval of ``t``: radians (rotations) or tile sizes (tips)."""
    if driver == "rotations":
        vals = rotation_targets(pattern, states, t)  # (F, T)
    else:
        free = pattern.topology.free_nodes
        x = {
            0: pattern.nodes[free],
            **{s: node_positions(pattern, states[s])[free] for s in (1, 2)},
        }
        vals = piecewise(t, x[1], x[0], x[2]).reshape(len(t), -1) / pattern.tile_size
    return np.abs(np.diff(vals, axis=0)).max(axis=1, initial=0.0)


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
        if lam > m.closing:
            return None
        placed = geometry.rotate(
            place_rigid(pattern, deployed, eps, np.array([lam * m.amplitude]))[0], lam * m.gamma
        )
        x = node_positions(pattern, placed)
        return (x + (piecewise(tk, cen[1], cen[0], cen[2]) - x.mean(0))).ravel()

    return guess


def _fine_grid(pattern: Pattern, states: dict[int, np.ndarray], t: np.ndarray, driver: str,
               max_increment: float) -> tuple[np.ndarray, np.ndarray]:
    """The internal sub-steps (no driver moves more than ``max_increment`` between two) and where
    the output frames ``t`` sit among them."""
    n_sub = np.maximum(
        1, np.ceil(_driver_increments(pattern, states, t, driver) / max_increment)
    ).astype(int)
    fine = np.concatenate(
        [np.linspace(a, b, k, endpoint=False) for a, b, k in zip(t[:-1], t[1:], n_sub)] + [t[-1:]]
    )
    return fine, np.concatenate([[0], np.cumsum(n_sub)])


def _continue(pattern: Pattern, sp: Springs, states: dict[int, np.ndarray], fine: np.ndarray,
              drivers: list[Drivers], mechanism, tol: float, stats: MinimiseStats) -> list[np.ndarray]:
    """The minimiser at every sub-step, each started from the best guess at hand: the mechanism's
    closed form where the drivers are on it, else closed state 1, the last solution or a secant."""
    x1 = node_positions(pattern, states[1]).ravel()
    zero = 1e-24 * sp.n_springs  # rms relative strain 1e-12: rounding level
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
    return sols


def elastic_path(
    pattern: Pattern,
    steps: int = 40,
    *,
    driver: str = "rotations",
    collision_tol: float = 1e-9,
    step_tol: float = 1e-11,
    max_increment: float = 0.03,
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
    fine, keep = _fine_grid(pattern, states, t, driver, max_increment)
    sp = springs(pattern)
    make = rotation_drivers if driver == "rotations" else tip_drivers
    drivers = make(pattern, states, fine)
    stats = MinimiseStats()
    sols = _continue(pattern, sp, states, fine, drivers, mechanism, step_tol * pattern.tile_size, stats)
    nodes = np.stack(sols)[keep].reshape(len(t), -1, 2)
    corners = nodes[:, pattern.tiles]
    solver = {
        "solves": len(fine),
        "linear_solves": stats.iterations,
        "factorizations": stats.factorizations,
        "rejected_steps": stats.rejected,
        "unconverged_steps": stats.max_iterations_hit,
        "step_tol_rel": step_tol,
        "max_increment": max_increment,
    }
    return finish_path(
        pattern,
        "elastic",
        driver,
        t,
        nodes,
        corners,
        sp,
        states,
        collision_tol,
        solver=solver,
        segments=segments,
    )
