"""``fabkiri print --style strips --marks``: the laser files for the tiles, with
the outline of every printed strip's pads engraved where it is to be glued.

The tiles are cut in place with the laser-cut pipeline
(:func:`fabkiri.fabricate.cut.sheets.cut_pattern`, tape layout: the strips replace
the tape), then each pad outline is moved onto its tile on the sheet by the
tile's rigid motion and added to the ``ENGRAVE`` layer, kept ``margin`` inside
the tile like every other mark, and the sheets are rendered again. The usual
read-back checks and the layout verifier then run on the final bytes.
"""

from __future__ import annotations

import numpy as np
import shapely

from ...exchange.dxf.writer import dxf_bytes
from ...exchange.svg import svg_bytes
from ...pattern import geometry
from ...pattern.model import Pattern
from ..cut.materials import Material
from ..cut.preview import png_bytes
from ..cut.sheets import CutOptions, CutResult, cut_pattern
from .geometry import Strips


def marked_cut(
    pattern: Pattern,
    state: int,
    strips: Strips,
    corners: np.ndarray,
    material: Material,
    stem: str,
    pattern_file: str,
) -> tuple[CutResult, int]:
    """Tape-style cut files with pad outlines engraved; returns the result and the number of marks."""
    colors = material.colors
    opts = CutOptions(
        material=material,
        hinge="tape",
        state=state,
        stem=stem,
        pattern_file=pattern_file,
        colors=colors,
    )
    res = cut_pattern(pattern, opts)
    Q = res.tile_regions  # placed tile corners on the sheets (tape: the tiles themselves)
    assert Q is not None and res.tile_sheet is not None  # a cut records where each tile went
    margin = 0.5 + material.kerf_mm / 2 + 0.05  # the cut's own label margin, plus a hair
    A, B = pattern.topology.hinge_tiles.T
    n = 0
    for h in range(len(strips.outline)):
        for side, t in ((0, A[h]), (1, B[h])):
            theta, shift = geometry.kabsch(corners[t], Q[t])
            pad = strips.pads[h, side]
            moved = shapely.transform(pad, lambda c, th=theta, s=shift: geometry.rotate(c, th) + s)
            inside = shapely.intersection(
                moved, shapely.buffer(shapely.Polygon(Q[t]), -margin, join_style="mitre")
            )
            for g in shapely.get_parts(inside):
                if g.is_empty or g.area <= 0 or g.geom_type != "Polygon":
                    continue
                res.sheets[int(res.tile_sheet[t])].add(
                    "ENGRAVE", np.asarray(g.exterior.coords)[:-1], True
                )
                n += 1
    multi = len(res.sheets) > 1
    for sd in res.sheets:
        name = f"{stem}-sheet{sd.index}" if multi else stem
        if f"{name}.dxf" in res.files:
            res.files[f"{name}.dxf"] = dxf_bytes(sd, colors)
        if f"{name}.svg" in res.files:
            res.files[f"{name}.svg"] = svg_bytes(sd, colors)
    if f"{stem}.png" in res.files:
        res.files[f"{stem}.png"] = png_bytes(res.sheets, colors)
    res.manifest["pad_marks"] = {
        "layer": "ENGRAVE",
        "count": n,
        "margin_mm": margin,
        "source": "fabkiri print --style strips --marks",
    }
    return res, n
