"""DXF writer (ezdxf): R2010, millimetres, one layer per purpose, LWPOLYLINEs only.

Byte-reproducible: ezdxf's ``write_fixed_meta_data_for_testing`` option fixes
the creation/update dates and GUIDs it would otherwise draw from the clock and
the random generator; entity handles are sequential.

Bulk strokes: a 64x64 sheet engraves tens of thousands of label strokes, and
ezdxf spends ~80 µs building and exporting each LWPOLYLINE object. The
``ENGRAVE`` layer is therefore written in bulk: ezdxf exports one prototype
LWPOLYLINE of the document, and every stroke is that prototype's tag text with
its own handle (reserved from the document's handle generator, so
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

from .drawing import COLORS, LAYERS, SheetDrawing

DXF_VERSION = "R2010"
BULK_LAYERS = ("ENGRAVE",)  # first in LAYERS: its entities open the ENTITIES section
ENTITIES_HEAD = "  0\nSECTION\n  2\nENTITIES\n"
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
    """``(head, mid)`` of ezdxf's own export of an open 2-point LWPOLYLINE on ``layer``.

    An entity is ``head + handle + mid + " 90\\n{n}\\n 70\\n{flags}\\n" + vertices``;
    None when ezdxf's export does not have that shape.
    """
    e = LWPolyline.new(handle=_PROBE_HANDLE, owner=msp.layout_key, dxfattribs={"layer": layer}, doc=doc)
    e.set_points(_PROBE_POINTS, format="xy")
    buf = io.StringIO()
    e.export_dxf(TagWriter(buf, dxfversion=doc.dxfversion))
    text = buf.getvalue()
    head, sep, rest = text.partition(f"  5\n{_PROBE_HANDLE}\n")
    mid, sep2, verts = rest.partition(" 90\n2\n 70\n0\n")
    if not sep or not sep2 or verts != "".join(f" 10\n{x}\n 20\n{y}\n" for x, y in _PROBE_POINTS):
        return None
    return head + "  5\n", "\n" + mid


def _bulk_text(polylines, handles: list[str], head: str, mid: str) -> str:
    """Every polyline as the prototype's tags (vertices formatted like ezdxf: ``%s`` of a float)."""
    if not polylines:
        return ""
    pts = np.concatenate([p for p, _ in polylines])
    vtx = [f" 10\n{x!r}\n 20\n{y!r}\n" for x, y in zip(pts[:, 0].tolist(), pts[:, 1].tolist())]
    counts = [len(p) for p, _ in polylines]
    ends = np.cumsum(counts).tolist()
    out = []
    start = 0
    for h, n, end, (_, closed) in zip(handles, counts, ends, polylines):
        out.append(f"{head}{h}{mid} 90\n{n}\n 70\n{1 if closed else 0}\n")
        out.append("".join(vtx[start:end]))
        start = end
    return "".join(out)


def dxf_bytes(sheet: SheetDrawing, colors: str = "default", *, bulk: bool = True) -> bytes:
    """The sheet as DXF text (ASCII, ``\\n`` line ends)."""
    with _fixed_metadata():
        doc = ezdxf.new(DXF_VERSION, units=units.MM)
        doc.header["$INSUNITS"] = 4  # millimetres; ezdxf's default would be 6 (metres)
        doc.header["$EXTMIN"] = (0.0, 0.0, 0.0)
        doc.header["$EXTMAX"] = (sheet.width, sheet.height, 0.0)
        doc.header["$LIMMIN"] = (0.0, 0.0)
        doc.header["$LIMMAX"] = (sheet.width, sheet.height)
        for name in LAYERS:
            doc.layers.add(name, color=COLORS[colors][name][1])
        msp = doc.modelspace()
        bulk_text = []
        for i, name in enumerate(LAYERS):
            polylines = sheet.layers[name]
            # only a leading run of bulk layers: their entities must open the ENTITIES section
            leading = all(n in BULK_LAYERS for n in LAYERS[:i + 1])
            proto = _prototype(doc, msp, name) if bulk and leading else None
            if proto is not None:
                # the handles add_lwpolyline would have drawn, in the same order
                handles = [doc.entitydb.next_handle() for _ in polylines]
                bulk_text.append(_bulk_text(polylines, handles, *proto))
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
        at = text.index(ENTITIES_HEAD) + len(ENTITIES_HEAD)
        text = text[:at] + "".join(bulk_text) + text[at:]
    return text.encode("ascii")
