"""What the elastic path prescribes at every ``t``: the registry of path drivers.

A *driver* is a strategy object (:class:`PathDriver`) that says which linear constraints
``A x = b`` hold the nodes at each path parameter ``t`` while the spring energy is minimised
(:mod:`.elastic`), how far they move between two parameters (so the path is sub-stepped finely
enough to follow one branch), and optionally where the minimiser should start and in which order
the parameters are solved. Drivers are found by name (``deploy --driver NAME``); a tessellation
kind names its default (``Tessellation.deploy_driver``: ``rotations`` for quads, whose holes are
parallelograms moving on a checkerboard mechanism; ``homotopy`` for kagome), so a new kind plugs
in by naming a registered driver or registering its own.

Built-in drivers, loaded on first use: ``rotations`` (:mod:`.mechanism`), ``tips`` (here) and
``homotopy`` (:mod:`.homotopy`).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import ClassVar

import numpy as np
from scipy import sparse

from ...errors import InputError
from ...pattern import geometry
from ...pattern.kinds.tessellation import tessellation
from ...pattern.model import Pattern
from ...registry import Registry
from ..path import node_positions, piecewise

AUTO = "auto"  # the pattern's kind chooses (Tessellation.deploy_driver)


@dataclass(frozen=True, eq=False)
class Drivers:
    """Linear driver constraints ``A x = b`` at one ``t`` on the flat node coordinates."""

    name: str
    A: sparse.csr_matrix  # (m, 2n)
    b: np.ndarray  # (m,)


@dataclass(frozen=True, eq=False)
class Plan:
    """A driver's output frames for one pattern, and what it knows before any solve.

    ``guess(t)`` is a closed-form minimiser at ``t`` (flat nodes) or None where it has none;
    ``segments`` are the t-ranges where the path is known to leave a zero-energy mechanism.
    """

    t: np.ndarray
    segments: list[tuple[float, float]] = field(default_factory=list)
    guess: Callable[[float], np.ndarray | None] | None = None


class PathDriver:
    """A path driver: subclass, set ``name`` and ``help``, implement :meth:`values` and
    :meth:`constraints`, then :func:`register_driver` an instance.

    ``solve`` (None here) may be a method ``solve(pattern, springs, states, fine, drivers, plan,
    step_tol, stats) -> (solutions, figures)`` that replaces the default forward continuation of
    :mod:`.elastic`; its figures join the path's ``solver`` summary.
    """

    name: ClassVar[str] = ""
    help: ClassVar[str] = ""
    solve: Callable | None = None
    # a driver whose values are tile angles from the deployed shape may hold the hinge gaps open:
    # the default continuation then adds the contact term of :mod:`.contact` at this weight
    contact_weight: ClassVar[float] = 0.0
    contact_kappa: ClassVar[float] = 0.5  # its clearance, a fraction of the rigid tiles' gap
    # a driver's own ``solve`` may keep every tile convex (:func:`.contact.corner_term`) at this weight
    convex_weight: ClassVar[float] = 0.0
    convex_kappa: ClassVar[float] = 0.5  # its clearance, a fraction of each designed corner angle

    def plan(
        self, pattern: Pattern, states: dict[int, np.ndarray], t: np.ndarray, steps: int
    ) -> Plan:
        """The output frames (``t`` unless the driver adds some) and a closed-form guess."""
        return Plan(t)

    def values(self, pattern: Pattern, states: dict[int, np.ndarray], t: np.ndarray) -> np.ndarray:
        """``(F, m)`` the driven quantities at every ``t``, in radians or tile sizes: their largest
        change between two parameters sets the sub-steps."""
        raise NotImplementedError

    def constraints(
        self, pattern: Pattern, states: dict[int, np.ndarray], t: np.ndarray
    ) -> list[Drivers]:
        """One :class:`Drivers` per ``t``."""
        raise NotImplementedError


_DRIVERS: Registry[PathDriver] = Registry(
    {
        "rotations": "fabkiri.mechanics.drivers.rotations",
        "tips": "fabkiri.mechanics.drivers.registry",
        "homotopy": "fabkiri.mechanics.drivers.homotopy",
    }
)


def register_driver(driver: PathDriver) -> PathDriver:
    """Add a driver to the registry (a driver's module calls this when it is imported)."""
    return _DRIVERS.add(driver.name, driver)


def driver_names() -> tuple[str, ...]:
    """Every known driver name, built-in first."""
    return _DRIVERS.names()


def path_driver(name: str, pattern: Pattern | None = None) -> PathDriver:
    """The driver named ``name`` (``auto``: the default of ``pattern``'s kind); InputError if
    unknown."""
    if name == AUTO:
        if pattern is None:
            raise InputError("the auto driver needs the pattern whose kind chooses it")
        name = tessellation(pattern.kind).deploy_driver
    found = _DRIVERS.find(name)
    if found is None:
        raise InputError(f"driver must be one of {', '.join(driver_names())}, not {name!r}")
    return found


def angle_drivers(
    pattern: Pattern, t: np.ndarray, targets: np.ndarray, centroids: np.ndarray
) -> list[Drivers]:
    """One driver set per ``t``: the Kabsch angle of every tile relative to its deployed shape
    (``targets``, ``(F, T)``) and the centroid of the nodes (``centroids``, ``(F, 2)``).

    In 2D "the Kabsch angle of tile T is θ" is the linear equation ``Σ_k cross(Rot(θ) p_k, x_k)
    = 0`` (``p_k`` its centred deployed corners), so these are ``T + 2`` linear constraints that
    remove every rigid-body mode and pin each state exactly.
    """
    tiles = pattern.tiles
    T, n = len(tiles), len(pattern.nodes)
    deployed = pattern.corners()
    p = deployed - deployed.mean(axis=1, keepdims=True)  # (T, k, 2), k corners per tile
    rows = np.repeat(np.arange(T), 2 * tiles.shape[1])
    cols = np.stack([2 * tiles, 2 * tiles + 1], -1).ravel()  # (T, k, 2) flattened
    cent_rows = np.concatenate([np.full(n, T), np.full(n, T + 1)])
    cent_cols = np.concatenate([2 * np.arange(n), 2 * np.arange(n) + 1])
    out = []
    for theta, c in zip(targets, centroids):
        w = geometry.rotate(p, theta[:, None])  # cross(w, x) = w_x x_y - w_y x_x
        vals = np.stack([-w[..., 1], w[..., 0]], -1).ravel()
        A = sparse.csr_matrix(
            (
                np.concatenate([vals, np.full(2 * n, 1.0 / n)]),
                (np.concatenate([rows, cent_rows]), np.concatenate([cols, cent_cols])),
            ),
            shape=(T + 2, 2 * n),
        )
        out.append(Drivers("rotations", A, np.concatenate([np.zeros(T), c])))
    return out


def node_centroids(pattern: Pattern, states: dict[int, np.ndarray], t: np.ndarray) -> np.ndarray:
    """``(F, 2)`` the node centroid moved linearly between the three states."""
    x = {0: pattern.nodes, **{s: node_positions(pattern, states[s]) for s in (1, 2)}}
    cen = {s: v.mean(axis=0) for s, v in x.items()}
    return np.stack([piecewise(tk, cen[1], cen[0], cen[2]) for tk in np.atleast_1d(t)])


class Tips(PathDriver):
    """The free boundary corners (the tips pulled in an experiment) moved linearly in position.
    Linear tip motion is not the mechanism, so even a rigid design shows E > 0 all along."""

    name = "tips"
    help = "the boundary tips moved linearly"

    def _tips(self, pattern: Pattern, states: dict[int, np.ndarray]):
        free = pattern.topology.free_nodes
        x = {
            0: pattern.nodes[free],
            **{s: node_positions(pattern, states[s])[free] for s in (1, 2)},
        }
        return free, x

    def values(self, pattern, states, t):
        _, x = self._tips(pattern, states)
        return piecewise(t, x[1], x[0], x[2]).reshape(len(t), -1) / pattern.tile_size

    def constraints(self, pattern, states, t):
        free, x = self._tips(pattern, states)
        n = len(pattern.nodes)
        if len(free) < 2:
            raise InputError("the tips driver needs at least two free corners")
        dof = np.stack([2 * free, 2 * free + 1], -1).ravel()
        A = sparse.csr_matrix(
            (np.ones(len(dof)), (np.arange(len(dof)), dof)), shape=(len(dof), 2 * n)
        )
        return [
            Drivers("tips", A, piecewise(tk, x[1], x[0], x[2]).ravel()) for tk in np.atleast_1d(t)
        ]


TIPS = register_driver(Tips())
