"""Target shapes by name or file, scaled and centred: the front door of the target modules.

A :class:`Target` (``curve.py``) is a closed counter-clockwise curve in mm
with projection, signed distance and the four-arc split used for boundary
matching (docs/algorithm.md#shape-matching); ``shapes.py`` holds the built-in shapes
and ``files.py`` the CSV, JSON and SVG readers. This module loads a
target by template name or file and re-exports the names callers use.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ... import limits
from ...errors import InputError
from ...templates import template_dir
from .curve import SIDES, Target
from .files import from_points, from_spec, from_svg_path, read_dxf, read_points_file, read_svg
from .projector import ARC_PAD, Projector
from .shapes import SHAPES, circle, ellipse, heart, polygon, rectangle, star, superellipse

__all__ = [
    "ARC_PAD",
    "DEFAULT_SIZE",
    "SHAPES",
    "SIDES",
    "TEMPLATE_DIR",
    "Projector",
    "Target",
    "circle",
    "ellipse",
    "from_points",
    "from_spec",
    "from_svg_path",
    "heart",
    "load_target",
    "named_targets",
    "polygon",
    "read_points_file",
    "read_svg",
    "rectangle",
    "star",
    "superellipse",
    "target_from_dict",
]

TEMPLATE_DIR = template_dir("targets")
DEFAULT_SIZE = 100.0  # mm, larger bounding-box dimension of a named target


def named_targets() -> list[str]:
    return sorted(p.stem for p in TEMPLATE_DIR.glob("*.json"))


def load_target(ref: str, size: float | None = None, curve: str | None = None) -> Target:
    """A target by template name (``templates/targets/NAME.json``) or file
    (``.csv``, ``.json``, ``.svg``), scaled so its larger dimension is ``size`` mm.

    Named targets default to 100 mm; files keep their own mm coordinates
    unless ``size`` is given. Every target is centred on the origin. A ``size`` that is not a length
    (negative, zero, not finite) is refused: the CLI checks ``--size``, a library caller gets it here.
    """
    if size is not None:
        limits.check_length(size, "size")
    p = Path(ref)
    named = TEMPLATE_DIR / f"{ref}.json"
    if named.exists() and not p.exists():
        tgt = read_points_file(named)
        return tgt.scaled_to(size or DEFAULT_SIZE)
    if p.suffix.lower() in (".csv", ".txt", ".json", ".svg", ".dxf") or p.exists():
        if not p.exists():
            raise InputError(f"target file {p} does not exist")
        readers = {".svg": lambda p: read_svg(p, curve or "polyline"), ".dxf": read_dxf}
        tgt = readers.get(p.suffix.lower(), read_points_file)(p)
        if curve and curve != tgt.kind:
            tgt = Target(tgt.name, curve, tgt.points, source=tgt.source)
        if size:
            return tgt.scaled_to(size)
        _check_own_size(tgt, p)
        return tgt.centred()
    raise InputError(
        f"unknown target {ref!r} (named targets: {', '.join(named_targets())}; or give a .csv/.json/.svg/.dxf file)"
    )


def _check_own_size(tgt: Target, path: Path) -> None:
    """A file read at its own coordinates must span a length, as ``size`` must (a file in metres or
    micrometres read as mm would design a pattern no other command can read)."""
    extent = float(np.ptp(tgt.points, axis=0).max())
    if not limits.MIN_LENGTH_MM <= extent <= limits.MAX_LENGTH_MM:
        raise InputError(
            f"target file {path} spans {extent:.3g} mm, outside [{limits.MIN_LENGTH_MM:g}, "
            f"{limits.MAX_LENGTH_MM:g}] mm (its coordinates are read as mm; give a size to scale it)"
        )


def target_from_dict(d: dict, name: str = "target") -> Target:
    """The :class:`Target` stored in a pattern (``Target.to_dict``): the same curve, kind and corners."""
    if not isinstance(d, dict) or "points" not in d:
        raise InputError(f"{name}: a stored target needs 'points'")
    kind = d.get("kind", "polyline")
    corners = d.get("corners")
    try:
        pts = np.asarray(d["points"], dtype=float)
        c = None if corners is None else np.asarray(corners, dtype=float)
    except (TypeError, ValueError):
        raise InputError(f"{name}: stored target points must be numbers") from None
    return Target(
        str(d.get("name", name)),
        kind if kind in ("spline", "polyline") else "polyline",
        pts,
        corners=c,
        source=dict(d.get("source") or {}),
    )
