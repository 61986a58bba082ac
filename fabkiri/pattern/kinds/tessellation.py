"""Tessellation kinds: what a pattern's tiles are and how its holes close.

A :class:`Tessellation` is the one place that knows the combinatorics of a kind of kirigami: how
many corners a tile has (its *arity*), how many corners a hole has, which closed states exist, the
fold rule that says which gap closes at every hinge in each state, the names of the boundary sides
a target's arcs are fitted to, and the generator of the kind's standard pattern. The pattern model,
the topology and the contraction read these instead of literal 4s, so a new kind (kagome triangles,
periodic tubes) is one module that calls :func:`register`.

Kinds are looked up by name (``Pattern.kind``, the ``kind`` field of pattern.json). The built-in
kinds are imported on first use, as trimesh loads its file-format handlers: importing this module
costs nothing and cannot form an import cycle with the model.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from ...errors import PatternError
from ...registry import Registry

if TYPE_CHECKING:
    from ..model import Pattern
    from ..topology import FoldRule, Topology

DEFAULT_KIND = "quad"


@dataclass(frozen=True)
class Tessellation:
    """The combinatorial rules of one kind of kirigami tessellation.

    Attributes
    ----------
    kind:
        Registry name, stored in pattern.json (``"quad"`` is the default and is not written).
    arity:
        Corners per tile (4 for rotating squares, 3 for kagome triangles).
    hole_arity:
        Corners per hole: the number of tile edges around one bounded face of the cut.
    states:
        Ids of the closed (contracted) states, the two dual edge correspondences.
    fold_rule:
        ``fold_rule(topology, state) -> FoldRule``: which gap folds at each hinge in ``state``.
    standard:
        ``standard(rows, cols, *, tile_size, angle_deg, name) -> Pattern``: the kind's standard
        deployed pattern in mm.
    boundary_sides:
        Names of the sides of the standard pattern's boundary, in CCW order; a target outline is
        split into one arc per side.
    rigid_family:
        Whether a closed-form rigid-deployable family exists for this kind (``design --rigid``).
    lattice_counts:
        ``lattice_counts(rows, cols) -> (holes, free corners, hinges bordering no hole)`` of the
        standard lattice, which the verifier's topology check compares a pattern that names its
        lattice against.
    hinges_border_holes:
        Whether every hinge of a pattern of this kind must border a hole (true for quads; a kagome
        row may end in a tile hanging on one hinge outside every hole).
    deploy_driver:
        Name of the elastic deployment path's default driver for this kind (a driver registered in
        ``fabkiri.mechanics.drivers.registry``: ``rotations`` follows the quad checkerboard mechanism,
        ``homotopy`` assumes no mechanism).
    """

    kind: str
    arity: int
    hole_arity: int
    states: tuple[int, ...]
    fold_rule: Callable[[Topology, int], FoldRule]
    standard: Callable[..., Pattern]
    boundary_sides: tuple[str, ...]
    rigid_family: bool = False
    lattice_counts: Callable[[int, int], tuple[int, int, int]] | None = None
    hinges_border_holes: bool = True
    deploy_driver: str = "rotations"

    @property
    def tile_noun(self) -> str:
        """What one tile is called in messages: ``quad`` for quads, ``<kind> tile`` otherwise."""
        return "quad" if self.kind == DEFAULT_KIND else f"{self.kind} tile"

    def check_state(self, state: Any) -> int:
        """``state`` as an int, or :class:`ValueError` naming the kind's states."""
        if state not in self.states:
            names = " or ".join(str(s) for s in self.states)
            raise ValueError(f"state must be {names}, not {state!r}")
        return int(state)


# built-in kinds, imported when first asked for (their modules call register())
_KINDS: Registry[Tessellation] = Registry(
    {"quad": "fabkiri.pattern.kinds.quad.rules", "kagome": "fabkiri.pattern.kinds.kagome.lattice"}
)


def register(tessellation: Tessellation) -> Tessellation:
    """Add a kind to the registry (a kind's module calls this when it is imported)."""
    return _KINDS.add(tessellation.kind, tessellation)


def tessellation(kind: str = DEFAULT_KIND) -> Tessellation:
    """The registered :class:`Tessellation` named ``kind``; :class:`PatternError` if unknown."""
    found = _KINDS.find(kind)
    if found is None:
        raise PatternError(f"unknown tessellation kind {kind!r} (known: {', '.join(kinds())})")
    return found


def kinds() -> tuple[str, ...]:
    """Names of every known kind, built-in or registered."""
    return tuple(sorted(_KINDS.names()))


def kind_of_arity(arity: int) -> str | None:
    """The built-in or registered kind whose tiles have ``arity`` corners (a file format that
    stores only faces, such as OBJ, names its kind this way); None if no kind has that arity."""
    for kind in kinds():
        if tessellation(kind).arity == arity:
            return kind
    return None
