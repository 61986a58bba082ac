"""The flat sheet a tube is cut from, and how its seam is joined.

A tube's pattern stores one seam copy column (:mod:`fabkiri.pattern.kinds.periodic.sheet`); the sheet that is cut
holds every tile once: the copy column is dropped, so the seam hinges (column ``C - 1`` to the copy)
become pairs of free corners at the sheet's two side edges. They are joined after cutting, across
the seam, with the sheet's hinge kind (tape across the seam, or a glued ligament tab). Both corners
of every pair are engraved on the sheet (``S1`` .. ``Sn`` and a tick, :func:`mark_seam`) and the
assembly note ``seam.txt`` lists the pairs by label and tile number.

Before anything is cut the tube itself must close: every closed state's seam a pure translation
(the verifier's seam checks). The flat sheet is then an ordinary planar pattern, cut, read back and
verified by the usual pipeline; its tiles are the tube's tiles, so the read-back proof carries over.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
import shapely

from ...errors import CheckFailed
from ...mechanics.contract import contract
from ...mechanics.tube import tube_state
from ...pattern import geometry
from ...pattern.kinds.periodic.sheet import Seam, flat_sheet, seam_map, seam_of, tube_tiles
from ...pattern.model import Pattern
from ...verify.pattern_checks import tolerances
from ...verify.seam import seam_checks
from ..cut.text import text_strokes

if (
    TYPE_CHECKING
):  # the cutter is loaded where a tube is cut (print reads a planar pattern without it)
    from ..cut.sheets import CutOptions, CutResult

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
        out.append(
            {
                "tile": int(flat[tile]),
                "corner": CORNER[corner],
                "joins_tile": int(flat[first_of[copy]]),
                "joins_corner": CORNER[copy_corner],
            }
        )
    return out


# how the seam's pairs are joined and found: on a cut sheet, and on printed tiles (which carry no marks)
JOINS = {
    "cut": (
        "Join each pair with the sheet's hinge kind across the seam (tape over both corners, or a glued "
        "tab for ligament hinges):",
        "Both corners of each pair are engraved with its label (S1, S2, ...) and a tick.",
    ),
    "print": (
        "Join each pair across the seam with a strip of the hinge material (or tape) over both corners:",
        "Tiles are numbered row by row from the sheet's bottom-left tile (0) as printed; the first and "
        "last column of the print are the seam's two sides.",
    ),
}


def seam_note(
    pattern: Pattern, seam: Seam, state: int, hinges: list[dict], made: str = "cut"
) -> str:
    """The assembly note: which corners to join across the seam, and the tube each state makes
    (``made``: ``cut`` or ``print``, how the pairs are joined and found)."""
    Y = pattern.contracted.get(state, contract(pattern, state).corners)
    m = seam_map(Y, seam)
    done = "cut" if made == "cut" else "printed"
    if seam.closed == "cone":
        ts = tube_state(pattern, seam, Y, state)
        roll = (
            f"Roll the sheet ({done} in closed state {state}) so its left and right edges meet: they close with a "
            f"rotation of {m.rotation:.4f} rad about an apex, so it rolls into a cone of radius "
            f"{ts.radius_min_mm:.3f} to {ts.radius_max_mm:.3f} mm, {ts.length_mm:.3f} mm long."
        )
    else:
        roll = (
            f"Roll the sheet ({done} in closed state {state}) so its left and right edges meet: they close with a "
            f"pure translation of {m.period:.3f} mm (rotation {m.rotation:.1e} rad), the circumference; the "
            f"tube's radius is {m.period / (2 * np.pi):.3f} mm."
        )
    lines = [
        f"Seam of {pattern.name or 'the tube'}: {len(hinges)} hinges join the sheet's right edge to its left "
        f"edge after {'cutting' if made == 'cut' else 'printing'}.",
        roll,
        JOINS[made][0],
    ]
    lines += [
        f"  S{i + 1}: tile {h['tile']} corner {h['corner']}  <->  tile {h['joins_tile']} corner "
        f"{h['joins_corner']}"
        for i, h in enumerate(hinges)
    ]
    lines.append(JOINS[made][1])
    return "\n".join(lines) + "\n"


def tube_cut_inputs(
    pattern: Pattern, state: int, made: str = "cut"
) -> tuple[Pattern, dict[str, bytes], dict]:
    """For a tube: (its flat sheet, extra files, manifest entry); for a flat pattern: itself, nothing.
    ``made``: ``cut`` or ``print`` (the note's words on joining the seam).

    Raises :class:`CheckFailed` when a closed state's seam is not a pure translation (nothing is cut).
    """
    seam = seam_of(pattern)
    if seam is None:
        return pattern, {}, {}
    closed = {s: pattern.contracted.get(s, contract(pattern, s).corners) for s in (1, 2)}
    bad = [c for c in seam_checks(pattern, closed, tolerances(pattern)) if not c.ok]
    if bad:
        raise CheckFailed(
            "the tube does not close across its seam, nothing cut: "
            + "; ".join(f"{c.name} {c.value:.3g} {c.unit} (tol {c.tol:.3g})" for c in bad)
        )
    hinges = seam_hinges(pattern, seam)
    sheet = flat_sheet(pattern.with_contracted(closed), seam)
    note = seam_note(pattern.with_contracted(closed), seam, state, hinges, made)
    entry = {"columns": seam.columns, "rows": len(seam.pairs), "hinges": hinges, "note": "seam.txt"}
    return sheet, {"seam.txt": note.encode()}, entry


def _placed(result: CutResult, tile: int, pts: np.ndarray, scale: float) -> tuple[int, np.ndarray]:
    """Sheet index (0-based) and sheet coordinates of pattern points on ``tile`` (manifest placement)."""
    row = result.manifest["tiles"][tile]
    return int(row["sheet"]) - 1, geometry.rotate(
        pts * scale, float(row["rotation_rad"])
    ) + np.array(row["shift_mm"])


def _region(result: CutResult, tile: int, pts: np.ndarray, scale: float) -> tuple[int, np.ndarray]:
    """Sheet index (0-based) and the tile's region as cut, where its marks must lie: the cut's own
    (a ligament sheet's tiles are inset from their pattern outline to leave the ligaments room), else
    the pattern tile placed as the manifest says."""
    if result.tile_regions is not None and result.tile_sheet is not None:
        return int(result.tile_sheet[tile]), np.asarray(result.tile_regions[tile], dtype=float)
    return _placed(result, tile, pts, scale)


def _corner_mark(poly: np.ndarray, k: int, text: str) -> list[np.ndarray]:
    """Engraved strokes marking corner ``k`` of a placed tile: a tick towards the centre and the seam
    label beside it, shrunk until every stroke lies inside the tile."""
    c = poly.mean(0)
    p = poly[k]
    edge = float(np.linalg.norm(np.roll(poly, -1, 0) - poly, axis=1).min())
    tile = shapely.Polygon(poly).buffer(-0.02 * edge)
    for h in (0.18, 0.12, 0.08):
        strokes = [np.stack([p + 0.12 * (c - p), p + 0.3 * (c - p)])]
        strokes += text_strokes(text, h * edge, p + 0.5 * (c - p))
        if all(tile.contains(shapely.LineString(s)) for s in strokes):
            return strokes
    return strokes[:1] if tile.contains(shapely.LineString(strokes[0])) else []


def mark_seam(
    result: CutResult, hinges: list[dict], sheet: Pattern, state: int, options: CutOptions
) -> None:
    """Engrave both ends of every seam hinge (``S1`` .. ``Sn``, a tick at the corner) on the cut sheets and
    rewrite the sheets' DXF, SVG and PNG bytes and the manifest's engrave figures."""
    from ...exchange.dxf.writer import dxf_bytes
    from ...exchange.svg import svg_bytes
    from ..cut.manifest import PIERCE_S
    from ..cut.preview import png_bytes

    Y = sheet.contracted[state]
    scale = float(result.manifest["scale"])
    before = [(sd.count("ENGRAVE"), sd.length("ENGRAVE")) for sd in result.sheets]
    for i, h in enumerate(hinges):
        for tile, corner in ((h["tile"], h["corner"]), (h["joins_tile"], h["joins_corner"])):
            s, poly = _region(result, tile, Y[tile], scale)
            for stroke in _corner_mark(poly, CORNER.index(corner), f"S{i + 1}"):
                result.sheets[s].add("ENGRAVE", stroke, False, tile)
    colors = options.colors or options.material.colors
    mat = options.material
    for sd, row, (n0, l0) in zip(result.sheets, result.manifest["sheets"], before, strict=True):
        if row.get("dxf"):
            result.files[row["dxf"]] = dxf_bytes(sd, colors)
        if row.get("svg"):
            result.files[row["svg"]] = svg_bytes(sd, colors, options.stroke_mm)
        dn, dl = sd.count("ENGRAVE") - n0, sd.length("ENGRAVE") - l0
        row["engrave_paths"] += dn
        row["engrave_length_mm"] = round(row["engrave_length_mm"] + dl, 3)
        row["cut_time_s"] = round(
            row["cut_time_s"] + dl / mat.engrave_speed_mm_s + PIERCE_S * dn, 1
        )
    if (
        f"{options.stem}.png" in result.files
    ):  # at the preview's resolution: its smallest label readable
        heights = [
            r["label_height_mm"] for r in result.manifest["tiles"] if r.get("label_height_mm")
        ]
        result.files[f"{options.stem}.png"] = png_bytes(
            result.sheets, colors, label_mm=min(heights, default=None)
        )
