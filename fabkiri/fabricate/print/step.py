"""STEP export of the printed solids with build123d (optional extra ``cad``).

The solids are built from the same :class:`~fabkiri.fabricate.print.solid.Body`
descriptions as the meshes, so STEP and STL/3MF describe the same geometry
(circles are the same regular polygons). build123d (OpenCascade) is imported
lazily: ``fabkiri print`` without ``--step`` never loads it. Registered as the solid format
``step`` (:mod:`fabkiri.exchange.file_formats`), written only.
"""

from __future__ import annotations

import os
import re
import tempfile
from pathlib import Path

import numpy as np
import shapely
from shapely.geometry.polygon import orient

from ...errors import FabricationError
from ...exchange.file_formats import SolidFormat, register_format
from .solid import Body, Prism

_STAMP = re.compile(rb"(FILE_NAME\s*\(\s*'[^']*'\s*,\s*)'[^']*'")


def _b3d():
    try:
        import build123d  # noqa: F401  (a heavy import)
    except ImportError:
        raise FabricationError(
            "--step needs build123d: pip install 'fabkiri[cad]' (or pip install build123d)"
        ) from None
    return build123d


def _prism_solids(b3d, prism: Prism, polys) -> list:
    out = []
    h = prism.z1 - prism.z0
    for poly in shapely.get_parts(np.asarray(list(polys), dtype=object)):
        ring = np.asarray(orient(poly, 1.0).exterior.coords)[:-1]
        pts = [(float(x), float(y), prism.z0) for x, y in ring]
        wire = b3d.Wire.make_polygon(pts, close=True)
        if prism.scale_top != 1.0:
            cx, cy = prism.centre
            s = prism.scale_top
            top = [(cx + s * (x - cx), cy + s * (y - cy), prism.z1) for x, y, _ in pts]
            out.append(b3d.Solid.make_loft([wire, b3d.Wire.make_polygon(top, close=True)]))
        else:
            face = b3d.Face(wire)
            for hole in poly.interiors:
                hp = [(float(x), float(y), prism.z0) for x, y in np.asarray(hole.coords)[:-1]]
                face = face - b3d.Face(b3d.Wire.make_polygon(hp, close=True))
            out.append(b3d.Solid.extrude(face, b3d.Vector(0, 0, h)))
    return out


def body_solid(body: Body):
    """A build123d ``Compound`` of the body's connected parts.

    A body starts with an ``add`` of disjoint outlines (tiles or strips); each
    outline becomes its own solid and receives only the later operations that
    touch it, which keeps OpenCascade's booleans small.
    """
    b3d = _b3d()
    op0, first = body.ops[0]
    if op0 != "add":
        raise FabricationError(f"body {body.name} must start by adding material")
    later = [(op, pr) for op, pr in body.ops[1:] if pr.polygons]
    later_polys = [np.array(pr.polygons, dtype=object) for _, pr in later]
    trees = [shapely.STRtree(p) for p in later_polys]
    parts = []
    for poly in first.polygons:
        solid = _prism_solids(b3d, first, [poly])[0]
        grown = poly.buffer(1e-6)
        for (op, pr), polys, tree in zip(later, later_polys, trees):
            idx = tree.query(grown, predicate="intersects")
            if op == "add" and body.kind in ("hinges",):
                continue  # handled below: separate parts
            for s in _prism_solids(b3d, pr, polys[np.sort(idx)]):
                solid = solid + s if op == "add" else solid - s
        parts.append(solid)
    if body.kind == "hinges":  # strips are disjoint parts added in several prisms
        parts = []
        for _op, pr in body.ops:
            parts.extend(_prism_solids(b3d, pr, pr.polygons))
    return b3d.Compound(children=[p for p in parts])


def step_bytes(bodies: list[Body]) -> bytes:
    """One STEP file holding every body, with a fixed header time stamp."""
    b3d = _b3d()
    shapes = []
    for body in bodies:
        c = body_solid(body)
        c.label = body.name
        shapes.append(c)
    assembly = b3d.Compound(children=shapes)
    fd, tmp = tempfile.mkstemp(suffix=".step")
    os.close(fd)
    try:
        if not b3d.export_step(assembly, tmp):
            raise FabricationError("build123d could not write the STEP file")
        data = Path(tmp).read_bytes()
    finally:
        Path(tmp).unlink(missing_ok=True)
    return _STAMP.sub(rb"\1'1970-01-01T00:00:00'", data, count=1)


def step_volume(path: str | os.PathLike) -> float:
    """Total solid volume (mm³) of a STEP file, read back with build123d."""
    b3d = _b3d()
    shape = b3d.import_step(str(path))
    return float(sum(s.volume for s in shape.solids()))


# written only (build123d, the optional extra ``cad``); :func:`step_volume` reads a volume back
register_format(SolidFormat("step", (".step", ".stp"), write=step_bytes))
