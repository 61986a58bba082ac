"""Target readers: a JSON target description, a points list, CSV and SVG files."""

from __future__ import annotations

import json
import math
import re
from pathlib import Path

import numpy as np

from ... import limits
from ...errors import InputError
from ...fileio import read_input
from .curve import Target
from .shapes import SHAPES


def from_spec(spec: dict, name: str = "target") -> Target:
    """A target from a JSON description: ``{"shape": "ellipse", "aspect": 2}``,
    ``{"points": [[x, y], ...], "curve": "spline" | "polyline"}`` or ``{"svg_path": "M ..."}``.
    Optional ``"corners"``: four split parameters in [0, 1) or four points [x, y]."""
    if not isinstance(spec, dict):
        raise InputError(f"{name}: a target description must be a JSON object")
    args = {
        k: v
        for k, v in spec.items()
        if k not in ("shape", "name", "corners", "description", "size")
    }
    if "shape" in spec:
        shape = spec["shape"]
        if shape not in SHAPES:
            raise InputError(
                f"{name}: unknown shape {shape!r} (known: {', '.join(sorted(SHAPES))})"
            )
        try:
            tgt = SHAPES[shape](**args)
        except TypeError as exc:
            raise InputError(f"{name}: bad parameters for shape {shape!r} ({exc})") from None
    elif "points" in spec:
        tgt = from_points(spec["points"], spec.get("curve", "polyline"), name)
    elif "svg_path" in spec:
        tgt = from_svg_path(spec["svg_path"], name, spec.get("curve", "polyline"))
    else:
        raise InputError(f"{name}: a target needs 'shape', 'points' or 'svg_path'")
    tgt.name = spec.get("name", tgt.name if "shape" in spec else name)
    if "corners" in spec:
        tgt = _with_corners(tgt, spec["corners"], name)
    tgt.source = {k: v for k, v in spec.items() if k != "points"}
    return tgt


def _with_corners(tgt: Target, corners, name: str) -> Target:
    c = np.asarray(corners, dtype=float)
    if c.shape == (4, 2):
        u, _, _, _ = tgt.project(c)
        c = u
    elif c.shape != (4,):
        raise InputError(
            f"{name}: 'corners' must be 4 parameters or 4 points [x, y] (BL, BR, TR, TL)"
        )
    return Target(tgt.name, tgt.kind, tgt.points, corners=c, source=tgt.source)


def from_points(points, curve: str = "polyline", name: str = "points") -> Target:
    try:
        pts = np.asarray(points, dtype=float)
    except (TypeError, ValueError):
        raise InputError(f"{name}: points must be a list of [x, y] numbers") from None
    if pts.ndim != 2 or pts.shape[1] != 2:
        raise InputError(f"{name}: points must be pairs [x, y], got shape {pts.shape}")
    far = np.abs(pts).max(initial=0.0)
    if far > limits.MAX_COORD_MM and np.isfinite(far):  # a unit mistake, as in a pattern
        raise InputError(
            f"{name}: a point lies {far:.3g} mm from the origin (at most {limits.MAX_COORD_MM:g} mm)"
        )
    if curve not in ("polyline", "spline"):
        raise InputError(f"{name}: curve must be 'polyline' or 'spline', not {curve!r}")
    return Target(name, curve, pts)


def from_svg_path(
    d: str, name: str = "svg", curve: str = "polyline", samples: int = 1024
) -> Target:
    """A target from an SVG path ``d`` string (first closed subpath), sampled densely."""
    try:
        from svgpathtools import parse_path
    except ImportError as exc:  # pragma: no cover - declared dependency
        raise InputError(f"{name}: SVG paths need the svgpathtools package ({exc})") from None
    try:
        path = parse_path(d)
    except Exception as exc:  # svgpathtools raises bare errors on bad syntax
        raise InputError(f"{name}: cannot parse the SVG path ({exc})") from None
    subs = path.continuous_subpaths() if len(path) else []
    if not subs:
        raise InputError(f"{name}: the SVG path is empty")
    sub = subs[0]
    lengths = np.array([seg.length() for seg in sub])
    pts = []
    for seg, length in zip(sub, lengths):
        if type(seg).__name__ == "Line":
            pts.append(seg.start)
            continue
        k = max(2, int(round(samples * length / lengths.sum())))
        pts.extend(seg.point(t) for t in np.linspace(0, 1, k, endpoint=False))
    z = np.array(pts, dtype=complex)
    xy = np.stack([z.real, -z.imag], -1)  # SVG's y axis points down
    return Target(name, curve, xy)


