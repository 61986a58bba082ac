"""``fabkiri verify`` as a library call: a pattern's proof of both closed states and, with a cut file,
the proof that the file's tiles are that pattern's (:func:`verify_files`)."""

from __future__ import annotations

import os
from pathlib import Path

from ..design.core.conformance import parse_shape_tol
from ..errors import InputError
from ..pattern.kinds.periodic.sheet import flat_sheet, seam_of
from ..pattern.model import Pattern
from ..verify import verify_layout, verify_pattern
from ..verify.report import Report

DEFAULT_TOL_MM = 0.05  # the default material's (acrylic-3) tolerance


def verify_files(
    pattern: Pattern,
    layout: str | os.PathLike | None = None,
    *,
    tol_mm: float = DEFAULT_TOL_MM,
    exact: bool = False,
    tol_rad: float = 1e-6,
    shape_tol: str = "2%",
) -> Report:
    """The verification report of ``pattern`` at the fabrication tolerance ``tol_mm`` (``exact``: the
    relative tier for solver output instead) and, with ``layout`` (a .dxf or .svg), of that cut file
    against it at ``tol_mm``; a tube is checked against the flat sheet it is cut as."""
    report = verify_pattern(
        pattern,
        tol_mm=None if exact else tol_mm,
        tol_rad=tol_rad,
        shape_tol=parse_shape_tol(shape_tol),
    )
    if layout is None:
        return report
    if not Path(layout).exists():
        raise InputError(f"{layout}: no such layout file")
    seam = seam_of(pattern)  # a tube is cut as its flat sheet (docs/tubes.md)
    sheet = pattern if seam is None else flat_sheet(pattern, seam)
    cut = verify_layout(sheet, str(layout), tol_mm=tol_mm, tol_rad=tol_rad)
    report.extend(cut)
    report.kind = "pattern and layout"
    report.meta["layout"] = str(layout)
    report.meta["layout_tol_mm"] = tol_mm
    report.meta["tolerance"] = f"pattern {report.meta['tolerance']}; layout {cut.meta['tolerance']}"
    return report
