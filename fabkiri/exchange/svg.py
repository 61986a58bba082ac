"""SVG, the cut files' second drawing format: written (svgwrite) and read (any SVG, and fast for
fabkiri's own layout).

The writer: millimetre-sized, 1 user unit = 1 mm, one group per layer. The drawing is y-up; SVG is
y-down, so every point is written as ``(x, H - y)``. Strokes are 0.1 mm (a kerf: visible in
viewers), fills none, so laser software reads every element as a vector path. No ``<text>``:
labels are strokes.

The readers: :func:`read_svg_layers` reads fabkiri's own layout (a ``<g id=LAYER>`` per layer,
straight ``M``/``L``/``Z`` paths in a millimetre viewBox) straight from its numbers, for the
writer's read-back of large sheets; :func:`read_cut_svg` reads any SVG a laser tool writes with
svgelements (transforms, curves, units, Inkscape layers), keeping only the CUT group (or the named
one) and leaving out annotation layers. Registered as the drawing format ``svg``
(:mod:`.file_formats`).
"""

from __future__ import annotations

import io
import re
import xml.etree.ElementTree as ET
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import InputError, VerifyError
from .drawing import COLORS, DECIMALS, LAYERS, SheetDrawing
from .file_formats import DrawingFormat, register_format
from .linework import MM_PER_PX, NON_CUT_LAYERS, Linework, Polylines

STROKE_MM = 0.1  # visible when rendered (0.01 exports from Inkscape as all white); colour, not width, says cut
INKSCAPE_NS = "http://www.inkscape.org/namespaces/inkscape"
SVG_NS = "{http://www.w3.org/2000/svg}"
INKSCAPE_LABEL = "{http://www.inkscape.org/namespaces/inkscape}label"


# ------------------------------------------------------------------ writing


def _num(v: float) -> str:
    s = f"{v:.{DECIMALS}f}".rstrip("0").rstrip(".")
    return "0" if s in ("-0", "") else s


def path_data(points: np.ndarray, closed: bool, height: float) -> str:
    """``M x,y L x,y ... [Z]`` with y flipped."""
    ys = np.round(height - points[:, 1], DECIMALS) + 0.0
    xy = [f"{_num(x)},{_num(y)}" for x, y in zip(points[:, 0].tolist(), ys.tolist())]
    return "M" + " L".join(xy) + (" Z" if closed else "")


def _nums(values: np.ndarray) -> list[str]:
    """:func:`_num` of many values."""
    return [
        "0" if t in ("-0", "") else t
        for t in (
            f.rstrip("0").rstrip(".") for f in map(f"{{:.{DECIMALS}f}}".format, values.tolist())
        )
    ]


def layer_paths(polylines, groups, height: float) -> list[str]:
    """The ``d`` of every path of a layer: :func:`path_data` of each polyline, the consecutive
    polylines of one group (>= 0) joined as subpaths of one path."""
    if not polylines:
        return []
    pts = np.concatenate([p for p, _ in polylines])
    xs = _nums(pts[:, 0])
    ys = _nums(np.round(height - pts[:, 1], DECIMALS) + 0.0)
    xy = [f"{x},{y}" for x, y in zip(xs, ys)]
    out: list[str] = []
    start = 0
    prev = None
    for (p, closed), g in zip(polylines, groups):
        d = "M" + " L".join(xy[start : start + len(p)]) + (" Z" if closed else "")
        start += len(p)
        if g >= 0 and g == prev:
            out[-1] += " " + d
        else:
            out.append(d)
        prev = g
    return out


def svg_bytes(sheet: SheetDrawing, colors: str = "default", stroke_mm: float = STROKE_MM) -> bytes:
    """The sheet as SVG (UTF-8)."""
    import svgwrite  # loaded with the first SVG written, not by its readers

    W, H = sheet.width, sheet.height
    dwg = svgwrite.Drawing(size=(f"{_num(W)}mm", f"{_num(H)}mm"), profile="full", debug=False)
    dwg.attribs["viewBox"] = f"0 0 {_num(W)} {_num(H)}"
    dwg.attribs["xmlns:inkscape"] = INKSCAPE_NS
    for name in LAYERS:
        stroke = COLORS[colors][name][0]
        g = dwg.g(id=name, fill="none", stroke=stroke, stroke_width=_num(stroke_mm))
        g.attribs["stroke-linejoin"] = "round"
        g.attribs["inkscape:groupmode"] = "layer"
        g.attribs["inkscape:label"] = name
        for d in layer_paths(sheet.layers[name], sheet.groups[name], H):
            g.add(dwg.path(d=d))
        dwg.add(g)
    return ('<?xml version="1.0" encoding="utf-8" ?>\n' + dwg.tostring() + "\n").encode("utf-8")


# ------------------------------------------------------------------ fabkiri's own layout


