"""The flat sheet a tube is cut from, and how its seam is joined.

A tube's pattern stores one seam copy column (:mod:`fabkiri.pattern.periodic`); the sheet that is cut
holds every tile once: the copy column is dropped, so the seam hinges (column ``C - 1`` to the copy)
become pairs of free corners at the sheet's two side edges. They are joined after cutting, across
the seam, with the sheet's hinge kind (tape across the seam, or a glued ligament tab); the assembly
note ``seam.txt`` lists every pair by the tile numbers printed on the sheet.

Before anything is cut the tube itself must close: every closed state's seam a pure translation
(the verifier's seam checks). The flat sheet is then an ordinary planar pattern, cut, read back and
verified by the usual pipeline; its tiles are the tube's tiles, so the read-back proof carries over.
"""

from __future__ import annotations

import numpy as np

from ..errors import CheckFailed
from ..mechanics.contract import contract
from ..pattern.model import Pattern
from ..pattern.periodic import Seam, flat_sheet, seam_map, seam_of, tube_tiles
from ..verify.pattern_checks import tolerances
from ..verify.seam import seam_checks

CORNER = ("BL", "BR", "TR", "TL")


def seam_hinges(pattern: Pattern, seam: Seam) -> list[dict]:
    """Every seam hinge as the two sheet corners it joins: (tile, corner) of column ``C - 1`` and of the
    first column, in the flat sheet's tile numbers."""
    top = pattern.topology
    flat = np.full(pattern.n_tiles, -1)
    flat[tube_tiles(pattern, seam)] = np.arange(pattern.n_tiles - len(seam.copy))
    first_of = dict(zip(seam.copy.tolist(), seam.first.tolist(), strict=True))
    out = []
    for (a, b), (ca, cb) in zip(top.hinge_tiles.tolist(), top.hinge_corner.tolist(), strict=True):
        if (a in first_of) == (b in first_of):
            continue  # within the sheet, or within the copy column
        tile, corner, copy, copy_corner = (a, ca, b, cb) if b in first_of else (b, cb, a, ca)
        out.append({"tile": int(flat[tile]), "corner": CORNER[corner],
                    "joins_tile": int(flat[first_of[copy]]), "joins_corner": CORNER[copy_corner]})
    return out


def seam_note(pattern: Pattern, seam: Seam, state: int, hinges: list[dict]) -> str:
    """The assembly note: which corners to join across the seam, and the tube each state makes."""
    Y = pattern.contracted.get(state, contract(pattern, state).corners)
    m = seam_map(Y, seam)
    lines = [f"Seam of {pattern.name or 'the tube'}: {len(hinges)} hinges join the sheet's right edge to its left "
             f"edge after cutting.",
             f"Roll the sheet (cut in closed state {state}) so its left and right edges meet: they close with a "
             f"pure translation of {m.period:.3f} mm (rotation {m.rotation:.1e} rad), the circumference; the "
             f"tube's radius is {m.period / (2 * np.pi):.3f} mm.",
             "Join each pair with the sheet's hinge kind across the seam (tape over both corners, or a glued "
             "tab for ligament hinges):"]
    lines += [f"  tile {h['tile']} corner {h['corner']}  <->  tile {h['joins_tile']} corner {h['joins_corner']}"
              for h in hinges]
    return "\n".join(lines) + "\n"


def tube_cut_inputs(pattern: Pattern, state: int) -> tuple[Pattern, dict[str, bytes], dict]:
    """For a tube: (its flat sheet, extra files, manifest entry); for a flat pattern: itself, nothing.

    Raises :class:`CheckFailed` when a closed state's seam is not a pure translation (nothing is cut).
    """
    seam = seam_of(pattern)
    if seam is None:
        return pattern, {}, {}
    closed = {s: pattern.contracted.get(s, contract(pattern, s).corners) for s in (1, 2)}
    bad = [c for c in seam_checks(pattern, closed, tolerances(pattern)) if not c.ok]
    if bad:
        raise CheckFailed("the tube does not close across its seam, nothing cut: "
                          + "; ".join(f"{c.name} {c.value:.3g} {c.unit} (tol {c.tol:.3g})" for c in bad))
    hinges = seam_hinges(pattern, seam)
    sheet = flat_sheet(pattern.with_contracted(closed), seam)
    note = seam_note(pattern.with_contracted(closed), seam, state, hinges)
    entry = {"columns": seam.columns, "rows": len(seam.pairs), "hinges": hinges, "note": "seam.txt"}
    return sheet, {"seam.txt": note.encode()}, entry
