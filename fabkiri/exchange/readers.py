"""Reading cut files back: the ``CUT`` linework of a DXF or SVG in millimetres, y up.

Any DXF or SVG a laser tool writes is read, not only fabkiri's own: DXF through a fast scan of
one layer's tags (:mod:`.dxfcodec`) with ezdxf as the fallback for everything else, SVG with
:mod:`.svgread`, each in the file's declared units. Annotation layers (notes, engraving, scoring) are
never cut and are left out.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..errors import VerifyError
from .dxfcodec import INSUNITS_MM, read_layer_tags
from .linework import JOIN_MM, MM_PER_PX, NON_CUT_LAYERS, SNAP_MM, Linework
from .svgread import read_cut_svg

__all__ = [
    "CURVE_TYPES",
    "INSUNITS_MM",
    "JOIN_MM",
    "MM_PER_PX",
    "NON_CUT_LAYERS",
    "SNAP_MM",
    "Linework",
    "read_cut_file",
]

# ------------------------------------------------------------------ reading


def read_cut_file(path: str | Path, layer: str = "CUT") -> Linework:
    """The CUT linework of a DXF or SVG file, in mm with y up (``layer``: another named layer, e.g. ENGRAVE;
    a file without it gives an empty linework with ``layer_found`` False)."""
    p = Path(path)
    if not p.exists():
        raise VerifyError(f"{p}: no such layout file")
    suffix = p.suffix.lower()
    if suffix == ".dxf":
        return _read_dxf(p, layer)
    if suffix == ".svg":
        return read_cut_svg(p, layer)
    raise VerifyError(f"{p}: a layout must be a .dxf or .svg file")


def _read_dxf(p: Path, layer: str = "CUT") -> Linework:
    fast = read_layer_tags(p, layer)
    if fast is not None:
        return fast
    return _read_dxf_full(p, layer)


CURVE_TYPES = {"LWPOLYLINE", "POLYLINE", "LINE", "ARC", "CIRCLE", "SPLINE", "ELLIPSE"}


def _read_dxf_full(p: Path, layer_name: str = "CUT") -> Linework:
    """Every curve of the modelspace in world coordinates, blocks exploded, with its layer and colour.

    ezdxf does the work: ``recover`` reads damaged files, ``disassemble.recursive_decompose``
    expands INSERTs (any depth, with their transforms), ``to_primitives`` gives each entity's path
    in WCS (its OCS applied, curves flattened to 1 µm).
    """
    import ezdxf
    from ezdxf import disassemble, recover
    from ezdxf.lldxf.validator import is_binary_dxf_file

    try:
        # ezdxf's recover reads ASCII DXF only; its plain reader takes binary DXF
        doc = ezdxf.readfile(str(p)) if is_binary_dxf_file(str(p)) else recover.readfile(str(p))[0]
    except (OSError, ezdxf.DXFError, UnicodeDecodeError, ValueError) as exc:
        raise VerifyError(f"{p}: not a readable DXF file ({exc})") from None
    unit = INSUNITS_MM.get(int(doc.header.get("$INSUNITS", 0)))
    if unit is None:
        raise VerifyError(f"{p}: unsupported drawing units $INSUNITS={doc.header.get('$INSUNITS')}")
    lw = Linework(p, layer_found=False)
    layer_colour = {layer.dxf.name.upper(): layer.color for layer in doc.layers}
    flat = 0.001 / unit
    for prim in disassemble.to_primitives(disassemble.recursive_decompose(doc.modelspace()), flat):
        e = prim.entity
        if e is None or e.dxftype() not in CURVE_TYPES or prim.path is None:
            continue
        layer = e.dxf.layer.upper()
        aci = e.dxf.get("color", 256)
        colour = str(layer_colour.get(layer, 7) if aci in (0, 256) else aci)
        closed = bool(
            getattr(e, "closed", False) or getattr(e, "is_closed", False) or e.dxftype() == "CIRCLE"
        )
        for sub in prim.path.sub_paths():
            pts = np.array([(v.x, v.y) for v in sub.flattening(flat)], dtype=float)
            lw.add(pts * unit, closed, layer, colour)
    if layer_name != "CUT" or any(name == "CUT" for name in lw.layers):
        found = any(name == layer_name for name in lw.layers)
        lw = lw.subset(i for i, name in enumerate(lw.layers) if name == layer_name)
        lw.layer_found = found
    else:  # a plain file from another tool: every outline not on an annotation layer
        lw = lw.subset(i for i, name in enumerate(lw.layers) if name not in NON_CUT_LAYERS)
    return lw
