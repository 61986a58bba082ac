"""The DXF writer (ezdxf): R2010, millimetres, one layer per purpose, LWPOLYLINEs only.

Byte-reproducible: ezdxf's ``write_fixed_meta_data_for_testing`` option fixes
the creation/update dates and GUIDs it would otherwise draw from the clock and
the random generator; entity handles are sequential.

Bulk strokes: a 64x64 sheet engraves tens of thousands of label strokes, and
ezdxf is slow building and exporting each LWPOLYLINE object. The
``ENGRAVE`` layer is therefore written in bulk: ezdxf exports one prototype
LWPOLYLINE of the document, and every stroke is that prototype's tag text with
its own handle (the tag codec :mod:`.tags`; reserved from the document's handle generator, so
``$HANDSEED`` and every later handle are what ezdxf would give), vertex count,
flags and vertices (formatted as ezdxf does: ``%s`` of a float). The result is
byte-identical to adding each stroke with ``add_lwpolyline`` (tested);
``bulk=False`` does exactly that. If the prototype's tags ever differ from the
expected shape (another ezdxf), the object path is used.
"""

from __future__ import annotations

import io
from contextlib import contextmanager

import ezdxf
import numpy as np
from ezdxf import units
from ezdxf.entities import LWPolyline
from ezdxf.lldxf.tagwriter import TagWriter

from ..drawing import COLORS, LAYERS, SheetDrawing
from .tags import insert_entities, lwpolyline_tags, split_prototype

DXF_VERSION = "R2010"
NON_PLOTTING = ("NOTES",)  # annotation for the maker, never cut: the layer's plot flag is off
BULK_LAYERS = ("ENGRAVE",)  # first in LAYERS: its entities open the ENTITIES section
_PROBE_HANDLE = "FFFFF0"
_PROBE_POINTS = [(1.25, 2.5), (3.75, 4.5)]


@contextmanager
def _fixed_metadata():
    old = ezdxf.options.write_fixed_meta_data_for_testing
    ezdxf.options.write_fixed_meta_data_for_testing = True
    try:
        yield
    finally:
        ezdxf.options.write_fixed_meta_data_for_testing = old


def _prototype(doc, msp, layer: str) -> tuple[str, str] | None:
    """``(head, mid)`` of ezdxf's own export of an open 2-point LWPOLYLINE on ``layer``
    (:func:`~.tags.split_prototype`); None when it is not canonical."""
    e = LWPolyline.new(
        handle=_PROBE_HANDLE, owner=msp.layout_key, dxfattribs={"layer": layer}, doc=doc
    )
    e.set_points(_PROBE_POINTS, format="xy")
    buf = io.StringIO()
    e.export_dxf(TagWriter(buf, dxfversion=doc.dxfversion))
    return split_prototype(buf.getvalue(), _PROBE_HANDLE, _PROBE_POINTS)


def _set_extents(doc, msp, sheet: SheetDrawing) -> None:
    """The header from the drawing: ``$EXTMIN``/``$EXTMAX`` its bounding box, ``$LIMMIN``/``$LIMMAX``
    the sheet (grown to hold the drawing), ``$PSVPSCALE`` 1:1. ezdxf writes the modelspace layout's
    own extents and limits over the header's on save, so they are set there too."""
    pts = [p for polylines in sheet.layers.values() for p, _ in polylines if len(p)]
    if pts:
        xy = np.concatenate(pts)
        lo, hi = xy.min(axis=0), xy.max(axis=0)
    else:  # an empty sheet: its frame
        lo, hi = np.zeros(2), np.array([sheet.width, sheet.height])
    lo, hi = [float(v) for v in lo], [float(v) for v in hi]
    # ezdxf copies the layout's extents only when neither is the zero vector: the header as well
    msp.dxf.extmin = doc.header["$EXTMIN"] = (lo[0], lo[1], 0.0)
    msp.dxf.extmax = doc.header["$EXTMAX"] = (hi[0], hi[1], 0.0)
    msp.dxf.limmin = (min(0.0, lo[0]), min(0.0, lo[1]))
    msp.dxf.limmax = (max(sheet.width, hi[0]), max(sheet.height, hi[1]))
    doc.header["$PSVPSCALE"] = 1.0  # 0 ("scaled to fit") leaves LibreCAD's dxf2pdf page blank


def dxf_bytes(sheet: SheetDrawing, colors: str = "default", *, bulk: bool = True) -> bytes:
    """The sheet as DXF text (ASCII, ``\\n`` line ends)."""
    with _fixed_metadata():
        doc = ezdxf.new(DXF_VERSION, units=units.MM)
        doc.header["$INSUNITS"] = 4  # millimetres; ezdxf's default would be 6 (metres)
        msp = doc.modelspace()
        _set_extents(doc, msp, sheet)
        for name in LAYERS:
            layer = doc.layers.add(name, color=COLORS[colors][name][1])
            if name in NON_PLOTTING:
                layer.dxf.plot = (
                    0  # CAM and plot tools leave it out (the sheet frame is no toolpath)
                )
        bulk_text = []
        for i, name in enumerate(LAYERS):
            polylines = sheet.layers[name]
            # only a leading run of bulk layers: their entities must open the ENTITIES section
            leading = all(n in BULK_LAYERS for n in LAYERS[: i + 1])
            proto = _prototype(doc, msp, name) if bulk and leading else None
            if proto is not None:
                # the handles add_lwpolyline would have drawn, in the same order
                handles = [doc.entitydb.next_handle() for _ in polylines]
                bulk_text.append(lwpolyline_tags(polylines, handles, *proto))
                continue
            attribs = {"layer": name}
            for pts, closed in polylines:
                msp.add_lwpolyline(pts.tolist(), format="xy", close=closed, dxfattribs=attribs)
        # the CLASSES section order depends on what ezdxf loaded earlier in the process: sort it
        doc.classes.add_required_classes(doc.dxfversion)  # what write() would add, then sort all
        cls = doc.classes.classes
        ordered = sorted(cls.items(), key=lambda kv: str(kv[0]))
        cls.clear()
        cls.update(ordered)
        buf = io.StringIO()
        doc.write(buf)
    text = buf.getvalue()
    if bulk_text:
        # the bulk layers come first in the modelspace, so first in the ENTITIES section
        text = insert_entities(text, "".join(bulk_text))
    return text.encode("ascii")
