"""Printable solids described once: prisms added and subtracted in order.

Every printed body is an ordered list of prism operations (:class:`Body`), so the
meshes of :mod:`.mesh` and the STEP solids of :mod:`.cad` are the same solids.
manifold3d does the booleans and sections; trimesh holds the meshes that are written.
"""

from __future__ import annotations

import itertools
from collections.abc import Iterable
from dataclasses import dataclass

import numpy as np
import shapely
import shapely.affinity
from shapely.geometry import Polygon
from shapely.geometry.polygon import orient

from .printers import Printer

SECTION_NOISE_MM = 1e-4  # vertex noise of sliced meshes (float32 STL: ~1e-5 mm at bed size)


@dataclass(frozen=True, eq=False)
class Prism:
    """Disjoint polygons extruded from ``z0`` to ``z1``; with ``scale_top`` the
    top is scaled about ``centre`` (a frustum)."""

    polygons: tuple[Polygon, ...]
    z0: float
    z1: float
    scale_top: float = 1.0
    centre: tuple[float, float] = (0.0, 0.0)


@dataclass(frozen=True, eq=False)
class Body:
    """A named solid: prisms added and subtracted in order."""

    name: str
    kind: str  # "tile", "hinge", "tiles", "hinges"
    ops: tuple[tuple[str, Prism], ...]
    material: str = ""
    variants: tuple[
        Body, ...
    ] = ()  # the same part described otherwise, tried if this one's file is not 2-manifold


def _rings(polys: Iterable[Polygon]) -> list[np.ndarray]:
    rings = []
    for p in polys:
        for g in getattr(p, "geoms", [p]):
            if g.is_empty:
                continue
            g = orient(g, 1.0)
            rings.append(np.asarray(g.exterior.coords)[:-1])
            rings.extend(np.asarray(r.coords)[:-1] for r in g.interiors)
    return rings


def float32_grid(extent_mm: float) -> float:
    """The finest power-of-two grid (mm) whose points up to ``extent_mm`` from the origin
    float32 stores exactly (24-bit significand)."""
    return float(2.0 ** (np.ceil(np.log2(max(extent_mm, 1.0))) - 23))


def bed_grid(printer: Printer) -> float:
    """:func:`float32_grid` of everything printed on this bed (cutting prisms reach 1 mm past it)."""
    return float32_grid(max(printer.bed_mm) + 2.0)


def _manifold(prism: Prism, grid: float = 0.0):
    """The prism as a manifold; with ``grid`` its outlines are snap-rounded onto it first,
    so two distinct outline vertices never become one once written in float32 (a weld
    that leaves edges shared by four faces) and no edge is shorter than the grid."""
    import manifold3d as m3d

    polys = (
        prism.polygons
        if not grid
        else (shapely.set_precision(shapely.union_all(prism.polygons), grid),)
    )
    cs = m3d.CrossSection(_rings(polys), fillrule=m3d.FillRule.Positive)
    h = prism.z1 - prism.z0
    if prism.scale_top != 1.0:
        cx, cy = prism.centre
        return m3d.Manifold.extrude(
            cs.translate((-cx, -cy)), h, scale_top=(prism.scale_top, prism.scale_top)
        ).translate((cx, cy, prism.z0))
    return m3d.Manifold.extrude(cs, h).translate((0.0, 0.0, prism.z0))


def realise(body: Body, grid: float = 0.0):
    """The manifold3d solid of a body (outlines snapped to ``grid`` mm, see :func:`_manifold`)."""
    import manifold3d as m3d

    acc = m3d.Manifold()
    ops = [
        (op, prism) for op, prism in body.ops if any(not p.is_empty for p in prism.polygons)
    ]  # e.g. no bottom strip
    for op, run in itertools.groupby(
        ops, key=lambda o: o[0]
    ):  # a run of adds (or subs) as one batched union
        ms = [_manifold(prism, grid) for _, prism in run]
        m = ms[0] if len(ms) == 1 else m3d.Manifold.batch_boolean(ms, m3d.OpType.Add)
        acc = acc + m if op == "add" else acc - m
    return acc


def to_trimesh(manifold):
    import trimesh

    mesh = manifold.to_mesh64()
    return trimesh.Trimesh(
        np.asarray(mesh.vert_properties)[:, :3].astype(np.float64),
        np.asarray(mesh.tri_verts).astype(np.int64),
        process=False,
    )


def translate_body(body: Body, dx: float, dy: float) -> Body:
    ops = tuple(
        (
            op,
            Prism(
                tuple(shapely.affinity.translate(p, dx, dy) for p in pr.polygons),
                pr.z0,
                pr.z1,
                pr.scale_top,
                (pr.centre[0] + dx, pr.centre[1] + dy),
            ),
        )
        for op, pr in body.ops
    )
    return Body(
        body.name,
        body.kind,
        ops,
        body.material,
        tuple(translate_body(v, dx, dy) for v in body.variants),
    )


def manifold_of(mesh):
    """A mesh (trimesh, e.g. re-read from a file) as a manifold3d solid, with the
    float32 coordinates and 32-bit indices a written file holds."""
    import manifold3d as m3d

    return m3d.Manifold(
        m3d.Mesh(
            vert_properties=np.asarray(mesh.vertices, dtype=np.float32),
            tri_verts=np.asarray(mesh.faces, dtype=np.uint32),
        )
    )


def edge_defects(vertices: np.ndarray, faces: np.ndarray) -> int:
    """Edges not used by exactly two faces, plus faces with a repeated vertex,
    once the vertices are welded by position, as any STL reader does."""
    v = np.ascontiguousarray(vertices)
    _, weld = np.unique(
        v.view(np.dtype((np.void, 3 * v.dtype.itemsize))).ravel(), return_inverse=True
    )
    f = weld.reshape(-1)[np.asarray(faces)]
    degenerate = (f[:, 0] == f[:, 1]) | (f[:, 1] == f[:, 2]) | (f[:, 0] == f[:, 2])
    e = np.sort(np.concatenate([f[:, [0, 1]], f[:, [1, 2]], f[:, [2, 0]]]), axis=1).astype(np.int64)
    _, counts = np.unique(e[:, 0] * (int(weld.max(initial=0)) + 1) + e[:, 1], return_counts=True)
    return int((counts != 2).sum() + degenerate.sum())


def float32_defects(tm) -> int:
    """:func:`edge_defects` of a mesh as a file stores it (float32 coordinates)."""
    return edge_defects(np.asarray(tm.vertices, dtype=np.float32), tm.faces)


def section_polys(manifold, z: float) -> list[Polygon]:
    """The section of a solid at height ``z`` as disjoint polygons (holes kept)."""
    rings = [np.asarray(r, dtype=float) for r in manifold.slice(z).to_polygons()]
    rings = [r for r in rings if len(r) >= 3]
    if not rings:
        return []
    idx = np.repeat(np.arange(len(rings)), [len(r) for r in rings])
    lr = shapely.linearrings(np.concatenate(rings), indices=idx)
    polys = shapely.polygons(lr)
    ccw = shapely.is_ccw(lr)
    outer, holes = polys[ccw], polys[~ccw]
    if not len(holes):
        return list(outer)
    out = []
    tree = shapely.STRtree(holes)
    for o in outer:
        inside = holes[tree.query(o, predicate="contains_properly")]
        out.append(o.difference(shapely.union_all(inside)) if len(inside) else o)
    return out
