"""The lattices next to the one a kagome design chose from the outline, tried when it misses the shape.

A lattice cut to the outline is fitted along Lawson steps whose path turns on the last bits of the target's
points: the heart chosen at 80 mm (7x14 cut to 59 tiles) ends at 3.23 %, the same lattice at 120 mm at
0.92 % (docs/kagome.md, "The lattices next to the chosen one"). Another lattice of the outline's aspect
takes another path, so when the chosen lattice misses, the front door designs the next lattices of the
aspect rule (:func:`fabkiri.design.kagome.trim.blocks_for`) in turn and keeps the first that meets every
check; when none does, the chosen lattice's design. A lattice the user names (``--tiles``) is never
switched: a design on it that misses only names the next lattice in a hint.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from .. import limits as size_limits
from ..design.kagome import aspect as KA
from ..design.kagome import trim as KT
from ..design.targets.curve import Target
from ..errors import InputError

# lattices tried after a chosen one misses, each one design with its own routes (docs/kagome.md: a miss
# of the 80 mm heart then costs its design and one more)
NEXT_LATTICES = 2

Notify = Callable[[str], None] | None


def next_lattices(
    out, design_on: Callable, target: Target, aspect: dict, notify: Notify, i_know: bool = False
):
    """``(outcome, aspect report)``: ``out`` and ``aspect`` when ``out`` meets the shape; else the first
    design on the next ``NEXT_LATTICES`` lattices of the outline (``design_on((rows, cols))``) that meets
    every check, with the aspect report of its lattice, or ``out`` when none does. The report's ``tried``
    lists each lattice designed (tiles, Hausdorff fraction, valid), its ``note`` the last line said."""
    if out.report["shape"]["status"] != "missed":
        return out, aspect
    tried = [_tried(out)]
    blocks = [b for b in KT.blocks_for(target, KA.DEFAULT_TILES) if b != out.tiles]
    for rows, cols in blocks[:NEXT_LATTICES]:
        last = tried[-1]
        _say(
            notify,
            f"kagome {_name(last)} (cut to the outline) missed the shape, Hausdorff "
            f"{100 * last['hausdorff_rel']:.2f} % of the size: designing the next lattice of the outline's "
            f"aspect, {rows}x{cols} (cut to the outline)",
        )
        try:
            size_limits.check_tiles(rows, cols, "design kagome", i_know)
            nxt = design_on((rows, cols))
        except InputError as e:  # refused (too large, no room for the limits): the next one
            _say(notify, f"kagome {rows}x{cols} skipped: {e}")
            continue
        tried.append(_tried(nxt))
        if nxt.valid:
            fit = KA.aspect_fit(rows, cols, target)
            note = f"kagome {rows}x{cols} (cut to the outline) met the shape: kept instead of {_name(tried[0])}"
            _say(notify, note)
            return nxt, {
                **aspect,
                "lattice": fit.lattice,
                "miss": fit.miss,
                "note": note,
                "tried": tried,
            }
    note = (
        f"no lattice next to {_name(tried[0])} met the shape either ("
        + ", ".join(f"{_name(t)} {100 * t['hausdorff_rel']:.2f} %" for t in tried[1:])
        + f"): kept {_name(tried[0])}"
    )
    _say(notify, note)
    return out, {**aspect, "note": note, "tried": tried}


def next_lattice_hint(out, rows: int, cols: int, target: Target) -> str | None:
    """One line naming the lattice next to a cut R x C the user asked for (``--tiles RxC --trim``) when its
    design misses the shape; None when it meets it or no other lattice of about its count suits."""
    if out.report["shape"]["status"] != "missed":
        return None
    other = [f.tiles for f in KA.ranked(target, rows * cols) if f.tiles != (rows, cols)]
    if not other:
        return None
    r, c = other[0]
    return (
        f"hint: the fit of a lattice cut to the outline turns on small differences of lattice and size; "
        f"the next lattice of the outline's aspect may meet the shape: --tiles {r}x{c} --trim"
    )


def _tried(out) -> dict[str, Any]:
    hd = out.report["conformance"]["hausdorff_rel"]
    return {"tiles": list(out.tiles), "hausdorff_rel": hd, "valid": out.valid}


def _name(tried: dict) -> str:
    return "{}x{}".format(*tried["tiles"])


def _say(notify: Notify, text: str) -> None:
    if notify is not None:
        notify(text)
