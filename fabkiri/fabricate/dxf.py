"""DXF writer (ezdxf): R2010, millimetres, one layer per purpose, LWPOLYLINEs only.

Byte-reproducible: ezdxf's ``write_fixed_meta_data_for_testing`` option fixes
the creation/update dates and GUIDs it would otherwise draw from the clock and
the random generator; entity handles are sequential.
"""

from __future__ import annotations

import io
from contextlib import contextmanager

import ezdxf
from ezdxf import units

from .drawing import COLORS, LAYERS, SheetDrawing

DXF_VERSION = "R2010"


@contextmanager
def _fixed_metadata():
    old = ezdxf.options.write_fixed_meta_data_for_testing
    ezdxf.options.write_fixed_meta_data_for_testing = True
    try:
        yield
    finally:
        ezdxf.options.write_fixed_meta_data_for_testing = old


def dxf_bytes(sheet: SheetDrawing, colors: str = "default") -> bytes:
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
        for name in LAYERS:
            attribs = {"layer": name}
            for pts, closed in sheet.layers[name]:
                msp.add_lwpolyline(pts.tolist(), format="xy", close=closed, dxfattribs=attribs)
        # the CLASSES section order depends on what ezdxf loaded earlier in the process: sort it
        cls = doc.classes.classes
        ordered = sorted(cls.items(), key=lambda kv: str(kv[0]))
        cls.clear()
        cls.update(ordered)
        buf = io.StringIO()
        doc.write(buf)
    return buf.getvalue().encode("ascii")
