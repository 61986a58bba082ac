"""Cut-layout verification: read a DXF or SVG back and prove it closes into both states.

The contract with the writers is docs/cut-files.md. Nothing but the geometry
and the declared allowances (manifest.json) is trusted:

1. read the ``CUT`` linework (all outlines for plain files from other tools),
   in millimetres, y up;
2. set the reference square aside, recover the tile polygons per hinge kind
   (``tape``: polygonize the noded linework; ``separate``: each closed outline
   shrunk by the kerf offset; ``ligament``: material minus hinge strips, grown
   by the tile shrink) and reduce each to its four corners;
3. match them to the design tiles (any order; one rigid motion per sheet for
   in-place layouts, one per tile for separate ones; a mirrored tile is an
   error) and check (a) congruence, (b) the in-place layout is the declared
   closed state, (c) the cut tiles reassembled by the hinge correspondence
   give the other closed state (both states for separate tiles), (d) every
   hinge is present.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import shapely
from scipy.sparse import csgraph
from scipy.spatial import cKDTree

from ..errors import VerifyError
from ..mechanics.contract import contract
from ..pattern import geometry
from ..pattern.model import Pattern
from ..pattern.topology import STATES
from .geom import point_segment_distance
from .pattern_checks import closed_state_checks, fabrication_tolerances
from .report import Check, Report, measured

MM_PER_PX = 25.4 / 96.0
INSUNITS_MM = {0: 1.0, 1: 25.4, 2: 304.8, 4: 1.0, 5: 10.0, 6: 1000.0, 13: 1e-3, 14: 0.1}
SNAP_MM = 1e-4  # endpoints closer than this are one node of the linework
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


# ------------------------------------------------------------------ manifest


def load_manifest(layout_path: Path) -> dict[str, Any] | None:
    m = layout_path.parent / "manifest.json"
    if not m.exists():
        return None
    from ..limits import loads_json  # nesting depth and number bounds, as pattern.json

    try:
        data = loads_json(m.read_text("utf-8"), f"{m} (manifest)", VerifyError)
    except (OSError, UnicodeDecodeError) as exc:
        raise VerifyError(f"{m}: not a readable manifest ({exc})") from None
    if not isinstance(data, dict):
        raise VerifyError(f"{m}: a manifest is a JSON object")
    return data


@dataclass
class Allowances:
    hinge: str  # tape | separate | ligament | plain
    layout: str  # in-place | exploded | nested | auto
    state: int
    scale: float
    kerf_offset: float
    tile_shrink: float
    reference: dict[int, np.ndarray]  # sheet -> 4 corners
    hinge_features: list[dict[str, Any]]
    tile_sheet: dict[int, int]
    sheet_files: dict[int, str]
    cross_sheet: set[int] = field(default_factory=set)  # hinges the writer declares split across sheets
    ligament_width: float | None = None  # declared ligament width (mm), when the manifest has one
    tiles_placed: dict[int, tuple[float, np.ndarray]] = field(default_factory=dict)  # tile -> (rotation, shift)
    labels: bool = False  # the manifest says the layout is labelled (fabkiri's tape marks come with the labels)


def _allowances(manifest: dict[str, Any] | None, where: str) -> Allowances:
    if manifest is None:
        return Allowances("plain", "auto", 1, 1.0, 0.0, 0.0, {}, [], {}, {})
    try:
        hinge = str(manifest.get("hinge", "separate"))
        if hinge not in ("tape", "separate", "ligament"):
            raise VerifyError(f"{where}: unknown hinge kind {hinge!r} (tape, separate or ligament)")
        layout = str(manifest.get("layout", "in-place" if hinge in ("tape", "ligament") else "exploded"))
        state = int(manifest.get("state", 1))
        if state not in STATES:
            raise VerifyError(f"{where}: state must be 1 or 2, not {state}")
        scale = float(manifest.get("scale", 1.0))
        kerf = float(manifest.get("kerf_offset_mm", 0.0))
        shrink = float(manifest.get("tile_shrink_mm", 0.0))
        if not (scale > 0 and math.isfinite(scale)) or not (kerf >= 0 and math.isfinite(kerf)) \
                or not (shrink >= 0 and math.isfinite(shrink)):
            raise VerifyError(f"{where}: scale must be positive and kerf_offset_mm, tile_shrink_mm non-negative")
        ref: dict[int, np.ndarray] = {}
        rs = manifest.get("reference_square")
        for item in ([rs] if isinstance(rs, dict) else (rs or [])):
            ref[int(item.get("sheet", 1))] = np.asarray(item["corners"], dtype=float).reshape(-1, 2)
        feats = list(manifest.get("hinge_features") or [])
        tile_sheet = {int(t["tile"]): int(t.get("sheet", 1)) for t in manifest.get("tiles") or []}
        sheet_files = {}
        for sh in manifest.get("sheets") or []:
            for key in ("dxf", "svg"):
                if sh.get(key):
                    sheet_files.setdefault(int(sh["index"]), {})[key] = str(sh[key])
        cross = {int(h["hinge"]) for h in manifest.get("hinges") or [] if h.get("cross_sheet")}
        lig = manifest.get("ligament") if isinstance(manifest.get("ligament"), dict) else {}
        lig_w = float(lig["width_mm"]) if lig.get("width_mm") else None
        placed = {int(t["tile"]): (float(t["rotation_rad"]), np.asarray(t["shift_mm"], dtype=float))
                  for t in manifest.get("tiles") or [] if "rotation_rad" in t and "shift_mm" in t}
    except VerifyError:
        raise
    except (TypeError, ValueError, KeyError, AttributeError) as exc:
        raise VerifyError(f"{where}: malformed manifest ({type(exc).__name__}: {exc})") from None
    params = manifest.get("parameters") if isinstance(manifest.get("parameters"), dict) else {}
    return Allowances(hinge, layout, state, scale, kerf, shrink, ref, feats, tile_sheet, sheet_files, cross, lig_w,
                      placed, bool(params.get("labels", False)))


# ------------------------------------------------------------------ recovery


def _drop_reference(lw: Linework, corners: np.ndarray | None) -> int:
    """Remove the closed polyline whose corners are the reference square's."""
    if corners is None:
        return 0
    keep_p, keep_c, dropped = [], [], 0
    for pts, cl in zip(lw.polylines, lw.closed):
        if cl and len(pts) == len(corners) and not dropped:
            d = np.linalg.norm(pts[:, None] - corners[None], axis=-1).min(axis=1).max()
            if d <= 1e-3:
                dropped += 1
                continue
        keep_p.append(pts)
        keep_c.append(cl)
    lw.polylines, lw.closed = keep_p, keep_c
    return dropped


def _snapped_segments(lw: Linework, eps: float = SNAP_MM) -> np.ndarray:
    """All segments ``(n, 2, 2)`` with endpoints closer than ``eps`` merged."""
    if not lw.polylines:
        return np.zeros((0, 2, 2))
    pts = np.concatenate(lw.polylines)
    n = np.array([len(q) for q in lw.polylines])
    start = np.concatenate([[0], np.cumsum(n)[:-1]])
    owner = np.repeat(np.arange(len(n)), n)
    local = np.arange(len(pts)) - start[owner]
    nxt = start[owner] + (local + 1) % n[owner]
    # every vertex starts a segment, except the last one of an open polyline
    use = (local < n[owner] - 1) | np.asarray(lw.closed)[owner]
    segs = np.stack([pts[use], pts[nxt[use]]], 1)
    pts = segs.reshape(-1, 2)
    pairs = cKDTree(pts).query_pairs(eps, output_type="ndarray")
    if len(pairs):
        from scipy import sparse

        n = len(pts)
        g = sparse.coo_matrix((np.ones(len(pairs)), (pairs[:, 0], pairs[:, 1])), shape=(n, n))
        _, label = csgraph.connected_components(g, directed=False)
        first = np.full(label.max() + 1, -1)
        first[label[::-1]] = np.arange(n)[::-1]
        pts = pts[first[label]]
    segs = pts.reshape(-1, 2, 2)
    return segs[np.linalg.norm(segs[:, 1] - segs[:, 0], axis=1) > 0]


