"""Seam checks of a periodic (tube) pattern: the sheet rolls into a tube in every state.

For a pattern with a seam (:mod:`fabkiri.pattern.kinds.periodic.sheet`) the verifier measures, per state:

* the seam map, first column -> seam copy: a pure translation in each closed state (so the closed
  sheet rolls into a cylinder), a translation (cylinder) or a rigid motion (cone) when deployed;
* no overlaps across the seam: the tube's tiles and their copies moved by the seam translation do not
  overlap, so rolling the sheet (a local isometry, one-to-one on a strip one period wide) overlaps
  nothing in 3D either.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from ..pattern.kinds.periodic.sheet import Seam, seam_map, seam_of, tube_tiles
from ..pattern.model import Pattern
from . import geom
from .report import Check, measured

if TYPE_CHECKING:  # pattern_checks imports this module
    from .pattern_checks import Tolerances


def seam_checks(pattern: Pattern, states: dict[int, np.ndarray], tol: Tolerances) -> list[Check]:
    """Seam checks of the deployed state and every closed state in ``states`` (state -> (T, 4, 2)).

    ``tol`` is the verifier's :class:`~fabkiri.verify.pattern_checks.Tolerances`. A planar pattern
    (no seam) has no seam checks.
    """
    seam = seam_of(pattern)
    if seam is None:
        return []
    out = []
    rows: list[tuple[int | str, np.ndarray]] = [
        ("deployed", pattern.corners()),
        *sorted(states.items()),
    ]
    for s, Y in rows:
        out += _state_checks(pattern, seam, s, Y, tol)
    return out


def _state_checks(
    pattern: Pattern, seam: Seam, s: int | str, Y: np.ndarray, tol: Tolerances
) -> list[Check]:
    g = "deployed" if s == "deployed" else f"state {s}"
    m = seam_map(Y, seam)
    size = tol.tile_size
    figures = (
        f"rotation {m.rotation:.3g} rad, period {m.period:.6g} mm; first column tiles "
        f"{seam.first.tolist()} -> copies {seam.copy.tolist()}"
    )
    if seam.state_kind(s) == "cone":
        out = [
            measured(
                f"{g}: seam is a rigid motion (cone)",
                m.rigid_dev,
                tol.length,
                "mm",
                worst=f"tile {m.worst_tile}",
                group=g,
                detail=f"largest corner distance from the best rigid seam map ({figures})",
            )
        ]
        return out  # a cone's sheet is periodic by a rotation: no translation overlap test
    out = [
        measured(
            f"{g}: seam closes by a pure translation",
            m.translation_dev,
            tol.length,
            "mm",
            worst=f"tile {m.worst_tile}",
            group=g,
            detail=f"largest corner distance from the best translation, "
            f"{m.translation_dev / size:.3g} tile sizes ({figures})",
        )
    ]
    tube = Y[tube_tiles(pattern, seam)]
    t = Y[seam.copy].reshape(-1, 2).mean(0) - Y[seam.first].reshape(-1, 2).mean(0)
    i, j, depth = geom.overlap_depths(np.concatenate([tube, tube + t]))
    n = len(tube)
    across = (i < n) != (j < n)  # pairs within one copy are the planar overlap check
    d = depth[across]
    k = int(np.argmax(d)) if len(d) else None
    worst = (
        None if k is None else f"tiles {int(i[across][k]) % n}/{int(j[across][k]) % n} (tube order)"
    )
    out.append(
        measured(
            f"{g}: no overlaps across the seam",
            float(d.max(initial=0.0)),
            tol.length,
            "mm",
            worst=worst,
            group=g,
            detail="penetration depth between the tube's tiles and their copies one period on",
        )
    )
    return out
