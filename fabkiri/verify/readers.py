"""Reading cut files back: the ``CUT`` linework of a DXF or SVG in millimetres, y up.

Any DXF or SVG a laser tool writes is read, not only fabkiri's own: DXF through a fast scan of
fabkiri's own LWPOLYLINE layout with ezdxf as the fallback for everything else, SVG with
svgelements, each in the file's declared units. Annotation layers (notes, engraving, scoring) are
never cut and are left out.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import VerifyError

MM_PER_PX = 25.4 / 96.0
INSUNITS_MM = {0: 1.0, 1: 25.4, 2: 304.8, 4: 1.0, 5: 10.0, 6: 1000.0, 13: 1e-3, 14: 0.1}
SNAP_MM = 1e-4  # endpoints closer than this are one node of the linework
JOIN_MM = 2e-3  # cut ends closer than this meet (rounding to 1 µm moves a point by 0.7 µm; a 10 µm bridge is not cut)
NON_CUT_LAYERS = {"NOTES", "ENGRAVE", "SCORE"}


# ------------------------------------------------------------------ reading


@dataclass
class Linework:
    """Polylines (mm, y up) read from one cut file, and whether each is closed."""

    path: Path
    polylines: list[np.ndarray] = field(default_factory=list)
    closed: list[bool] = field(default_factory=list)
    layer_found: bool = True  # a CUT layer/group existed
    layers: list[str] = field(default_factory=list)  # per polyline: its layer or group name ("" if none)
    colours: list[str] = field(default_factory=list)  # per polyline: its stroke colour ("" if none)

    def add(self, pts: np.ndarray, closed: bool, layer: str = "CUT", colour: str = "") -> None:
        pts = np.asarray(pts, dtype=float).reshape(-1, 2)
        if len(pts) >= 3 and abs(pts[0, 0] - pts[-1, 0]) <= 1e-9 and abs(pts[0, 1] - pts[-1, 1]) <= 1e-9:
            pts, closed = pts[:-1], True
        if len(pts) >= 2:
            self.polylines.append(pts)
            self.closed.append(bool(closed) and len(pts) >= 3)
            self.layers.append(str(layer))
            self.colours.append(str(colour))

    def subset(self, keep) -> Linework:
        keep = list(keep)
        return Linework(self.path, [self.polylines[i] for i in keep], [self.closed[i] for i in keep],
                        self.layer_found, [self.layers[i] for i in keep], [self.colours[i] for i in keep])

    def cut_classes(self) -> list[Linework]:
        """The candidate cut linework: the CUT layer if there is one, else every colour class outside the
        annotation layers (one candidate per colour: a colour-only file keeps its layers as colours)."""
        if self.layer_found or not self.polylines:
            return [self]
        rest = [i for i, name in enumerate(self.layers) if name.upper() not in NON_CUT_LAYERS]
        colours = sorted({self.colours[i] for i in rest})
        if len(colours) <= 1:
            return [self.subset(rest)]
        return [self.subset([i for i in rest if self.colours[i] == c]) for c in colours]


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
        return _read_svg(p, layer)
    raise VerifyError(f"{p}: a layout must be a .dxf or .svg file")


_CUT_LAYER_RE = re.compile(rb"\n[ \t]*8\nCUT[ \t]*(?=\n)", re.IGNORECASE)


def _read_dxf_fast(p: Path, layer_name: str = "CUT") -> Linework | None:
    """Straight LWPOLYLINEs and LINEs on layer CUT of an ASCII DXF, read from the raw tags.

    A DXF is a flat list of (group code, value) line pairs; cut files carry far
    more engraving than cutting, and building ezdxf entities for all of it
    takes seconds on a 64x64 sheet. Entity starts (code-0 lines) are found with
    numpy on the line table, the CUT layer tags with a regular expression, and
    only those entities are parsed. Anything else (no CUT layer, curves,
    bulges, blocks, binary DXF, odd structure) returns None and the full ezdxf
    reader takes over.
    """
    try:
        raw = p.read_bytes()
        if raw.startswith(b"AutoCAD Binary DXF"):
            return None
        data = b"\n" + raw.replace(b"\r\n", b"\n").replace(b"\r", b"\n")
        if not data.endswith(b"\n"):
            data += b"\n"
        buf = np.frombuffer(data, dtype=np.uint8)
        nl = np.flatnonzero(buf == 10)  # nl[k] opens line k; code lines are even
        k = np.arange(0, len(nl) - 1, 2)
        end = nl[k + 1]
        length = end - nl[k] - 1
        zero = (buf[end - 1] == ord("0")) & ((length == 1) | (buf[end - 2] == ord(" ")))
        starts = nl[k[zero]]  # every "0" code line: an entity, section or table boundary
        m = re.search(rb"\n[ \t]*0\n[ \t]*SECTION[ \t]*\n[ \t]*2\n[ \t]*ENTITIES[ \t]*\n", data)
        if m is None:
            return None
        lo = m.end() - 1
        e = re.compile(rb"\n[ \t]*0\n[ \t]*ENDSEC[ \t]*(?=\n)").search(data, lo)
        hi = e.start() if e else len(data) - 1
        units = re.search(rb"\n[ \t]*9\n[ \t]*\$INSUNITS[ \t]*\n[ \t]*70\n[ \t]*(-?\d+)", data)
        insunits = int(units.group(1)) if units and units.start() < lo else 0
        unit = INSUNITS_MM.get(insunits)
        if unit is None:
            raise VerifyError(f"{p}: unsupported drawing units $INSUNITS={insunits}")
        starts = starts[(starts >= lo) & (starts < hi)]
        bounds = np.append(starts, hi)
        layer_re = _CUT_LAYER_RE if layer_name == "CUT" else \
            re.compile(rb"\n[ \t]*8\n" + layer_name.encode() + rb"[ \t]*(?=\n)", re.IGNORECASE)
        tags_at = np.array([t.start() for t in layer_re.finditer(data, lo, hi)], dtype=np.int64)
        if len(tags_at) == 0:
            return None  # no CUT layer: a plain file, read it all with ezdxf
        tags_at = tags_at[np.searchsorted(nl, tags_at) % 2 == 0]
        owners = np.unique(np.searchsorted(starts, tags_at, side="right") - 1)
        lw = Linework(p, layer_found=True)
        for o in owners[owners >= 0].tolist():
            lines = data[bounds[o] + 1: bounds[o + 1]].decode("utf-8", "replace").split("\n")
            tags = list(zip((c.strip() for c in lines[0::2]), lines[1::2]))
            kind = tags[0][1].strip()
            layer = next((v.strip().upper() for c, v in tags if c == "8"), "")
            if layer != layer_name:
                continue  # the layer was not this entity's layer tag
            if kind == "LINE":
                get = dict(tags)
                lw.add(np.array([[float(get["10"]), float(get["20"])],
                                 [float(get["11"]), float(get["21"])]]) * unit, False)
                continue
            if any(c in ("210", "220", "230") for c, _ in tags):
                return None  # an extrusion direction (OCS): the full reader maps it to world coordinates
            if kind != "LWPOLYLINE":
                return None  # curves, old-style polylines, blocks: the full reader
            if any(c == "42" and float(v) != 0.0 for c, v in tags):
                return None  # an arc segment
            xs = [float(v) for c, v in tags if c == "10"]
            ys = [float(v) for c, v in tags if c == "20"]
            if len(xs) != len(ys):
                return None
            flags = next((int(v) for c, v in tags if c == "70"), 0)
            lw.add(np.column_stack([xs, ys]).reshape(-1, 2) * unit, bool(flags & 1))
        return lw
    except VerifyError:
        raise
    except Exception:  # malformed tag stream: let the full reader name the problem
        return None


def _read_dxf(p: Path, layer: str = "CUT") -> Linework:
    fast = _read_dxf_fast(p, layer)
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

    try:
        doc, _ = recover.readfile(str(p))
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
        closed = bool(getattr(e, "closed", False) or getattr(e, "is_closed", False) or e.dxftype() == "CIRCLE")
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


def _read_svg(p: Path, layer_name: str = "CUT") -> Linework:
    import svgelements as se

    try:
        svg = se.SVG.parse(_without_annotation_layers(p, layer_name), reify=True)
    except Exception as exc:  # svgelements raises many kinds on bad XML
        raise VerifyError(f"{p}: not a readable SVG file ({type(exc).__name__}: {exc})") from None
    if not svg.height:
        raise VerifyError(f"{p}: the SVG has no height; cannot flip y")
    # svgelements' own mm constant is rounded (3.7795296 px/mm, 5e-7 off); take
    # the px-per-mm factor from the declared size instead
    mm_per_px = _declared_mm(svg.values.get("height"), float(svg.height))
    height = float(svg.height) * mm_per_px
    groups = list(svg.elements(lambda e: isinstance(e, se.Group)))

    def name(g) -> str:
        for v in (g.values.get(INKSCAPE_LABEL), g.values.get("inkscape:label"), g.id):
            if str(v or "").upper() in NON_CUT_LAYERS | {"CUT"}:
                return str(v).upper()
        return ""

    layer_of: dict[int, str] = {}
    for g in groups:  # document order: an inner named group overrides its parent
        if name(g):
            for e in g.select():
                if isinstance(e, se.Shape):
                    layer_of[id(e)] = name(g)
    cut_found = layer_name in layer_of.values()
    shapes = [e for e in svg.elements() if isinstance(e, se.Shape)
              and (layer_of.get(id(e)) == layer_name if cut_found or layer_name != "CUT"
                   else layer_of.get(id(e), "") not in NON_CUT_LAYERS)]
    lw = Linework(p, layer_found=cut_found)
    for shape in shapes:
        path_ = se.Path(shape)
        layer = layer_of.get(id(shape), "")
        colour = str(shape.stroke.hex) if shape.stroke is not None and shape.stroke.value is not None else ""
        pts: list[tuple[float, float]] = []
        for seg in path_.segments():
            if isinstance(seg, se.Move):
                if len(pts) >= 2:
                    lw.add(_svg_mm(pts, height, mm_per_px), False, layer, colour)
                pts = [(seg.end.x, seg.end.y)]
            elif isinstance(seg, se.Close):
                if len(pts) >= 3:
                    lw.add(_svg_mm(pts, height, mm_per_px), True, layer, colour)
                pts = []
            elif isinstance(seg, se.Line):
                pts.append((seg.end.x, seg.end.y))
            else:  # curves: sample finely (tile outlines are straight; be tolerant)
                for t in np.linspace(0, 1, 17)[1:]:
                    q = seg.point(t)
                    pts.append((q.x, q.y))
        if len(pts) >= 2:
            lw.add(_svg_mm(pts, height, mm_per_px), False, layer, colour)
    return lw


def _without_annotation_layers(p: Path, keep: str = "CUT"):
    """The SVG with its NOTES/ENGRAVE/SCORE groups removed, when it has a CUT group; else the path.

    Only the CUT group is read when there is one, and svgelements would spend
    seconds building the tens of thousands of label strokes of a 64x64 sheet.
    Kept as is (the whole file goes to svgelements) when anything could reach
    into a removed group (``<use>``, a CUT group inside an annotation group)
    or ElementTree cannot parse it (svgelements then names the problem).
    """
    import io
    import xml.etree.ElementTree as ET

    try:
        root = ET.parse(p).getroot()
    except (ET.ParseError, OSError):
        return str(p)

    def name(el) -> str:
        return str(el.get("id") or el.get(INKSCAPE_LABEL) or "").upper()

    groups = [el for el in root.iter() if el.tag.rsplit("}", 1)[-1] == "g"]
    if not any(name(g) == keep for g in groups):
        return str(p)
    if any(el.tag.rsplit("}", 1)[-1] == "use" for el in root.iter()):
        return str(p)
    drop = {id(g) for g in groups if name(g) in (NON_CUT_LAYERS | {"CUT"}) - {keep}
            and not any(name(d) == keep for d in g.iter() if d.tag.rsplit("}", 1)[-1] == "g")}
    if not drop:
        return str(p)
    for parent in list(root.iter()):
        for child in [c for c in parent if id(c) in drop]:
            parent.remove(child)
    return io.BytesIO(ET.tostring(root))


INKSCAPE_LABEL = "{http://www.inkscape.org/namespaces/inkscape}label"


_UNIT_MM = {"mm": 1.0, "cm": 10.0, "in": 25.4, "pt": 25.4 / 72, "pc": 25.4 / 6, "px": MM_PER_PX, "": MM_PER_PX}


def _declared_mm(attr: Any, height_px: float) -> float:
    """mm per svgelements px, from the root's declared height (e.g. '400mm')."""
    import re

    m = re.fullmatch(r"\s*([0-9.eE+-]+)\s*([a-z]*)\s*", str(attr or ""))
    if not m or m.group(2) not in _UNIT_MM or height_px <= 0:
        return MM_PER_PX
    try:
        return float(m.group(1)) * _UNIT_MM[m.group(2)] / height_px
    except ValueError:
        return MM_PER_PX


def _svg_mm(pts: list[tuple[float, float]], height_mm: float, mm_per_px: float = MM_PER_PX) -> np.ndarray:
    a = np.asarray(pts, dtype=float) * mm_per_px
    a[:, 1] = height_mm - a[:, 1]
    return a
