"""Deployment paths from closed state 1 through the deployed state to closed state 2.

The method: docs/algorithm.md#deployment.

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
from .drivers.registry import AUTO, PathDriver, driver_names, path_driver, register_driver
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

# drivers tried, in order, when a kind's default driver (``driver="auto"``) finds no clean path
FALLBACKS: dict[str, tuple[str, ...]] = {"rotations": ("homotopy",)}


def deployment_path(
    pattern: Pattern,
    steps: int = 40,
    *,
    path: str = "auto",
    driver: str = AUTO,
    collision_tol: float = 1e-9,
) -> DeploymentPath:
    """``path="auto"``: the rigid path if the pattern is rigid-deployable, else the elastic one,
    driven by ``driver`` (``auto``: the default of the pattern's kind, see :mod:`.drivers`).

    With ``driver="auto"``, when the kind's default driver finds no clean path (tiles overlap or
    cross themselves somewhere) and it has fallbacks (:data:`FALLBACKS`: after ``rotations``,
    ``homotopy``, whose tiles need not follow the checkerboard mechanism), each is tried and the first clean path is kept;
    if none is clean, the default's path is returned with what every driver found in its
    ``solver["drivers_tried"]``, so the report says no driver found a collision-free path."""
    if path not in ("auto", "rigid", "elastic"):
        raise InputError(f"path must be auto, rigid or elastic, not {path!r}")
    if path == "rigid" or (path == "auto" and is_rigid_deployable(pattern)):
        return rigid_path(pattern, steps, collision_tol=collision_tol)
    first = elastic_path(pattern, steps, driver=driver, collision_tol=collision_tol)
    if driver != AUTO or _clean(first):
        return first
    tried = {first.driver: _figures(first)}
    for name in FALLBACKS.get(str(first.driver), ()):
        other = elastic_path(pattern, steps, driver=name, collision_tol=collision_tol)
        tried[name] = _figures(other)
        if _clean(other):
            other.solver["drivers_tried"] = tried
            return other
    first.solver["drivers_tried"] = tried
    return first


def _clean(p: DeploymentPath) -> bool:
    c = p.collisions
    return c.collision_free() and not c.self_intersecting


def _figures(p: DeploymentPath) -> dict:
    """What a driver's path found: its overlaps, the deepest area, bow-tie tiles, largest E."""
    c = p.collisions
    return {
        "overlaps": len(c.overlaps),
        "overlap_max_area_mm2": c.max_area,
        "self_intersecting_tiles": len(c.self_intersecting),
        "energy_max": float(p.energy.max()),
    }
