"""The file formats ``cut`` writes, as strategy objects chosen by name (``--formats dxf,svg,png``).

A :class:`SheetFormat` turns a finished cut's :class:`~.drawing.SheetDrawing` sheets into bytes:
one file per sheet (DXF, SVG: ``STEM.dxf`` or ``STEM-sheetN.dxf``) or one file for the whole cut
(the PNG preview, ``STEM.png``). ``cut_pattern`` asks every format the options name, in the order
they are registered here; the written files then go through the read-back and the atomic writer.
A new format (e.g. PDF for a laser driver) is one module with its writer that calls
:func:`register_sheet_format`, plus one line in :data:`_SHEET_FORMATS`; the read-back verifies
the DXF and SVG only (a reader in ``verify/`` is needed before a new format is verified on read).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING

from ...registry import Registry

if TYPE_CHECKING:
    from ...exchange.drawing import SheetDrawing
    from .sheets import CutJob


@dataclass(frozen=True)
class SheetFormat:
    """One file format of a cut: ``write(job, sheets) -> bytes``, with ``sheets`` one sheet
    (``per_sheet``) or every sheet of the cut; ``suffix`` names the files (with the dot)."""

    name: str
    suffix: str
    per_sheet: bool
    write: Callable[[CutJob, list[SheetDrawing]], bytes]


def _dxf(job: CutJob, sheets: list[SheetDrawing]) -> bytes:
    from ...exchange.dxf.writer import dxf_bytes

    return dxf_bytes(sheets[0], job.colors)


def _svg(job: CutJob, sheets: list[SheetDrawing]) -> bytes:
    from ...exchange.svg import svg_bytes

    return svg_bytes(sheets[0], job.colors, job.options.stroke_mm)


def _png(job: CutJob, sheets: list[SheetDrawing]) -> bytes:
    """The preview of every sheet, scaled so the smallest label or corner label is legible."""
    from .preview import png_bytes

    shown = [h for h in (job.label_heights, job.corner_heights) if h is not None and (h > 0).any()]
    smallest = min((float(h[h > 0].min()) for h in shown), default=None)
    return png_bytes(sheets, job.colors, label_mm=smallest)


_SHEET_FORMATS: Registry[SheetFormat] = Registry({})


def register_sheet_format(fmt: SheetFormat) -> SheetFormat:
    """Add a format (a new format's module calls this when it is imported)."""
    return _SHEET_FORMATS.add(fmt.name, fmt)


def sheet_format_names() -> tuple[str, ...]:
    """The formats ``cut`` writes, in the order it writes them."""
    return _SHEET_FORMATS.names()


def sheet_format(name: str) -> SheetFormat | None:
    """The format of this name; None if unknown."""
    return _SHEET_FORMATS.find(name)


register_sheet_format(SheetFormat("dxf", ".dxf", True, _dxf))
register_sheet_format(SheetFormat("svg", ".svg", True, _svg))
register_sheet_format(SheetFormat("png", ".png", False, _png))
