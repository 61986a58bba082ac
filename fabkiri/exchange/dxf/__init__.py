"""DXF, the cut files' drawing format: written (:mod:`.writer`, ezdxf) and read (:mod:`.reader`),
both through the one tag codec of fabkiri's canonical LWPOLYLINE entity (:mod:`.tags`).

Registered as the drawing format ``dxf`` (:mod:`fabkiri.exchange.file_formats`). ezdxf is loaded
with the writer or with a file the tags cannot take, not with this package.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from ..file_formats import DrawingFormat, register_format
from .reader import read_cut_dxf

if TYPE_CHECKING:
    from ..drawing import SheetDrawing


def _write(sheet: SheetDrawing, colors: str = "default") -> bytes:
    from .writer import dxf_bytes  # ezdxf: loaded with the first DXF written

    return dxf_bytes(sheet, colors)


register_format(DrawingFormat("dxf", (".dxf",), write=_write, read=read_cut_dxf))
