"""The elastic deployment path of a reconfigurable design that is not rigid-deployable.

The method: docs/algorithm.md#elastic-path.


**Elastic path** (every other reconfigurable design; a reconstruction [R] of the
paper's Fig. 2C, whose SI procedure is unknown). At each ``t`` some *drivers*
are prescribed between the three states and the spring energy of
:mod:`.energy` is minimised over all node coordinates with the drivers held,
warm-started from a linear extrapolation of the previous two steps. Drivers are
strategy objects found by name in :mod:`.drivers` (``auto``: the default of the
pattern's kind); ``rotations`` lives in :mod:`.mechanism`, ``homotopy`` (each
tile's rigid motion interpolated, kagome's default) in :mod:`.homotopy`:

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
  (λ = 1), and the residual enters only once the mechanism is near folding its
  first gap flat (λ > ``leaves``, 0.9 ``closing``), linearly up to the closed
  state (:func:`rotation_targets`), so every gap of the rigidly turned tiles
  stays open until the closed state; the contact term of :mod:`.contact` holds
  the sprung gaps above half of that, and the continuation then runs outward
  from the deployed state on each half. So E = 0 along the mechanism-like middle and
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

from ..pattern.model import Pattern
from .contact import GapTerm, blend_term, contact_figures, hinge_gaps
from .drivers.registry import AUTO, Drivers, PathDriver, path_driver
from .drivers.rotations import (  # noqa: F401  (re-exported: the rotations driver lived here)
    MechanismSplit,
    barrier_frames,
    gap_angles,
    mechanism_split,
    rotation_drivers,
    rotation_targets,
)
from .energy import Springs, WithTerm, springs
from .path import (
    DeploymentPath,
    Frames,
    closed_states,
    finish_path,
    node_positions,
    path_parameter,
)


@dataclass
class MinimiseStats:
    iterations: int = 0  # linear solves
    factorizations: int = 0
    rejected: int = 0
    max_iterations_hit: int = 0


def minimise(
    sp: Springs | WithTerm,
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
            lu = None if step > chord_limit or mu else lu  # chord steps only near convergence
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


def _kkt_lu(
    sp: Springs | WithTerm,
    x: np.ndarray,
    mu: float,
    A: sparse.csr_matrix,
    At: sparse.csr_matrix,
    eye,
):
    """Sparse LU of the KKT matrix ``[[H + μI, Aᵀ], [A, 0]]`` at ``x``, or None if it is exactly singular."""
    H = sp.hessian(x)
    if mu:
        H = H + mu * eye
    K = sparse.bmat([[H, At], [A, None]], format="csc")
    try:
        return splu(K)
    except RuntimeError:
        return None


def _fine_grid(
    pattern: Pattern,
    states: dict[int, np.ndarray],
    t: np.ndarray,
    driver: PathDriver,
    max_increment: float,
) -> tuple[np.ndarray, np.ndarray]:
    """The internal sub-steps (no driver moves more than ``max_increment`` between two) and where
    the output frames ``t`` sit among them."""
    inc = np.abs(np.diff(driver.values(pattern, states, t), axis=0)).max(axis=1, initial=0.0)
    n_sub = np.maximum(1, np.ceil(inc / max_increment)).astype(int)
    fine = np.concatenate(
        [np.linspace(a, b, k, endpoint=False) for a, b, k in zip(t[:-1], t[1:], n_sub)] + [t[-1:]]
    )
    return fine, np.concatenate([[0], np.cumsum(n_sub)])


def _continue(
    pattern: Pattern,
    sp: Springs,
    states: dict[int, np.ndarray],
    fine: np.ndarray,
    drivers: list[Drivers],
    mechanism,
    tol: float,
    stats: MinimiseStats,
    terms: list[GapTerm] | None = None,
) -> list[np.ndarray]:
    """The minimiser at every sub-step, each started from the best guess at hand: the mechanism's
    closed form where the drivers are on it, else the state it starts from, the last solution or a
    secant. Without ``terms`` it runs forward from closed state 1; with them (sub-step ``k``
    minimises the springs plus ``terms[k]``) outward from the deployed frame on each half, as
    a stiff contact term started from a closed state, its gaps folded flat, lands on another branch.
    """
    zero = 1e-24 * sp.n_springs  # rms relative strain 1e-12: rounding level
    sols: list = [None] * len(fine)
    # each closed state is the one zero-energy configuration its drivers allow: the outward
    # continuation's end starts from it, so a branch that strays shows as a jump before it
    ends = {0.0: node_positions(pattern, states[1]).ravel()}
    ends[1.0] = node_positions(pattern, states[2]).ravel()
    if terms is None:
        orders, start = [range(len(fine))], node_positions(pattern, states[1]).ravel()
    else:
        mid = int(np.argmin(np.abs(fine - 0.5)))
        orders, start = [range(mid, -1, -1), range(mid, len(fine))], pattern.nodes.ravel()
    for order in orders:
        prev = prev2 = None
        for k in order:
            exact = mechanism(fine[k]) if mechanism is not None else None
            if sols[k] is not None:  # the deployed frame, shared by both halves
                prev = sols[k]
                continue
            if exact is not None:  # on the mechanism the minimiser is known in closed form
                guess = exact
            elif terms is not None and float(fine[k]) in ends:
                guess = ends[float(fine[k])]
            elif prev is None:
                guess = start
            elif prev2 is None:
                guess = prev
            else:
                guess = 2.0 * prev - prev2  # secant predictor
            drv = drivers[k]
            energy = sp if terms is None else WithTerm(sp, terms[k])
            x = minimise(energy, guess, drv.A, drv.b, step_tol=tol, stats=stats, zero_energy=zero)
            sols[k] = x
            prev2, prev = prev, x
    return sols


def _contact_terms(
    pattern: Pattern, states: dict[int, np.ndarray], fine: np.ndarray, driver: PathDriver
) -> list[GapTerm] | None:
    """The contact term at every sub-step of a driver that asks for one (its values are the tile
    angles, so the rigid gaps are those tiles turned by them), else None."""
    if driver.contact_weight <= 0.0:
        return None
    gaps = hinge_gaps(pattern, states)
    return [
        blend_term(gaps, gaps.turned(th), weight=driver.contact_weight, kappa=driver.contact_kappa)
        for th in driver.values(pattern, states, fine)
    ]


def elastic_path(
    pattern: Pattern,
    steps: int = 40,
    *,
    driver: str = AUTO,
    collision_tol: float = 1e-9,
    step_tol: float = 1e-11,
    max_increment: float = 0.03,
) -> DeploymentPath:
    """The driven quasi-static path (see the module docstring for the drivers).

    ``driver`` names a registered :class:`.drivers.PathDriver`; ``auto`` takes the default of
    the pattern's kind. Between two output frames the drivers advance in internal sub-steps of at
    most ``max_increment`` (radians of tile rotation, or tile sizes of tip motion), so a coarse
    ``steps`` does not make the continuation jump onto another branch. ``step_tol`` (relative to
    the mean tile edge) ends each Newton solve.
    """
    drv = path_driver(driver, pattern)
    states = closed_states(pattern)
    plan = drv.plan(pattern, states, path_parameter(steps), steps)
    t = plan.t
    fine, keep = _fine_grid(pattern, states, t, drv, max_increment)
    sp = springs(pattern)
    drivers = drv.constraints(pattern, states, fine)
    stats = MinimiseStats()
    tol = step_tol * pattern.tile_size
    figures: dict = {}
    if drv.solve is None:
        terms = _contact_terms(pattern, states, fine, drv)
        sols = _continue(pattern, sp, states, fine, drivers, plan.guess, tol, stats, terms)
        if terms is not None:
            figures = contact_figures(terms, sols)
    else:
        sols, figures = drv.solve(pattern, sp, states, fine, drivers, plan, tol, stats)
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
        **figures,
    }
    frames = Frames("elastic", drv.name, t, nodes, corners, solver=solver, segments=plan.segments)
    return finish_path(pattern, frames, sp, states, collision_tol)
