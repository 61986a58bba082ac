"""Deployment paths from closed state 1 through the deployed state to closed state 2 (spec §7).

The path parameter ``t`` runs over [0, 1]: ``t = 0`` is closed state 1, ``t = ½``
the deployed (design) state and ``t = 1`` closed state 2. The three states are
Kabsch-aligned (proper rotation, all tile corners) to the deployed state first.

The paths live in their own modules: :mod:`.rigid_path` (rigid-deployable designs, one angle for
every tile), :mod:`.elastic` (every other reconfigurable design: the spring energy minimised with
drivers held) and :mod:`.collisions` (tile overlaps at every frame); :mod:`.path` holds the
:class:`DeploymentPath` they return. This module is the front door, :func:`deployment_path`, and
names the public API of all of them.
"""

from __future__ import annotations

from ..errors import InputError
from ..pattern.model import Pattern
from .collisions import CollisionReport, Overlap, collisions
from .drivers import AUTO, PathDriver, driver_names, path_driver, register_driver
from .elastic import elastic_path, mechanism_split
from .path import MARKS, DeploymentPath, closed_states, is_rigid_deployable
from .rigid_path import place_rigid, rigid_angles, rigid_path

__all__ = [
    "AUTO",
    "MARKS",
    "CollisionReport",
    "DeploymentPath",
    "Overlap",
    "PathDriver",
    "closed_states",
    "collisions",
    "deployment_path",
    "driver_names",
    "elastic_path",
    "is_rigid_deployable",
    "mechanism_split",
    "path_driver",
    "place_rigid",
    "register_driver",
    "rigid_angles",
    "rigid_path",
]


def deployment_path(
    pattern: Pattern,
    steps: int = 40,
    *,
    path: str = "auto",
    driver: str = AUTO,
    collision_tol: float = 1e-9,
) -> DeploymentPath:
    """``path="auto"``: the rigid path if the pattern is rigid-deployable, else the elastic one,
    driven by ``driver`` (``auto``: the default of the pattern's kind, see :mod:`.drivers`)."""
    if path not in ("auto", "rigid", "elastic"):
        raise InputError(f"path must be auto, rigid or elastic, not {path!r}")
    if path == "rigid" or (path == "auto" and is_rigid_deployable(pattern)):
        return rigid_path(pattern, steps, collision_tol=collision_tol)
    return elastic_path(pattern, steps, driver=driver, collision_tol=collision_tol)