def read_svg(path: Path, curve: str = "polyline") -> Target:
    """The one closed curve of an SVG file in mm, as drawn (:func:`~fabkiri.exchange.svg.outline_path`): its
    transforms and the file's units applied."""
    # the cut drawings' SVG module, loaded here: a design of a named target or points reads no SVG
    from ...exchange.svg import outline_path

    found = outline_path(path)
    if found is None:
        raise InputError(
            f"{path}: the SVG draws no curve (a <path>, <rect>, <circle>, <ellipse> or <polygon>)"
        )
    d, mm = found
    return from_svg_path(d, path.stem, curve).transformed(mm)


def read_dxf(path: Path) -> Target:
    """The one closed outline of a DXF drawing, in mm (:func:`~fabkiri.exchange.dxf.outline.dxf_outline`)."""
    # the cut drawings' DXF reader (ezdxf), loaded here as the SVG one is above
    from ...exchange.dxf.outline import dxf_outline

    return from_points(dxf_outline(path), "polyline", path.stem)


def read_points_file(path: Path) -> Target:
    """CSV (``x,y`` per line, optional header) or JSON (list of points or a target description)."""
    text = read_input(path, max_bytes=limits.MAX_PATTERN_BYTES, what="target file")
    if path.suffix.lower() == ".json":
        try:
            data = json.loads(text)
        except json.JSONDecodeError as exc:
            raise InputError(f"{path}: malformed JSON at line {exc.lineno}: {exc.msg}") from None
        if isinstance(data, list):
            return from_points(data, "polyline", path.stem)
        return from_spec(data, path.stem)
    rows = _csv_rows(text, path)
    if not rows:
        raise InputError(f"{path}: no x,y rows")
    return from_points(rows, "polyline", path.stem)


def _fields(line: str) -> list[str]:
    """A line's fields: split at ``;`` (then a comma is a decimal comma, as spreadsheets in many
    locales write it), else at commas and white space; quotes around a field dropped."""
    if ";" in line:
        parts = [p.strip().replace(",", ".") for p in line.split(";")]
    else:
        parts = re.split(r"[,\s]+", line)
    return [p.strip().strip("\"'") for p in parts if p.strip()]


def _xy_columns(names: list[str]) -> tuple[int, int] | None:
    """The columns a header names x and y (``x``, ``X [mm]``, ``y (mm)``), or None."""
    bare = [re.sub(r"[\s_]*[(\[].*$", "", n).strip().lower() for n in names]
    if "x" in bare and "y" in bare:
        return bare.index("x"), bare.index("y")
    return None


def _csv_rows(text: str, path: Path) -> list[list[float]]:
    """The x,y rows of a points CSV; header lines before the first row may name the x and y columns."""
    rows: list[list[float]] = []
    columns = None
    for lineno, line in enumerate(text.splitlines(), 1):
        line = line.split("#", 1)[0].strip()
        if not line:
            continue
        parts = _fields(line)
        try:
            vals = [float(p) for p in parts]
        except ValueError:
            if not rows:
                columns = _xy_columns(parts) or columns  # a header line
                continue
            raise InputError(f"{path}: line {lineno}: {line!r} is not 'x,y'") from None
        if columns is not None and len(vals) > max(columns):
            vals = [vals[columns[0]], vals[columns[1]]]
        elif len(vals) != 2:
            raise InputError(
                f"{path}: line {lineno}: {len(vals)} numbers, expected two (x,y); "
                "a header line naming the columns x and y picks them from more"
            )
        if not all(math.isfinite(v) for v in vals):
            raise InputError(f"{path}: line {lineno}: expected two finite numbers x,y")
        rows.append(vals)
    return rows