JOIN_MM = 2e-3  # cut ends closer than this meet (rounding to 1 µm moves a point by 0.7 µm; a 10 µm bridge is not cut)


def _node(segs: np.ndarray, eps: float = JOIN_MM):
    """Segments ``(n, 2, 2)`` noded: ends within ``eps`` of another line are put on it (T-junctions
    rounded off their edge), then every crossing and touch is a node. Returns the union."""
    lines = shapely.linestrings(segs)
    ends = shapely.points(np.unique(segs.reshape(-1, 2), axis=0))
    # each line snapped to the ends within eps of it only: the same snap as one
    # multiline to all ends (farther ends never move a vertex), without its n x m cost
    li, ei = shapely.STRtree(ends).query(lines, predicate="dwithin", distance=eps)
    order = np.lexsort((ei, li))
    has, rank = np.unique(li[order], return_inverse=True)
    near = shapely.multipoints(ends[ei[order]], indices=rank)  # one multipoint per line with ends near it
    lines[has] = shapely.snap(lines[has], near, eps)
    return shapely.unary_union(lines)


def _noded(lw: Linework, eps: float = JOIN_MM):
    """The CUT linework as noded line parts (shapely), endpoints within ``eps`` merged."""
    segs = _snapped_segments(lw, eps)
    if len(segs) == 0:
        return np.zeros(0, dtype=object)
    return shapely.get_parts(_node(segs, eps))


def join_pieces(lw: Linework, eps: float = JOIN_MM) -> Linework:
    """Open pieces and LINEs chained end to end into closed outlines where they close (within ``eps``).

    What stays open is a cut that ends in the material (see :func:`dangling_ends`).
    """
    if all(lw.closed):
        return lw
    merged = shapely.get_parts(shapely.line_merge(shapely.union_all(_noded(lw, eps))))
    out = Linework(lw.path, layer_found=lw.layer_found)
    for g in merged:
        pts = np.asarray(g.coords)
        out.add(pts, bool(g.is_ring))
    return out


def dangling_ends(lw: Linework, eps: float = JOIN_MM) -> np.ndarray:
    """Points ``(n, 2)`` where a cut line stops without meeting another cut (farther than ``eps``).

    Every line of a valid layout bounds a part: it ends where other lines meet it. An end in
    the material is a slit cut short (the tiles stay joined) or an extra cut into a part.
    """
    parts = _noded(lw, eps)
    if len(parts) == 0:
        return np.zeros((0, 2))
    ends = np.concatenate([shapely.get_coordinates(shapely.get_point(parts, 0)),
                           shapely.get_coordinates(shapely.get_point(parts, -1))])
    owner = np.concatenate([np.arange(len(parts)), np.arange(len(parts))])
    tree = shapely.STRtree(parts)
    pi, gi = tree.query(shapely.points(ends), predicate="dwithin", distance=eps)
    other = np.zeros(len(ends), dtype=bool)
    other[pi[gi != owner[pi]]] = True
    # a closed part meets itself at its ends
    ring = shapely.is_closed(parts)[owner]
    return ends[~other & ~ring]


