"""What a missed shape's message may advise: never an initial guess already tried, and where the outline
cut across a pocket of the target (a reflex corner, a hollow), that instead of a promise.

:func:`annotate` adds to each missed ``report["shape"][k]`` the guesses tried (``tried_inits``) and, for the
deployed outline, the pocket it covers most of (``pocket``, :mod:`fabkiri.design.targets.pockets`) and, where the
outline is a bent strip, the tiles and corners ``make`` would re-split it with (``pocket["strip"]``);
where the miss's tile estimate (``suggested_tiles``) is no remedy, that count and why instead
(``estimate_withheld``): the fabrication rows bind (more tiles at the size are narrower), or the design
refuses that count up front (the room check, a print style's least tile width).
``design.conformance.describe_miss`` words them.
"""

from __future__ import annotations

import numpy as np
import shapely

from ..design.quad.corner_split import bent_strip
from ..design.quad.fabrication import FabricationLimits
from ..design.targets.lookup import Target
from ..design.targets.pockets import pocket_covered, pockets
from ..errors import CheckFailed, InputError
from ..pattern.conformance import boundary_tip_order
from ..pattern.model import Pattern
from .design_strip import STARTS as STRIP_STARTS
from .print_tiles import check_room, check_tiles


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
        _refused_estimate(j, report, target, pattern)
        if k != "deployed" or target is None or pattern is None:
            continue
        top = pattern.topology
        tips = boundary_tip_order(top.tiles, top.hole_nodes, top.hole_tiles, top.free_nodes)
        worst = ((report.get("conformance") or {}).get("deployed") or {}).get("worst") or {}
        found = pocket_covered(target, pattern.nodes[tips], worst.get("at"))
        if found is None and j.get(
            "local_minimum"
        ):  # the deepest pocket, as measured: a likely cause
            _filled(j, target, pattern.nodes[tips])
        if found is not None:
            j["pocket"] = {**found[0].to_dict(), "covered": found[1]}
            lat = pattern.lattice or {}
            rows, cols = int(lat.get("rows", 0)), int(lat.get("cols", 0))
            strip = bent_strip(target, rows, cols) if min(rows, cols) >= 2 else None
            # what make does with these tiles (design/quad/corner_split.py), unless the design tried it
            if strip is not None and not _strip_tried(attempts, strip[1]):
                j["pocket"]["strip"] = {
                    "tiles": list(strip[1]),
                    "corners": strip[0].corner_points().tolist(),
                }


def _strip_tried(attempts: list[dict], tiles) -> bool:
    """Whether one of ``attempts`` was a bent strip (``design_strip.py``) of ``tiles``, either way round."""
    want = sorted(int(n) for n in tiles)
    return any(a["init"] in STRIP_STARTS and sorted(a.get("tiles") or ()) == want for a in attempts)


def _filled(j: dict, target: Target, outline) -> None:
    """``j["pocket_filled"]``: the deepest pocket of ``target`` and the share of it the ``outline``
    polygon fills (where the outline follows the target, none), when it fills some."""
    deepest = next(iter(pockets(target)), None)
    if deepest is None:
        return
    poly = shapely.make_valid(shapely.Polygon(np.asarray(outline, float)))
    share = float(deepest.polygon.intersection(poly).area / deepest.polygon.area)
    if share > 0:
        j["pocket_filled"] = {**deepest.to_dict(), "covered": share}


def _refused_estimate(
    j: dict, report: dict, target: Target | None, pattern: Pattern | None
) -> None:
    """Replace ``j["suggested_tiles"]`` by ``j["estimate_withheld"]`` (that count and why) where the
    design's fabrication rows bind (more tiles at this size are narrower: the estimate assumes the
    lattice's resolution alone) or its up-front checks refuse that count at ``target``'s size."""
    tiles = j.get("suggested_tiles")
    fab = report.get("fabrication") or {}
    if not tiles or not fab.get("limits") or target is None:
        return
    r, c = tiles
    active = sum((fab.get("active") or {}).values())
    why = (
        f"{active} fabrication rows are active (the process's limits bind), and more tiles at this size "
        f"are narrower; the 1/tiles per side estimate assumes the lattice's resolution alone"
        if active
        else _refusal(r, c, FabricationLimits(**fab["limits"]), target, pattern)
    )
    if why:
        j["estimate_withheld"] = {"tiles": [r, c], "why": why}
        del j["suggested_tiles"]


def _refusal(
    r: int, c: int, limits: FabricationLimits, target: Target, pattern: Pattern | None
) -> str | None:
    """Why the design refuses ``r`` x ``c`` tiles up front at ``target``'s size (print_tiles.py), or None."""
    options = ((pattern.design if pattern else None) or {}).get("options") or {}
    intent = options.get("fabrication") or {}
    try:
        check_room(r, c, limits, target)
        check_tiles(r, c, target, intent.get("printer"), intent.get("style"))
    except (InputError, CheckFailed) as exc:
        return f"the {r}x{c} the 1/tiles per side estimate names are refused up front ({exc.cli_message()})"
    return None
