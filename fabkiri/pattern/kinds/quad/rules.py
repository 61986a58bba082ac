"""The quad (rotating-squares) tessellation: its fold rules and its registry entry.

The topology module finds hinges, gaps and holes for any tile arity; what is quad about a quad
kirigami is here: the fold rule of the two closed states (the primal and dual edge
correspondences, docs/algorithm.md#holes-and-fold-rules) and the standard lattice of
:mod:`fabkiri.pattern.kinds.quad.lattice`.
"""

from __future__ import annotations

from ...topology import STATES, FoldRule, Topology
from ..rotating import alternating_fold_rule
from ..tessellation import Tessellation, register
from .lattice import standard_pattern


def quad_fold_rule(top: Topology, state: int) -> FoldRule:
    """Rotating squares: in state 1 every hinge folds the gap on the ``prev`` side of its even tile,
    in state 2 the other gap; every hole then folds at two opposite corners."""
    return alternating_fold_rule(
        top, state, what="rotating-squares quad", fold_at="two opposite corners"
    )


def quad_counts(rows: int, cols: int) -> tuple[int, int, int]:
    """Holes, free corners and hinges bordering no hole of the standard ``rows x cols`` lattice."""
    return (rows - 1) * (cols - 1), 2 * (rows + cols), 0


QUAD = register(
    Tessellation(
        kind="quad",
        arity=4,
        hole_arity=4,
        states=STATES,
        fold_rule=quad_fold_rule,
        standard=standard_pattern,
        boundary_sides=("B", "R", "T", "L"),
        rigid_family=True,
        lattice_counts=quad_counts,
    )
)