def recover_polygons(lw: Linework, al: Allowances, sheet: int = 1,
                     frame_tiles: np.ndarray | None = None) -> tuple[np.ndarray, str]:
    """Tile regions (shapely polygons) from one file's CUT linework, and the method used.

    ``frame_tiles``: the design tiles where the manifest puts them (its sheet frame), to find the
    declared ligaments on a sheet that was moved or turned since.
    """
    if not lw.polylines:  # e.g. a sheet that holds only the reference square
        return np.zeros(0, dtype=object), "nothing to recover"
    hinge = al.hinge
    if hinge != "tape":
        joined = join_pieces(lw)
        if hinge == "plain":  # no manifest: outlines that all close are separate tiles (or, nested, one
            # ligament sheet), else in-place linework
            rings = joined.subset(i for i, c in enumerate(joined.closed) if c)
            n_open = len(joined.closed) - len(rings.closed)
            # a sheet piece with holes stays one even with a few stray cuts across it (they are checked later)
            hinge = "ligament" if n_open < len(rings.closed) and _nested(rings) else \
                "separate" if not n_open else "tape"
        if hinge != "tape":  # stray open cuts are left out here and reported as cut ends in the material
            lw = joined.subset(i for i, c in enumerate(joined.closed) if c)
    if hinge == "tape":
        segs = _snapped_segments(lw, JOIN_MM)
        if len(segs) == 0:
            return np.zeros(0, dtype=object), "polygonize"
        noded = _node(segs)
        faces = shapely.get_parts(shapely.polygonize(shapely.get_parts(noded)))
        return faces, "polygonize of the noded linework"
    rings = [shapely.Polygon(p) for p, c in zip(lw.polylines, lw.closed) if c]
    if len(rings) != len(lw.polylines):
        raise VerifyError(f"{lw.path}: {len(lw.polylines) - len(rings)} open CUT polylines in a {al.hinge} "
                          f"layout, where every outline must be closed")
    polys = shapely.make_valid(np.array(rings, dtype=object))
    if hinge == "separate":
        out = shapely.buffer(polys, -al.kerf_offset, join_style="mitre", mitre_limit=10.0) if al.kerf_offset \
            else polys
        return shapely.get_parts(out[~shapely.is_empty(out)]), "closed outlines minus the kerf offset"
    material = _material(polys, al.kerf_offset)
    feats = [_feature_geometry(f["polygon"]) for f in al.hinge_features
             if f.get("polygon") and int(f.get("sheet", 1)) == sheet]
    strips = shapely.unary_union(feats) if feats else None
    # a file rounded to 1 µm may keep a hairline of material beside a declared strip: an opening at the
    # join tolerance drops it (and leaves convex tiles exactly as they are)
    parts = _hairline_free(material.difference(strips)) if strips is not None else np.zeros(0, dtype=object)
    # the declared strips (in the manifest's sheet frame) cut the piece into tiles where the sheet was not moved
    def cuts_tiles(parts) -> bool:
        return (shapely.area(parts) > 1.0).sum() >= max(2, len(feats) // 4)

    if strips is not None and cuts_tiles(parts):
        parts = _on_cut_edges(parts, material)
        how = "material minus the declared ligaments, corners on the cut edges"
    else:  # the ligaments are the strips an opening removes, wherever the sheet was moved
        parts = _on_cut_edges(_open_ligaments(material, al.ligament_width), material)
        how = "material opened to drop the ligaments, corners on the cut edges"
        # only when the opening left tiles joined: on a symmetric lattice the motion can be a quarter turn off
        short = frame_tiles is not None and (shapely.area(parts) > 1.0).sum() < len(frame_tiles)
        moved = _declared_strips_moved(parts, strips, frame_tiles, al) if short else None
        if moved is not None:
            again = _hairline_free(material.difference(moved))
            if cuts_tiles(again):
                parts, how = _on_cut_edges(again, material), "material minus the declared ligaments, moved with the sheet"
    if al.tile_shrink:
        parts = shapely.buffer(parts, al.tile_shrink, join_style="mitre", mitre_limit=10.0)
    return parts, how + ", grown by the tile shrink"


def _material(polys: np.ndarray, kerf_offset: float):
    """A ligament sheet's material: outer loops minus the loops inside them, less the kerf offset."""
    tree = shapely.STRtree(polys)
    inside = np.zeros(len(polys), dtype=bool)
    a, b = tree.query(polys, predicate="contains_properly")
    inside[b[a != b]] = True
    material = shapely.difference(shapely.unary_union(polys[~inside]), shapely.unary_union(polys[inside]))
    if kerf_offset:
        material = material.buffer(-kerf_offset, join_style="mitre", mitre_limit=10.0)
    return material


def sheet_material(lw: Linework, kerf_offset: float):
    """The material of a ligament sheet's CUT linework (its closed outlines)."""
    joined = join_pieces(lw)
    rings = [shapely.Polygon(p) for p, c in zip(joined.polylines, joined.closed) if c]
    return _material(shapely.make_valid(np.array(rings, dtype=object)), kerf_offset)


EDGE_ON_MM = 0.02  # a cut edge bounds an opened tile core when its midpoint is this close to the core


def _on_cut_edges(parts: np.ndarray, material) -> np.ndarray:
    """Opened tile cores as quads whose sides lie on the material's own cut edges.

    An opening leaves each tile's sides exact away from the ligament roots, but a root leaves a
    bump (or, at a mitre, a spike) that can pull a corner off. Each core's coarse quad is kept only
    to say which side is which: every side is put on the longest cut edge of the material that runs
    along it (parallel within 10°) with its midpoint on the core, and the corners are where those
    lines meet. Cores with no such edge on some side are left as they are. Vectorised over all
    (core, edge) pairs; ties between equally long edges go to the first the STRtree query lists.
    """
    if not len(parts):
        return parts
    xy, ring = shapely.get_coordinates(shapely.get_rings(shapely.get_parts(material)), return_index=True)
    same = ring[1:] == ring[:-1]
    segs = np.stack([xy[:-1][same], xy[1:][same]], 1)
    segs = segs[np.linalg.norm(segs[:, 1] - segs[:, 0], axis=1) > 0]
    mids = shapely.points(segs.mean(axis=1))
    out = np.array(parts, dtype=object)
    rings = shapely.get_exterior_ring(out)
    pi, si = shapely.STRtree(mids).query(rings, predicate="dwithin", distance=EDGE_ON_MM)
    # one pass over every (part, cut edge) pair: the coarse quad of each part that has pairs
    K = len(out)
    Q = np.full((K, 4, 2), np.nan)
    has_q = np.zeros(K, bool)
    for k in np.unique(pi):
        if out[k].geom_type == "Polygon":
            q = quad_corners(out[k])
            if q is not None:
                Q[k], has_q[k] = q, True
    keep = has_q[pi]
    pi, si = pi[keep], si[keep]
    q = Q[pi]  # (P, 4, 2) the quad of each pair's part
    e = segs[si, 1] - segs[si, 0]
    elen = np.linalg.norm(e, axis=1)
    side = np.roll(q, -1, 1) - q
    slen = np.linalg.norm(side, axis=-1)
    m = segs[si].mean(axis=1)
    dist = np.stack([point_segment_distance(m, q[:, i], q[:, (i + 1) % 4]) for i in range(4)], 1)
    along = np.abs(geometry.cross2(e[:, None, :], side)) <= 0.17 * elen[:, None] * slen
    dist = np.where(along & (dist <= 0.1 * slen), dist, np.inf)
    which = np.where(np.isfinite(dist).any(axis=1), dist.argmin(axis=1), -1)
    # per (part, side) the longest edge, the first of equals in query order (as argmax picks)
    ok = which >= 0
    order = np.lexsort((np.arange(len(pi))[ok], -elen[ok], which[ok], pi[ok]))
    idx = np.flatnonzero(ok)[order]
    key = pi[idx] * 4 + which[idx]
    first = np.r_[True, key[1:] != key[:-1]]
    best = np.full((K, 4), -1)
    best.reshape(-1)[key[first]] = idx[first]
    full = (best >= 0).all(axis=1)
    ks = np.flatnonzero(full)
    b = best[ks]  # (n, 4) pair index of each side's line
    P0, D = segs[si[b], 0], e[b]  # (n, 4, 2)
    p1, d1 = np.roll(P0, 1, axis=1), np.roll(D, 1, axis=1)  # side i-1 meets side i at corner i
    den = geometry.cross2(d1, D)
    par = np.abs(den) < 1e-9 * np.linalg.norm(d1, axis=-1) * np.linalg.norm(D, axis=-1)
    with np.errstate(divide="ignore", invalid="ignore"):
        C = p1 + (geometry.cross2(P0 - p1, D) / den)[..., None] * d1
    qk = Q[ks]
    size = np.linalg.norm(qk - qk.mean(1, keepdims=True), axis=-1).max(axis=1)
    good = ~par.any(axis=1) & (np.linalg.norm(C - qk, axis=-1).max(axis=1) <= 0.5 * size)
    for k, c in zip(ks[good], C[good]):
        out[k] = shapely.Polygon(c)
    return out


def _hairline_free(g) -> np.ndarray:
    """The parts of ``g`` after an opening at the join tolerance (drops 1 µm hairlines, keeps convex parts)."""
    g = g.buffer(-JOIN_MM, join_style="mitre", mitre_limit=UNDO_MITRE).buffer(JOIN_MM, join_style="mitre",
                                                                             mitre_limit=UNDO_MITRE)
    return shapely.get_parts(g)


def _declared_strips_moved(parts, strips, frame_tiles, al: Allowances):
    """The declared ligaments moved with the sheet: the rigid motion that takes the manifest's tile
    placement onto the tiles an opening found, applied to the strips. None if it cannot be found."""
    if strips is None or frame_tiles is None or not len(parts):
        return None
    grown = shapely.buffer(parts, al.tile_shrink, join_style="mitre", mitre_limit=10.0) if al.tile_shrink else parts
    quads, _ = quads_of(grown)
    a, res, _, theta, t = match_in_place(frame_tiles, quads)
    if (a >= 0).sum() < max(3, len(frame_tiles) // 2):
        return None
    from shapely import affinity

    return affinity.translate(affinity.rotate(strips, theta, origin=(0, 0), use_radians=True), t[0], t[1])


def _nested(lw: Linework) -> bool:
    """Whether a closed outline holds another (the outline of one sheet piece and its holes)."""
    polys = np.array([shapely.Polygon(p) for p in lw.polylines], dtype=object)
    if len(polys) < 2:
        return False
    a, b = shapely.STRtree(polys).query(polys, predicate="contains_properly")
    return bool((a != b).any())


def _open_ligaments(material, width: float | None):
    """The tile cores of a ligament sheet: an opening (mitre: convex tiles come back exactly) of
    radius above half the ligament width drops the strips: the smallest radius (x1.25 steps, from
    0.6 times the declared width, else from 10 µm) after which the piece count no longer grows."""
    def opened(r):
        g = material.buffer(-r, join_style="mitre", mitre_limit=10.0).buffer(r, join_style="mitre",
                                                                                   mitre_limit=10.0)
        parts = shapely.get_parts(g)
        return parts[shapely.area(parts) > 4 * r * r]
    r = 0.6 * width if width else 0.01  # a declared width is where the search starts
    best, first = opened(r), r
    while r < 5.0:
        r *= 1.25
        nxt = opened(r)
        if len(nxt) < len(best) and len(best) > 1:
            break
        if len(nxt) > len(best):
            best, first = nxt, r
    margin = opened(1.5 * first)  # clear of the strips' roots, when that keeps every tile
    return margin if len(margin) == len(best) else best


def _choose_cut(candidates: list[Linework], al: Allowances, sheet: int, D: np.ndarray, L: float,
                tol: float) -> Linework:
    """The candidate linework (a colour class of a file without a CUT layer) that forms the most
    design tiles; with one candidate, that one."""
    if len(candidates) == 1:
        return candidates[0]
    best, score = candidates[0], -1
    for lw in candidates:
        try:
            polys, _ = recover_polygons(lw, al, sheet)
        except VerifyError:
            continue
        quads, bad = quads_of(polys[shapely.area(polys) > tol ** 2])
        _, res, _ = match_by_shape(D, quads, L)
        n = int((res <= max(tol, 0.05 * L)).sum())  # near a tile's shape (kerf offsets not yet undone)
        key = (n, -(len(quads) + bad - n))  # most tiles, then fewest other regions
        if score == -1 or key > score:
            best, score = lw, key
    return best


UNDO_MITRE = 1000.0  # undoing an offset must keep sharp corners sharp
MAX_FITTED_OFFSET_MM = 0.25  # a kerf up to 0.5 mm: any more is not a laser's kerf


MAX_FITTED_SHRINK_MM = 2.5  # a ligament sheet's tiles shrunk by up to half a 5 mm gap


def _fit_offset(R: np.ndarray, D: np.ndarray, L: float, tol: float, lo: float = 0.0) -> float:
    """The outward (mitre) offset of separate outlines from their design tiles, 0 if none is needed.

    Per matched tile the offset that explains its area, (A_cut - A) / perimeter; their median, if
    it lies within [0, MAX_FITTED_OFFSET_MM]. Each tile's congruence is still checked after it is undone.
    """
    a, _, _ = match_by_shape(D, R, L)
    ok = a >= 0
    if not ok.any():
        return 0.0
    A = np.abs(geometry.signed_areas(D[a[ok]]))
    P = geometry.edge_lengths(D[a[ok]]).sum(axis=1)
    # a mitre offset k of a convex quad has area A + P k + k^2 sum cot(alpha/2): the root near the
    # first-order k (that alone is 0.02 mm off for a 0.7 mm shrink of 20 mm tiles)
    c2 = (1.0 / np.tan(0.5 * geometry.corner_angles(D[a[ok]]))).sum(axis=1)
    dA = np.abs(geometry.signed_areas(R[ok])) - A
    disc = np.maximum(P * P + 4 * c2 * dA, 0.0)
    k_each = np.where(np.abs(c2) > 1e-12, 2 * dA / (P + np.sqrt(disc)), dA / P)
    k = float(np.median(k_each))
    return k if 0.1 * tol < abs(k) and lo <= k <= MAX_FITTED_OFFSET_MM else 0.0


def _set_reference_aside(quads: np.ndarray, D: np.ndarray, L: float, tol: float) -> tuple[np.ndarray, float | None]:
    """Take out the reference square (a square that is no design tile, the largest such), by geometry.

    fabkiri cuts an uncompensated square beside the parts so the kerf can be measured; a file
    moved, turned or without its manifest still has it. Returns the other quads and its side.
    """
    if not len(quads):
        return quads, None
    e = geometry.edge_lengths(quads)
    diag = np.linalg.norm(quads[:, 2] - quads[:, 0], axis=1), np.linalg.norm(quads[:, 3] - quads[:, 1], axis=1)
    square = (e.max(axis=1) - e.min(axis=1) <= tol) & (np.abs(diag[0] - diag[1]) <= tol)
    if not square.any():
        return quads, None
    _, res, _ = match_by_shape(D, quads[square], L)
    cand = np.flatnonzero(square)[res > tol]
    if not len(cand):
        return quads, None
    k = int(cand[np.argmax(e[cand].mean(axis=1))])
    return np.delete(quads, k, axis=0), float(e[k].mean())


def _feature_geometry(poly: Any):
    """A hinge feature: one ring ``[[x, y], ...]`` or several ``[[[x, y], ...], ...]``."""
    try:
        arr = np.asarray(poly, dtype=float)
        if arr.ndim == 2 and arr.shape[1] == 2:
            return shapely.Polygon(arr)
        return shapely.MultiPolygon([shapely.Polygon(np.asarray(r, dtype=float)) for r in poly])
    except (TypeError, ValueError) as exc:
        raise VerifyError(f"malformed hinge feature polygon in the manifest ({exc})") from None


def quad_corners(poly: shapely.Polygon, eps: float = SNAP_MM) -> np.ndarray | None:
    """The four corners (CCW) of a recovered tile region, or None.

    Collinear and duplicate vertices (T-junctions, noding points) are dropped;
    if more than four corners remain (bevelled or notched corners), the
    polygon is simplified to four corners, then each corner is moved to where
    the longest original edges along its two sides meet.
    """
    if poly.is_empty or poly.geom_type != "Polygon":
        return None
    pts = np.asarray(poly.exterior.coords)[:-1]
    if shapely.LinearRing(pts).is_ccw is False:
        pts = pts[::-1]

    changed = True
    while changed and len(pts) > 3:
        changed = False
        prv, nxt = np.roll(pts, 1, 0), np.roll(pts, -1, 0)
        d = point_segment_distance(pts, prv, nxt)
        dup = np.linalg.norm(pts - prv, axis=1) <= eps
        bad = (d <= eps) | dup
        if bad.any():
            k = int(np.flatnonzero(bad)[0])
            pts = np.delete(pts, k, axis=0)
            changed = True
    if len(pts) == 4:
        return pts
    if len(pts) < 4:
        return None
    # more than four corners (bevelled or notched corners): drop the vertex
    # that costs the least area until four remain (Visvalingam-Whyatt) ...
    keep = list(range(len(pts)))
    while len(keep) > 4:
        q = pts[keep]
        prv, nxt = np.roll(q, 1, 0), np.roll(q, -1, 0)
        cost = np.abs(geometry.cross2(prv - q, nxt - q))
        keep.pop(int(np.argmin(cost)))
    coarse = pts[keep]
    # ... then put each corner where the longest original edges along its two
    # sides meet, which restores an apex cut off by a bevel or notch
    e = np.roll(pts, -1, 0) - pts
    elen = np.linalg.norm(e, axis=1)
    mid = pts + 0.5 * e
    lines = []
    for i in range(4):
        a, b = coarse[i], coarse[(i + 1) % 4]
        d = b - a
        dl = np.linalg.norm(d)
        if dl == 0:
            return None
        # parallel within 10° (quad corners are far sharper turns) and close to the side
        along = (np.abs(geometry.cross2(e, d)) <= 0.17 * elen * dl) & (geometry.dot2(e, d) > 0)
        near = np.abs(geometry.cross2(mid - a, d)) / dl <= 0.1 * dl
        cand = np.flatnonzero(along & near)
        k = cand[np.argmax(elen[cand])] if len(cand) else None
        lines.append((a, d) if k is None else (pts[k], e[k]))
    out = []
    for i in range(4):
        (p1, d1), (p2, d2) = lines[i - 1], lines[i]
        den = geometry.cross2(d1, d2)
        if abs(den) < 1e-9 * np.linalg.norm(d1) * np.linalg.norm(d2):
            out.append(coarse[i])
            continue
        x = p1 + geometry.cross2(p2 - p1, d2) / den * d1
        size = np.linalg.norm(coarse - coarse.mean(0), axis=1).max()
        out.append(x if np.linalg.norm(x - coarse[i]) <= 0.5 * size else coarse[i])
    return np.asarray(out)


def quads_of(polys: np.ndarray) -> tuple[np.ndarray, int]:
    """Corners ``(n, 4, 2)`` of recovered regions and how many are not quads.

    Plain four-vertex rings take a vectorised path; the rest go through
    :func:`quad_corners`.
    """
    polys = np.asarray(polys, dtype=object)
    if len(polys) == 0:
        return np.zeros((0, 4, 2)), 0
    simple = (shapely.get_type_id(polys) == 3) & (shapely.get_num_interior_rings(polys) == 0)
    rings = shapely.get_exterior_ring(polys[simple])
    four = np.zeros(len(polys), dtype=bool)
    out = []
    if len(rings):

        xy, ring = shapely.get_coordinates(rings, return_index=True)
        n = np.bincount(ring, minlength=len(rings))
        start = np.concatenate([[0], np.cumsum(n)[:-1]])
        last = start + n - 1  # the closing repeat of the first point
        keep = np.ones(len(xy), dtype=bool)
        keep[last] = False
        pos = np.arange(len(xy))
        m = n - 1  # distinct points per ring
        local = pos - start[ring]
        prv = start[ring] + (local - 1) % np.maximum(m[ring], 1)
        nxt = start[ring] + (local + 1) % np.maximum(m[ring], 1)
        # drop collinear and repeated vertices (T-junction and noding points) in one pass
        d = point_segment_distance(xy, xy[prv], xy[nxt])
        dup = np.linalg.norm(xy - xy[prv], axis=1) <= SNAP_MM
        keep &= ~((d <= SNAP_MM) | dup)
        cnt = np.bincount(ring[keep], minlength=len(rings))
        ok4 = cnt == 4
        if ok4.any():
            C = xy[keep & ok4[ring]].reshape(-1, 4, 2)
            cw = geometry.signed_areas(C) < 0
            C[cw] = C[cw, ::-1]
            out.append(C)
            four[np.flatnonzero(simple)[ok4]] = True
    bad = 0
    rest = [quad_corners(p) for p in polys[~four]]
    good = [q for q in rest if q is not None]
    bad = len(rest) - len(good)
    if good:
        out.append(np.asarray(good))
    return (np.concatenate(out) if out else np.zeros((0, 4, 2))), bad


# ------------------------------------------------------------------ matching


def _shift_fit(D: np.ndarray, R: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Best cyclic corner shift of R onto D (per pair) and the max corner residual
    after a proper rigid fit. ``D``, ``R``: (n, 4, 2)."""
    from .geom import tile_kabsch

    best = np.full(len(D), np.inf)
    shift = np.zeros(len(D), dtype=np.int64)
    for s in range(4):
        _, res = tile_kabsch(D, np.roll(R, -s, axis=1))
        better = res < best
        best[better], shift[better] = res[better], s
    return best, shift


def _mirror(R: np.ndarray) -> np.ndarray:
    M = R.copy()
    M[..., 0] *= -1
    return M[:, ::-1]


def _descriptor(C: np.ndarray, L: float) -> np.ndarray:
    """Rigid-motion and corner-shift invariant shape key of quads.

    Sorted edge lengths and angles, plus a chirality term Σ l_k (θ_{k+1} - θ_k)
    (each edge times the turn from its start to its end corner), which changes
    sign under a reflection, so mirror-image tiles get different keys.
    """
    lengths = geometry.edge_lengths(C)
    angles = geometry.corner_angles(C)
    chiral = (lengths * (np.roll(angles, -1, axis=1) - angles)).sum(axis=1, keepdims=True)
    return np.concatenate([np.sort(lengths, axis=1), np.sort(angles, axis=1) * L, chiral], axis=1)


def _shape_classes(D: np.ndarray, L: float) -> np.ndarray:
    """Class label of every design quad: tiles whose shape keys agree to 1e-6 of
    the tile size share one (a tile pair split across a rounding boundary just
    forms two neighbouring classes, both among a cut tile's candidates)."""
    key = np.round(_descriptor(D, L) / (1e-6 * L)).astype(np.int64)
    return np.unique(key, axis=0, return_inverse=True)[1].ravel()


def match_by_shape(D: np.ndarray, R: np.ndarray, L: float, k: int = 8) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Assign recovered quads ``R`` to design quads ``D`` one-to-one by shape.

    Returns ``assign`` (len R, design index or -1), residual and corner shift.
    Congruent design tiles form one class (a lattice of identical tiles is one
    class, matched in linear time); each recovered quad is fitted to the k
    nearest classes and classes are filled greedily by residual. The residual
    and corner shift are then recomputed against the member actually assigned.
    """
    n = len(R)
    assign = np.full(n, -1)
    resid = np.full(n, np.inf)
    shift = np.zeros(n, dtype=np.int64)
    if n == 0 or len(D) == 0:
        return assign, resid, shift
    label = _shape_classes(D, L)
    reps = np.unique(label, return_index=True)[1]  # first member of every class
    members = {c: list(np.flatnonzero(label == c)[::-1]) for c in range(len(reps))}
    kk = min(k, len(reps))
    _, cand = cKDTree(_descriptor(D[reps], L)).query(_descriptor(R, L), k=kk)
    cand = cand.reshape(n, kk)
    ri = np.repeat(np.arange(n), kk)
    ci = cand.ravel()
    res, _ = _shift_fit(D[reps[ci]], R[ri])
    for m in np.argsort(res, kind="stable"):
        r, c = ri[m], ci[m]
        if assign[r] < 0 and members[c]:
            assign[r] = members[c].pop()
    # whatever is left (its nearest classes were full) pairs up by brute force
    used = np.zeros(len(D), dtype=bool)
    used[assign[assign >= 0]] = True
    left_r = np.flatnonzero(assign < 0)
    left_d = np.flatnonzero(~used)
    if len(left_r) and len(left_d):
        rr = np.repeat(left_r, len(left_d))
        dd = np.tile(left_d, len(left_r))
        res, _ = _shift_fit(D[dd], R[rr])
        for m in np.argsort(res, kind="stable"):
            r, d = rr[m], dd[m]
            if assign[r] < 0 and not used[d]:
                assign[r] = d
                used[d] = True
    got = np.flatnonzero(assign >= 0)
    if len(got):
        resid[got], shift[got] = _shift_fit(D[assign[got]], R[got])
    return assign, resid, shift


def match_in_place(Y: np.ndarray, R: np.ndarray, n_hyp: int = 6, alternatives: list | None = None
                   ) -> tuple[np.ndarray, np.ndarray, np.ndarray, float, np.ndarray]:
    """Match recovered quads ``R`` to design closed-state tiles ``Y`` under ONE rigid motion.

    Hypotheses pair the recovered tile nearest the layout's centre with design
    tiles nearest the design's centre (and each corner shift); the best by
    mean capped centre distance wins, then the motion is refit on all matched corners.
    Returns assign, per-tile residual, shift, rotation angle, translation. ``alternatives``: a list
    that receives every other hypothesis as good as the best within 1 µm (a symmetric sheet matches
    several ways), each refitted as (assign, residual, shift).
    """
    n = len(R)
    assign = np.full(n, -1)
    if n == 0 or len(Y) == 0:
        return assign, np.full(n, np.inf), np.zeros(n, dtype=np.int64), 0.0, np.zeros(2)
    cr, cy = R.mean(axis=1), Y.mean(axis=1)
    cap = geometry.mean_edge_length(Y)
    r0 = int(np.argmin(np.linalg.norm(cr - cr.mean(0), axis=1)))
    cands = np.argsort(np.linalg.norm(cy - cy.mean(0), axis=1))[:n_hyp]
    tree = cKDTree(cr)
    R4 = np.stack([np.roll(R, -k, axis=1) for k in range(4)])  # every corner shift, once
    best = None
    hyps = []
    for d in cands:
        for s in range(4):
            theta, t = geometry.kabsch(Y[d], np.roll(R[r0], -s, axis=0))
            moved = geometry.rotate(Y, theta) + t  # design tiles in the sheet frame
            # score: mean corner residual of the nearest tiles, capped at a tile
            # size (a hypothesis one tile off, or a near-symmetric one, loses)
            _, idx = tree.query(moved.mean(axis=1))
            err = np.linalg.norm(R4[:, idx] - moved[None], axis=-1).max(axis=2).min(axis=0)
            score = float(np.minimum(err, cap).mean())
            hyps.append((score, theta, t))
            if best is None or score < best[0]:
                best = (score, theta, t)
    _, theta, t = best
    assign, resid, shift, theta, t = _refit(Y, R, theta, t, tree)
    if alternatives is not None:
        for score, th, tt in hyps:
            if score <= best[0] + 1e-3 and (abs(geometry.wrap_angle(th - theta)) > 1e-6 or
                                            np.linalg.norm(tt - t) > 1e-3):
                alternatives.append(_refit(Y, R, th, tt, tree)[:3])
    return assign, resid, shift, float(theta), t


def _refit(Y, R, theta, t, tree):
    """Assignment under one motion, then the motion refitted on every matched corner and applied."""
    assign, resid, shift = _assign_positions(Y, R, theta, t, tree)
    ok = assign >= 0
    if ok.sum() >= 1:
        src = Y[assign[ok]]
        i = np.flatnonzero(ok)
        dst = R[i[:, None], (np.arange(4)[None, :] + shift[i][:, None]) % 4]
        theta, t = geometry.kabsch(src, dst)
        assign, resid, shift = _assign_positions(Y, R, theta, t, tree)
    return assign, resid, shift, float(theta), t


def _assign_positions(Y, R, theta, t, tree):
    n = len(R)
    moved = geometry.rotate(Y, theta) + t
    dist, idx = tree.query(moved.mean(axis=1))  # design tile -> nearest recovered tile
    assign = np.full(n, -1)
    resid = np.full(n, np.inf)
    shift = np.zeros(n, dtype=np.int64)
    # one design tile per recovered tile: the nearest claims it
    order = np.lexsort((dist, idx))
    first = np.ones(len(order), dtype=bool)
    first[1:] = idx[order[1:]] != idx[order[:-1]]
    d = order[first]
    r = idx[d]
    diff = np.stack([np.linalg.norm(np.roll(R[r], -s, axis=1) - moved[d], axis=-1).max(axis=1)
                     for s in range(4)], axis=1)
    s = diff.argmin(axis=1)
    assign[r], resid[r], shift[r] = d, diff[np.arange(len(r)), s], s
    return assign, resid, shift


# ------------------------------------------------------------------ rebuilding closed states


def place_from_shapes(pattern: Pattern, C: np.ndarray, state: int) -> tuple[np.ndarray, np.ndarray]:
    """Assemble a closed state from per-tile shapes ``C`` (T, 4, 2), any frames.

    Breadth-first from tile 0: each child turns so the edge bounding its folded
    gap lies along the parent's, and its hinge copy sits on the parent's.
    Returns the placed corners and every hinge's split (mm) — non-zero only on
    non-tree hinges, where the loops fail to close.
    """
    top = pattern.topology
    fold = top.fold(state)
    Y = C.copy()
    tree = top.spanning_tree(0)
    a_is_par = tree.parent_is_a
    cA, cB = top.hinge_corner[tree.hinges].T
    eA, eB = fold.fold_corner_ends[tree.hinges].T
    cp, ep = np.where(a_is_par, cA, cB), np.where(a_is_par, eA, eB)
    cc, ec = np.where(a_is_par, cB, cA), np.where(a_is_par, eB, eA)
    for sel in tree.levels():
        p, c = tree.parents[sel], tree.children[sel]
        hp = Y[p, cp[sel]]
        dp = Y[p, ep[sel]] - hp
        loc = C[c] - C[c, cc[sel]][:, None, :]
        dc = loc[np.arange(len(c)), ec[sel]]
        phi = np.arctan2(dp[:, 1], dp[:, 0]) - np.arctan2(dc[:, 1], dc[:, 0])
        Y[c] = geometry.rotate(loc, phi[:, None]) + hp[:, None, :]
    A, B = top.hinge_tiles.T
    cA, cB = top.hinge_corner.T
    split = np.linalg.norm(Y[A, cA] - Y[B, cB], axis=1)
    return Y, split


def assembled(pattern: Pattern, C: np.ndarray, state: int) -> tuple[np.ndarray, np.ndarray]:
    """The cut shapes ``C`` assembled into ``state``: the tree placement refined to the least-squares
    fit of every hinge at once (see :mod:`.assemble`), and every hinge's split (mm)."""
    from .assemble import fit_assembly

    Y0, _ = place_from_shapes(pattern, C, state)
    Y = fit_assembly(pattern, C, state, Y0)
    A, B = pattern.topology.hinge_tiles.T
    cA, cB = pattern.topology.hinge_corner.T
    return Y, np.linalg.norm(Y[A, cA] - Y[B, cB], axis=1)


# ------------------------------------------------------------------ entry point


def verify_layout(pattern: Pattern, layout_path: str | Path, manifest: dict[str, Any] | None = None,
                  tol_mm: float = 0.05, tol_rad: float = 1e-6) -> Report:
    """Verify a cut layout (DXF or SVG) against ``pattern`` and both closed states.

    ``manifest`` None loads ``manifest.json`` beside the layout if present; a
    plain file without one is read as closed tile outlines (or, with open
    polylines, as in-place linework), without allowances. Lengths are compared
    with ``tol_mm``; angles derived from cut shapes with ``tol_mm`` / mean edge.
    """
    path = Path(layout_path)
    if manifest is None:
        manifest = load_manifest(path)
    al = _allowances(manifest, str(path.parent / "manifest.json") if manifest is not None else str(path))
    files = _sheet_files(path, al)
    # everything is compared on the sheet, in physical mm: the design is scaled
    # up (kerf and tolerance are physical lengths, not pattern lengths)
    L = pattern.tile_size * al.scale
    tol = fabrication_tolerances(float(tol_mm), L)
    rep = Report(subject=str(path), kind="layout",
                 meta={"tol_mm": tol.length, "tol_rad": tol.angle, "tile_size_mm": L, "tolerance": tol.describe(),
                       "hinge": al.hinge,
                       "layout": al.layout, "state": al.state, "files": [str(f) for f in files.values()]})
    g = "layout"
    D = pattern.corners() * al.scale  # design shapes (deployed = cut shapes), sheet mm
    T = pattern.n_tiles

    # ---- read and recover per sheet
    sheets: dict[int, np.ndarray] = {}  # sheet -> recovered quads (n, 4, 2)
    n_lines = 0
    methods = set()
    unusable = 0
    dangling: list[np.ndarray] = []
    references: list[float] = []
    frame = _frame_tiles(pattern, al)
    linework: dict[int, Linework] = {}
    for sheet, f in files.items():
        lw = _choose_cut(read_cut_file(f).cut_classes(), al, sheet, D, L, tol.length)
        _drop_reference(lw, al.reference.get(sheet))
        linework[sheet] = lw
        n_lines += len(lw.polylines)
        on = [t for t in range(T) if al.tile_sheet.get(t, 1) == sheet]
        polys, method = recover_polygons(lw, al, sheet, frame[on] if frame is not None else None)
        methods.add(method)
        polys = polys[shapely.area(polys) > tol.length ** 2]  # double-cut hairlines are not tiles
        quads, bad = quads_of(polys)
        quads, side = _set_reference_aside(quads, D, L, tol.length)
        if side is not None:
            references.append(side)
        unusable += bad
        sheets[sheet] = quads
        dangling.append(dangling_ends(lw))
    if n_lines == 0:  # a sheet may hold only the reference square, the whole layout may not
        raise VerifyError(f"{path}: no cut geometry (nothing on layer CUT besides the reference square)")
    rep.meta["recovery"] = sorted(methods)
    if references:
        rep.meta["reference_square_mm"] = references

    in_place = al.layout == "in-place"
    sheet_piece = any(m.startswith("material") for m in methods)  # a ligament sheet: tiles in place, shrunk
    if al.layout == "auto":  # plain file: in place if the outlines tile one connected region
        allq = np.concatenate(list(sheets.values())) if sheets else np.zeros((0, 4, 2))
        if len(allq):
            u = shapely.unary_union(shapely.make_valid(shapely.polygons(allq))).buffer(tol.length)
            in_place = (len(shapely.get_parts(u)) == 1 and len(allq) > 1) or sheet_piece
        rep.meta["layout"] = "in-place" if in_place else "separate"
    fitted = None
    if al.hinge == "plain" and (not in_place or sheet_piece) and sheets:
        # no manifest declares the kerf (or the gap): take the one offset the outlines share
        fitted = _fit_offset(np.concatenate(list(sheets.values())), D, L, tol.length,
                             lo=-MAX_FITTED_SHRINK_MM if sheet_piece else 0.0)
        if fitted:
            for k, R in sheets.items():
                sheets[k], bad = quads_of(shapely.buffer(shapely.polygons(R), -fitted, join_style="mitre",
                                                         mitre_limit=UNDO_MITRE))
                unusable += bad
        rep.meta["kerf_offset_fitted_mm"] = fitted

    # ---- match
    assign_all = np.full(T, -1)  # design tile -> global recovered index
    found_on = np.full(T, -1)  # design tile -> sheet it was found on
    cut_shapes = np.full((T, 4, 2), np.nan)
    resid_pos = np.full(T, np.nan)
    extra = 0

    def closed(s: int) -> np.ndarray:
        Y = pattern.contracted.get(s)
        return (contract(pattern, s).corners if Y is None else Y) * al.scale

    state = al.state
    labelings: list[np.ndarray] = []  # cut shapes under other, equally good labelings of a symmetric sheet
    if in_place and al.hinge == "plain" and sheets:
        # no manifest declares the state: take the closed state the sheet matches
        R0 = next(iter(sheets.values()))
        fit = {s: np.nanmax(np.append(match_in_place(closed(s), R0)[1], np.nan)) for s in STATES}
        state = min(STATES, key=lambda s: fit[s] if np.isfinite(fit[s]) else np.inf)
        rep.meta["state"] = state
    Ystate = closed(state)
    for sheet, R in sheets.items():
        if in_place:
            design_ids = np.array(sorted(t for t, s in al.tile_sheet.items() if s == sheet)) if al.tile_sheet \
                else np.arange(T)
            design_ids = design_ids[design_ids < T]
            alts: list = []
            a, res, sh, _, _ = match_in_place(Ystate[design_ids], R, alternatives=alts)
            a = np.where(a >= 0, design_ids[np.maximum(a, 0)], -1)
            if len(sheets) == 1:  # a symmetric sheet: the other labelings as good as this one
                for aa, rr, ss in alts:
                    if (aa >= 0).sum() == T and np.max(rr[aa >= 0]) <= tol.length:
                        C = np.full((T, 4, 2), np.nan)
                        k = np.flatnonzero(aa >= 0)
                        C[design_ids[aa[k]]] = R[k[:, None], (np.arange(4)[None, :] + ss[k][:, None]) % 4]
                        labelings.append(C)
        else:
            free = np.flatnonzero(assign_all < 0)
            a, res, sh = match_by_shape(D[free], R, L)
            a = np.where(a >= 0, free[np.maximum(a, 0)], -1)
        taken = (a >= 0) & (assign_all[np.maximum(a, 0)] < 0)
        extra += int(len(R) - taken.sum())
        r = np.flatnonzero(taken)
        d = a[r]
        assign_all[d] = r
        found_on[d] = sheet
        cut_shapes[d] = R[r[:, None], (np.arange(4)[None, :] + sh[r][:, None]) % 4]  # corner shift
        if in_place:
            resid_pos[d] = res[r]
    missing = np.flatnonzero(assign_all < 0)
    got = T - len(missing)
    rep.add(Check(f"{g}: tiles recovered", ok=not len(missing) and not extra and not unusable,
                  value=got, tol=T, unit="count", op="==", group=g,
                  worst=f"tile {int(missing[0])}" if len(missing) else None,
                  detail=(f"{got} of {T} design tiles found; missing {missing[:20].tolist()}; "
                          f"{extra} unmatched cut regions; {unusable} regions that are not quads")))
    have = assign_all >= 0

    # ---- (a) congruence of every cut tile with its design tile
    cong = np.full(T, np.nan)
    mirrored: list[int] = []
    if have.any():
        from .geom import leave_one_out_residual

        fit = leave_one_out_residual(D[have], cut_shapes[have])
        dl = np.abs(geometry.edge_lengths(cut_shapes[have]) - geometry.edge_lengths(D[have])).max(axis=1)
        cong[have] = np.maximum(fit, dl)
        bad = np.flatnonzero(have)[cong[have] > tol.length]
        if len(bad):
            mres, _ = _shift_fit(D[bad], _mirror(cut_shapes[bad]))
            mirrored = bad[mres <= np.maximum(tol.length, 0.5 * cong[bad])].tolist()
    worst_cong = int(np.nanargmax(cong)) if have.any() else None
    rep.add(measured(f"{g}: (a) cut tiles congruent to design", float(np.nanmax(cong)) if have.any() else np.nan,
                     tol.length, "mm", worst=f"tile {worst_cong}" if worst_cong is not None else None, group=g,
                     detail=(f"mirrored tiles {mirrored}; " if mirrored else "")
                     + "largest corner offset from a proper rigid fit of the other corners, and edge-length change"))

    # ---- (b) in place: the sheet is the declared closed state
    if in_place:
        rep.add(measured(f"{g}: (b) in place = closed state {state}",
                         float(np.nanmax(resid_pos)) if have.any() else np.nan, tol.length, "mm",
                         worst=f"tile {int(np.nanargmax(resid_pos))}" if have.any() else None, group=g,
                         detail="corner distance to the design's closed state under one rigid motion per sheet"))
        if have.all():
            layout_state = np.stack([cut_shapes[d] for d in range(T)]) if len(sheets) == 1 else None
            if layout_state is not None:
                for chk in closed_state_checks(pattern, layout_state, state, tol):
                    if "congruent" in chk.name or "loop closure" in chk.name:
                        continue
                    chk.name = f"{g}: (b) sheet {chk.name}"
                    chk.group = g
                    rep.add(chk)

    # ---- (c) reassemble by the hinge correspondence
    rebuild = [3 - state] if in_place else list(STATES)
    for s in rebuild:
        name = f"{g}: (c) state {s} from cut tiles"
        if not have.all():
            rep.add(Check(f"{name}: loop closure", ok=False, value=None, tol=tol.length, unit="mm", group=g,
                          detail="cannot reassemble: tiles are missing"))
            continue
        Y, split = assembled(pattern, cut_shapes, s)
        rep.add(measured(f"{name}: loop closure", float(split.max(initial=0.0)), tol.length, "mm",
                         worst=f"hinge {int(np.argmax(split))}" if len(split) else None, group=g,
                         detail="hinge split of the least-squares assembly of the cut tiles"))
        for chk in closed_state_checks(pattern, Y, s, tol):
            if "congruent" in chk.name:
                continue
            chk.name = f"{name}: {chk.name.split(': ', 1)[1]}"
            chk.group = g
            rep.add(chk)

    # ---- every cut runs its full length: no cut ends inside the material
    ends = np.concatenate(dangling) if dangling else np.zeros((0, 2))
    rep.add(_dangling_check(ends, cut_shapes, have, g, tol.length))

    # ---- (d) every hinge present
    top = pattern.topology
    A, B = top.hinge_tiles.T
    present = have[A] & have[B]
    why = "both tiles cut"
    if in_place and present.any():
        cA, cB = top.hinge_corner.T
        ok = np.zeros(len(A), dtype=bool)
        sel = np.flatnonzero(present)
        ok[sel] = np.linalg.norm(cut_shapes[A[sel], cA[sel]] - cut_shapes[B[sel], cB[sel]], axis=1) <= tol.length
        cross = found_on[A] != found_on[B]  # split along cut lines onto two sheets
        ok |= cross
        present &= ok
        why = "both tiles cut, hinge corners coincide on the sheet"
        if (cross & present).any():
            why += f" ({int((cross & present).sum())} hinges cross sheets)"
    if al.hinge == "ligament":
        listed = {int(f.get("hinge", -1)) for f in al.hinge_features if f.get("polygon")}
        h_idx = np.arange(len(A))
        split = np.isin(h_idx, list(al.cross_sheet)) & (found_on[A] != found_on[B])
        present &= np.isin(h_idx, list(listed)) | split
        why += ", a ligament listed"
        if split.any():
            why += f" or the hinge declared split across sheets ({int(split.sum())}, to be joined by hand)"
    absent = np.flatnonzero(~present)
    rep.add(Check(f"{g}: (d) every hinge present", ok=not len(absent), value=int(len(absent)), tol=0,
                  unit="count", group=g, worst=f"hinge {int(absent[0])}" if len(absent) else None,
                  detail=f"{len(absent)} of {len(A)} hinges missing ({why})" if len(absent) else why))
    _physical_checks(rep, pattern, al, files, linework, cut_shapes, have, found_on, sheet_piece, in_place,
                     fitted, g, labelings)
    return rep


def _physical_checks(rep: Report, pattern: Pattern, al: Allowances, files: dict[int, Path],
                     linework: dict[int, Linework], cut_shapes: np.ndarray, have: np.ndarray, found_on: np.ndarray,
                     sheet_piece: bool, in_place: bool, fitted: float | None, g: str,
                     labelings: list[np.ndarray] = ()) -> None:
    """Ligaments present and uncut (a ligament sheet); tape marks at the hinges (an in-place tape layout).
    A symmetric sheet matches the design in several equally good ways (``labelings``), which put the
    hinges at different corners; its marks say which one was cut, so the best of them is reported."""
    from .physical import ligament_check, mark_status, tape_mark_check

    A, B = pattern.topology.hinge_tiles.T
    if sheet_piece and have.any():
        shrink = al.tile_shrink if al.hinge != "plain" else -(fitted or 0.0)
        kerf = al.kerf_offset if al.hinge != "plain" else 0.0
        cores = np.full(len(cut_shapes), None, dtype=object)
        cores[have] = shapely.buffer(shapely.polygons(cut_shapes[have]), -shrink, join_style="mitre",
                                     mitre_limit=10.0)
        for sheet, lw in linework.items():
            on = have & (found_on == sheet)
            hinges = np.flatnonzero(on[A] & on[B] & ~np.isin(np.arange(len(A)), list(al.cross_sheet)))
            if not len(hinges):
                continue
            c = cores.copy()
            c[~on] = None
            material = sheet_material(lw, kerf)
            if len(shapely.get_parts(material)) >= on.sum():
                continue  # no piece joins two tiles: the ligaments are not in this file (e.g. printed top faces)
            rep.add(ligament_check(pattern, material, c, on, list(lw.polylines), hinges, g))
    elif in_place and al.hinge in ("tape", "plain") and not sheet_piece and have.any():
        marks = {}
        for sheet, f in files.items():
            m = read_cut_file(f, "ENGRAVE")
            if m.layer_found:
                marks[sheet] = m.polylines
        if not marks:
            return  # no named engrave layer (a colour-only file): marks cannot be told from cuts
        # the labeling whose hinges carry the most marks (a symmetric sheet has several)
        status = [mark_status(pattern, C, have, found_on, marks) for C in [cut_shapes, *labelings]]
        k = max(range(len(status)), key=lambda i: (status[i][1].sum(), -i))
        hs, marked, room = status[k]
        if not len(hs) or not (al.hinge == "tape" and al.labels) and marked.sum() < 0.5 * len(hs):
            return  # no tape hinges on one sheet, or a layout without tape marks (the manifest does not say)
        chk = tape_mark_check(hs, marked, room, g)
        if k:
            chk.detail += " (the sheet is symmetric: hinges placed by the labeling its marks fit best)"
        rep.add(chk)


def _frame_tiles(pattern: Pattern, al: Allowances) -> np.ndarray | None:
    """Design tiles where the manifest placed them: Rot(rotation) (scaled closed-state tile) + shift."""
    if al.layout != "in-place" or len(al.tiles_placed) != pattern.n_tiles:
        return None
    Y = pattern.contracted.get(al.state)
    Y = (contract(pattern, al.state).corners if Y is None else Y) * al.scale
    out = np.empty_like(Y)
    for t, (th, shift) in al.tiles_placed.items():
        out[t] = geometry.rotate(Y[t], th) + shift
    return out


def _dangling_check(ends: np.ndarray, cut_shapes: np.ndarray, have: np.ndarray, g: str, tol: float) -> Check:
    """A cut that stops in the material: a slit short of its end leaves two tiles joined, a stray
    cut weakens a part. Names the tiles nearest the first such end."""
    worst, detail = None, "every cut line ends on another cut"
    if len(ends):
        ids = np.flatnonzero(have)
        where = []
        if len(ids):
            polys = shapely.polygons(cut_shapes[ids])
            d = shapely.distance(polys[None, :], shapely.points(ends[:1])[:, None])[0]
            near = ids[np.argsort(d)[:2]]
            where = [int(t) for t, dd in zip(near, np.sort(d)[:2]) if dd <= max(10 * tol, 1.0)]
        if len(where) == 2:
            worst = f"tiles {where[0]}/{where[1]}"
            detail = f"the slit between tiles {where[0]} and {where[1]} stops short: they stay joined"
        elif where:
            worst = f"tile {where[0]}"
            detail = f"a cut ends inside tile {where[0]}"
        else:
            detail = "a cut ends in the material"
        detail += f" ({len(ends)} cut ends in the material, first at ({ends[0, 0]:.4g}, {ends[0, 1]:.4g}) mm)"
    return Check(f"{g}: cuts run their full length", ok=not len(ends), value=int(len(ends)), tol=0, unit="count",
                 group=g, worst=worst, detail=detail)


def _sheet_files(path: Path, al: Allowances) -> dict[int, Path]:
    """Every sheet of the layout in the same format as ``path`` (just ``path`` for one sheet)."""
    fmt = path.suffix.lower().lstrip(".")
    named = {k: v.get(fmt) for k, v in al.sheet_files.items() if v.get(fmt)}
    if len(named) <= 1:
        sheet = next((k for k, v in named.items() if v == path.name), 1)
        return {sheet: path}
    if path.name not in named.values():
        raise VerifyError(f"{path}: not one of the sheets listed in the manifest ({sorted(named.values())})")
    out = {}
    for k, name in sorted(named.items()):
        f = path.parent / name
        if not f.exists():
            raise VerifyError(f"{f}: sheet {k} listed in the manifest is missing")
        out[k] = f
    return out
