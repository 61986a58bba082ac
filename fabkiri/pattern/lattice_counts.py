"""Whether a pattern's tiles form a kirigami lattice: one hole per independent cycle of the tile graph,
every hinge a corner of a hole (or as many hole-less hinges as the kind's lattice has), and, when the
pattern names its lattice, that lattice's counts of holes and free corners.

One rule for every reader: ``verify`` reports it as its topology check, ``info`` as a problem and the
deployment path refuses a pattern that fails it (a tile removed by hand leaves a ring of 8 tiles that
is no hole, and a closed state with a gap in it).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .kinds.tessellation import tessellation
from .model import Pattern


@dataclass(frozen=True)
class TopologyCount:
    """How far the counts are off (``bad`` 0: a lattice), the counts in words, and the hinges that
    border no hole."""

    bad: int
    detail: str
    orphan: np.ndarray

    def problem(self) -> str | None:
        """One sentence when the tiles form no lattice, else None."""
        if not self.bad:
            return None
        return f"the tiles form no kirigami lattice: {self.detail}"


def topology_count(pattern: Pattern) -> TopologyCount:
    """Count the pattern's holes, free corners and hole-less hinges against what its lattice needs
    (topology in docs/algorithm.md#verifier-checks)."""
    top = pattern.topology
    tess = tessellation(pattern.kind)
    T, H, K = top.n_tiles, top.n_hinges, top.n_holes
    expected = H - T + 1
    holes_per_hinge = (top.gap_face >= 0).sum(axis=1)
    orphan = np.flatnonzero(holes_per_hinge == 0) if K else np.zeros(0, dtype=np.int64)
    bad = abs(K - expected)
    lat = pattern.lattice or {}
    detail = (
        f"{T} tiles, {H} hinges, {len(top.free_nodes)} free corners, {K} holes (cycles: {expected})"
    )
    counts = tess.lattice_counts
    if lat.get("rows") and lat.get("cols") and counts is not None:
        m, n = int(lat["rows"]), int(lat["cols"])
        holes, free, holeless = counts(m, n)
        bad += abs(K - holes) + abs(len(top.free_nodes) - free)
        # a lattice without holes (a 2x2 kagome, a quad strip): no hinge borders one
        bad += abs(len(orphan) - holeless) if K else 0
        detail += f"; a {m}x{n} lattice expects {holes} holes and {free} free corners"
        if holeless:
            detail += f" and {holeless} hinges bordering no hole"
    elif tess.hinges_border_holes:
        bad += len(orphan)
    if len(orphan):
        detail += f"; hinges bordering no hole: {orphan[:10].tolist()}"
    return TopologyCount(int(bad), detail, orphan)
