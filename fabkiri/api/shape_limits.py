"""What a missed shape's message may advise: never an initial guess already tried, and where the outline
cut across a pocket of the target (a reflex corner, a hollow), that instead of a promise.

:func:`annotate` adds to each missed ``report["shape"][k]`` the guesses tried (``tried_inits``) and, for the
deployed outline, the pocket it covers most of (``pocket``, :mod:`fabkiri.design.targets.pockets`) and, where the
outline is a bent strip, the tiles and corners ``make`` would re-split it with (``pocket["strip"]``);
``design.conformance.describe_miss`` words them.
"""

from __future__ import annotations

from ..design.quad.corner_split import bent_strip
from ..design.targets.lookup import Target
from ..design.targets.pockets import pocket_covered
from ..pattern.conformance import boundary_tip_order
from ..pattern.model import Pattern


def annotate(
    report: dict, attempts: list[dict], target: Target | None, pattern: Pattern | None = None
) -> None:
    """Add what was tried, and the pocket of ``target`` that the deployed outline of ``pattern`` covers,
    to every missed outline of ``report``."""
    tried = [a["init"] for a in attempts]
    for k, j in (report.get("shape") or {}).items():
        if j.get("status") != "missed":
            continue
        j["tried_inits"] = tried
        if k != "deployed" or target is None or pattern is None:
            continue
        top = pattern.topology
        tips = boundary_tip_order(top.tiles, top.hole_nodes, top.hole_tiles, top.free_nodes)
        worst = ((report.get("conformance") or {}).get("deployed") or {}).get("worst") or {}
        found = pocket_covered(target, pattern.nodes[tips], worst.get("at"))
        if found is not None:
            j["pocket"] = {**found[0].to_dict(), "covered": found[1]}
            lat = pattern.lattice or {}
            rows, cols = int(lat.get("rows", 0)), int(lat.get("cols", 0))
            strip = bent_strip(target, rows, cols) if min(rows, cols) >= 2 else None
            if strip is not None:  # what make does with these tiles (design/quad/corner_split.py)
                j["pocket"]["strip"] = {
                    "tiles": list(strip[1]),
                    "corners": strip[0].corner_points().tolist(),
                }
