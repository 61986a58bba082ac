"""The places of pinned hinges in a pivot's coaxial stack (see :mod:`.pingeom`).

Hinges that coincide in either closed state need different places: in the printed state they
share a pivot, in the other their ears meet while the print reconfigures. Two places (quads) are
the strip faces; three (kagome, whose coincidences form odd cycles) come from colouring the
coincidence graph of both states.
"""

from __future__ import annotations

import numpy as np

from ...errors import FabricationError
from ...pattern.model import Pattern
from . import geometry as printgeom
from .geometry import ClosedPlan


def pin_slots(pattern: Pattern, plan: ClosedPlan, stack: int) -> np.ndarray:
    """Per hinge, its place in the coaxial stack (0 .. stack-1; ear levels ``2·slot`` and ``2·slot+1``).

    Hinges that coincide in either closed state need different places: in the printed state they
    share a pivot, and in the other their ears meet while the print reconfigures. The strip faces
    (bottom 0, top 1) are such a placing where two meet at a point (quads); where more meet (three
    at a kagome merge corner, an odd cycle) the graph is coloured with ``stack`` places, most
    constrained hinge first (DSATUR) with backtracking."""
    from ..cut.hinges import coincident_pairs, hinge_points

    states = {plan.state: plan.corners}
    if plan.other_state_closes:
        states[3 - plan.state] = printgeom.closed_corners(pattern, 3 - plan.state)
    eps = printgeom.COINCIDE_TOL_REL * pattern.tile_size
    pairs = [coincident_pairs(hinge_points(pattern, c), eps) for c in states.values()]
    pairs_all = np.concatenate(pairs) if pairs else np.zeros((0, 2), np.int64)
    slot = plan.top.astype(np.int64)
    if not len(pairs_all) or (slot[pairs_all[:, 0]] != slot[pairs_all[:, 1]]).all():
        return slot
    H = plan.n_hinges
    nb: list[set[int]] = [set() for _ in range(H)]
    for i, j in pairs_all:
        nb[int(i)].add(int(j))
        nb[int(j)].add(int(i))
    found = _colour(nb, stack)
    if found is None:
        raise FabricationError(
            f"pinned hinges refused: the hinges that coincide in the closed states cannot be stacked in "
            f"{stack} places at a pivot (no colouring of their coincidence graph with {stack} colours found)"
        )
    return found


def _colour(nb: list[set[int]], k: int, budget: int = 100_000) -> np.ndarray | None:
    """A proper colouring of the graph ``nb`` with ``k`` colours (DSATUR order, backtracking up to
    ``budget`` tries), deterministic; ``None`` if none was found."""
    H = len(nb)
    col = np.full(H, -1, dtype=np.int64)
    order: list[int] = []  # the coloured vertices, in order (the backtracking stack)
    tries = 0
    nxt, retry = 0, -1  # the first colour to try, at the vertex to retry (-1: the next in order)
    while len(order) < H:
        tries += 1
        if tries > budget:
            return None
        v = retry if retry >= 0 else _most_saturated(nb, col)
        used = {int(col[u]) for u in nb[v] if col[u] >= 0}
        free = [c for c in range(nxt, k) if c not in used]
        if free:
            col[v] = free[0]
            order.append(v)
            nxt, retry = 0, -1
            continue
        if not order:  # every choice above was tried
            return None
        retry = order.pop()  # back up: the last vertex takes its next colour
        nxt = int(col[retry]) + 1
        col[retry] = -1
    return col


def _most_saturated(nb: list[set[int]], col: np.ndarray) -> int:
    """The uncoloured vertex with the most distinct colours around it (then the most neighbours,
    then the lowest index)."""
    best, key = -1, (-1, -1, 0)
    for v in np.flatnonzero(col < 0).tolist():
        kv = (len({int(col[u]) for u in nb[v] if col[u] >= 0}), len(nb[v]), -v)
        if kv > key:
            best, key = v, kv
    return best