_NUM = re.compile(r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?")
_SUBPATH = re.compile(r"(?=[Mm])")


def read_svg_layers(data: bytes) -> tuple[float, float, list[float], dict[str | None, Polylines]]:
    """``(width_mm, height_mm, viewbox, layers)``; layers from ``<g id=...>`` groups, y flipped back to y-up.

    A path with several subpaths (``M ... M ...``: the SVG writes each tile's strokes as one
    path) gives one polyline per subpath.
    """
    root = ET.fromstring(data)
    w, h = root.get("width", ""), root.get("height", "")
    vb = [float(v) for v in root.get("viewBox", "").split()]
    wmm = float(w[:-2]) if w.endswith("mm") else float("nan")
    hmm = float(h[:-2]) if h.endswith("mm") else float("nan")
    H = vb[3] if len(vb) == 4 else float("nan")
    layers: dict[str | None, Polylines] = {}  # a group without an id is the layer None
    for g in root.iter(f"{SVG_NS}g"):
        name = g.get("id")
        nums: list[str] = []
        counts: list[int] = []
        closed: list[bool] = []
        for el in g:
            tag = el.tag.replace(SVG_NS, "")
            if tag == "path":
                for sub in _SUBPATH.split(el.get("d", "")):
                    if not sub.strip():
                        continue
                    found = _NUM.findall(sub)
                    nums += found
                    counts.append(len(found))
                    closed.append(sub.strip().upper().endswith("Z"))
            elif tag in ("polyline", "polygon"):
                found = _NUM.findall(el.get("points", ""))
                nums += found
                counts.append(len(found))
                closed.append(tag == "polygon")
        if not counts:
            continue
        if any(c % 2 for c in counts):
            raise ValueError(f"SVG group {name}: a path with an odd number of coordinates")
        xy = np.asarray(nums, dtype=float).reshape(-1, 2)
        pl = Polylines(np.column_stack([xy[:, 0], H - xy[:, 1]]), np.asarray(counts) // 2, closed)
        if name in layers:  # two groups with one id: one layer
            old = layers[name]
            pl = Polylines(
                np.concatenate([old.pts, pl.pts]),
                np.concatenate([old.counts, pl.counts]),
                np.concatenate([old.closed, pl.closed]),
            )
        layers[name] = pl
    return wmm, hmm, vb, layers


# ------------------------------------------------------------------ any SVG


def read_cut_svg(p: Path, layer_name: str = "CUT") -> Linework:
    import svgelements as se

    try:
        svg = se.SVG.parse(without_annotation_layers(p, layer_name), reify=True)
    except Exception as exc:  # svgelements raises many kinds on bad XML
        raise VerifyError(f"{p}: not a readable SVG file ({type(exc).__name__}: {exc})") from None
    if not svg.height:
        raise VerifyError(f"{p}: the SVG has no height; cannot flip y")
    # svgelements' own mm constant is rounded (3.7795296 px/mm, 5e-7 off); take
    # the px-per-mm factor from the declared size instead
    mm_per_px = _declared_mm(svg.values.get("height"), float(svg.height))
    height = float(svg.height) * mm_per_px
    groups = list(svg.elements(lambda e: isinstance(e, se.Group)))
    layer_of = _layers_of(groups)
    cut_found = layer_name in layer_of.values()
    shapes = [
        e
        for e in svg.elements()
        if isinstance(e, se.Shape)
        and (
            layer_of.get(id(e)) == layer_name
            if cut_found or layer_name != "CUT"
            else layer_of.get(id(e), "") not in NON_CUT_LAYERS
        )
    ]
    lw = Linework(p, layer_found=cut_found)
    for shape in shapes:
        _add_shape(
            lw, shape, layer_of.get(id(shape), ""), lambda pts: _svg_mm(pts, height, mm_per_px)
        )
    return lw


def _layers_of(groups: list) -> dict[int, str]:
    """The layer (CUT, NOTES, ...) of each shape by ``id``, from the named groups around it."""
    import svgelements as se

    def name(g: se.Group) -> str:
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
    return layer_of


def _add_shape(lw: Linework, shape, layer: str, to_mm) -> None:
    """Each subpath of ``shape`` as a polyline of ``lw`` (closed where it closes), in mm by ``to_mm``."""
    import svgelements as se

    path_ = se.Path(shape)
    colour = (
        str(shape.stroke.hex) if shape.stroke is not None and shape.stroke.value is not None else ""
    )
    pts: list[tuple[float, float]] = []
    for seg in path_.segments():
        if isinstance(seg, se.Move):
            if len(pts) >= 2:
                lw.add(to_mm(pts), False, layer, colour)
            pts = [(seg.end.x, seg.end.y)]
        elif isinstance(seg, se.Close):
            if len(pts) >= 3:
                lw.add(to_mm(pts), True, layer, colour)
            pts = []
        elif isinstance(seg, se.Line):
            pts.append((seg.end.x, seg.end.y))
        else:  # curves: sample finely (tile outlines are straight; be tolerant)
            for t in np.linspace(0, 1, 17)[1:]:
                q = seg.point(t)
                pts.append((q.x, q.y))
    if len(pts) >= 2:
        lw.add(to_mm(pts), False, layer, colour)


def without_annotation_layers(p: Path, keep: str = "CUT") -> str | io.BytesIO:
    """The SVG with its NOTES/ENGRAVE/SCORE groups removed, when it has a CUT group; else the path.

    Only the CUT group is read when there is one, and svgelements would spend
    seconds building the tens of thousands of label strokes of a 64x64 sheet.
    Kept as is (the whole file goes to svgelements) when anything could reach
    into a removed group (``<use>``, a CUT group inside an annotation group)
    or ElementTree cannot parse it (svgelements then names the problem).
    """
    try:
        root = ET.parse(p).getroot()
    except (ET.ParseError, OSError):
        return str(p)

    def name(el: ET.Element) -> str:
        return str(el.get("id") or el.get(INKSCAPE_LABEL) or "").upper()

    groups = [el for el in root.iter() if el.tag.rsplit("}", 1)[-1] == "g"]
    if not any(name(g) == keep for g in groups):
        return str(p)
    if any(el.tag.rsplit("}", 1)[-1] == "use" for el in root.iter()):
        return str(p)
    drop = {
        id(g)
        for g in groups
        if name(g) in (NON_CUT_LAYERS | {"CUT"}) - {keep}
        and not any(name(d) == keep for d in g.iter() if d.tag.rsplit("}", 1)[-1] == "g")
    }
    if not drop:
        return str(p)
    for parent in list(root.iter()):
        for child in [c for c in parent if id(c) in drop]:
            parent.remove(child)
    return io.BytesIO(ET.tostring(root))


_UNIT_MM = {
    "mm": 1.0,
    "cm": 10.0,
    "in": 25.4,
    "pt": 25.4 / 72,
    "pc": 25.4 / 6,
    "px": MM_PER_PX,
    "": MM_PER_PX,
}


def _declared_mm(attr: Any, height_px: float) -> float:
    """mm per svgelements px, from the root's declared height (e.g. '400mm')."""
    m = re.fullmatch(r"\s*([0-9.eE+-]+)\s*([a-z]*)\s*", str(attr or ""))
    if not m or m.group(2) not in _UNIT_MM or height_px <= 0:
        return MM_PER_PX
    try:
        return float(m.group(1)) * _UNIT_MM[m.group(2)] / height_px
    except ValueError:
        return MM_PER_PX


def outline_path(p: Path) -> tuple[str, float] | None:
    """The one closed curve of any SVG (a ``<path>`` subpath, ``<rect>``, ``<circle>``, ``<ellipse>``,
    ``<polygon>``) with every transform and the viewBox applied (svgelements), as path data, and mm per
    unit of it (the root's declared size; a root without a physical unit keeps its user units as mm).
    None when the file draws nothing; :class:`InputError` when it is no SVG, or draws no closed curve or
    several (which of them is the outline is the user's to say, not the first one's by chance)."""
    import svgelements as se

    try:
        svg = se.SVG.parse(str(p), reify=True)
    except Exception as exc:  # svgelements raises many kinds on bad XML
        raise InputError(f"{p}: not a readable SVG file ({exc})") from None
    height = str(svg.values.get("height") or "")
    if re.search(r"(mm|cm|in|pt|pc)\s*$", height):
        mm = _declared_mm(height, float(svg.height))
    else:
        box = svg.viewbox
        mm = box.width / float(svg.width) if box is not None and svg.width else 1.0
    curves = [
        sub
        for e in svg.elements()
        if isinstance(e, se.Shape) and not isinstance(e, se.SimpleLine)
        for sub in _curves(se.Path(e))
    ]
    if not curves:
        return None
    closed = [c for c in curves if _closed(c)]
    if len(closed) != 1:
        sizes = ", ".join(_size(c, mm) for c in (closed or curves)[:3])
        if not closed:
            raise InputError(f"{p}: no closed curve, only open ones ({sizes}); close the outline")
        more = ", ..." if len(closed) > 3 else ""
        raise InputError(
            f"{p}: {len(closed)} closed curves ({sizes}{more}); which is the outline? a target file "
            "holds one: leave only it in the file"
        )
    return closed[0].d(), mm


def _curves(path) -> list:
    """The subpaths of a shape as paths, transforms applied; a lone move (no segment) is no curve."""
    import svgelements as se

    path.reify()
    return [c for c in (se.Path(s) for s in path.as_subpaths()) if len(c) > 1]


def _closed(curve) -> bool:
    """A curve closed by ``Z``, or ending where it starts (to a millionth of its size)."""
    import svgelements as se

    x0, y0, x1, y1 = curve.bbox()
    gap = abs(complex(*curve.first_point) - complex(*curve.current_point))
    return isinstance(curve[-1], se.Close) or gap <= 1e-6 * max(x1 - x0, y1 - y0)


def _size(curve, mm: float) -> str:
    x0, y0, x1, y1 = curve.bbox()
    return f"{(x1 - x0) * mm:.3g} x {(y1 - y0) * mm:.3g} mm"


def _svg_mm(
    pts: list[tuple[float, float]], height_mm: float, mm_per_px: float = MM_PER_PX
) -> np.ndarray:
    a = np.asarray(pts, dtype=float) * mm_per_px
    a[:, 1] = height_mm - a[:, 1]
    return a


register_format(
    DrawingFormat(
        "svg", (".svg",), write=lambda sheet, colors: svg_bytes(sheet, colors), read=read_cut_svg
    )
)
