"""A DXF drawing's one closed outline, as a design target (``design --target shape.dxf``).

CAD tools draw an outline as a closed LWPOLYLINE (bulges for arcs), a CIRCLE, ELLIPSE or SPLINE, or
as loose LINEs and ARCs meeting end to end (LibreCAD's way). The cut-file reader
(:func:`~.reader.read_cut_dxf`: blocks exploded, curves flattened to 1 µm, ``$INSUNITS`` to mm) gives
every curve; loose ones are joined by shapely's ``polygonize``, their ends snapped to a
:data:`GRID_MM` grid first (an arc's computed end misses its line's by round-off). Exactly one closed curve must result:
with several, which is the outline is the user's to say.
"""

from __future__ import annotations

from collections import Counter
from pathlib import Path

import numpy as np
import shapely
from shapely.geometry import MultiLineString
from shapely.ops import polygonize

from ...errors import InputError, VerifyError
from .reader import read_cut_dxf

GRID_MM = 1e-6


def dxf_outline(p: Path) -> np.ndarray:
    """The ``(n, 2)`` corners (mm) of the one closed outline a DXF draws, or :class:`InputError`."""
    try:
        lw = read_cut_dxf(p)
    except VerifyError as exc:
        raise InputError(str(exc)) from None
    rings = [pts for pts, closed in zip(lw.polylines, lw.closed) if closed]
    loose = [pts for pts, closed in zip(lw.polylines, lw.closed) if not closed]
    if loose:  # noded (split where they cross), then the loops they close
        lines = shapely.unary_union(shapely.set_precision(MultiLineString(loose), GRID_MM))
        rings += [
            np.asarray(poly.exterior.coords)[:-1] for poly in polygonize(shapely.get_parts(lines))
        ]
    if len(rings) == 1:
        return rings[0]
    if not lw.polylines:
        raise InputError(f"{p}: {_nothing_read(lw.unread)}")
    if not rings:
        raise InputError(
            f"{p}: no closed outline ({len(loose)} open curve(s) that close no loop); close it"
        )
    sizes = ", ".join(f"{w:.3g} x {h:.3g} mm" for w, h in (np.ptp(r, axis=0) for r in rings[:3]))
    raise InputError(
        f"{p}: {len(rings)} closed curves ({sizes}{', ...' if len(rings) > 3 else ''}); which is the "
        "outline? a target file holds one: leave only it in the drawing"
    )


def _nothing_read(unread: list[str]) -> str:
    """Why a drawing gave no curve: empty (Inkscape's R12 export writes only its paths), or what it
    holds instead, counted by kind."""
    if not unread:
        return (
            "the drawing is empty, no lines or curves (Inkscape's R12 DXF export leaves out every "
            "rectangle, circle, ellipse and polygon: convert them with Path > Object to Path, or "
            "save as its R14 DXF)"
        )
    kinds = Counter(unread)
    held = ", ".join(f"{n} {k}" for k, n in kinds.most_common())
    return f"no lines or curves to read as an outline; the drawing holds {held}"
