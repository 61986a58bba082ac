"""Checks of a print job's solids and of its files as written.

The mesh check (closed, consistently wound, on the bed, no shared volume, the
style's clearances), the printed tiles against the closed state, and the
written STL/3MF re-read as a slicer would.
"""

from __future__ import annotations

import io
from dataclasses import dataclass, field
from typing import cast

import numpy as np
import shapely

from ...errors import FabricationError
from . import geometry as printgeom
from .build import Realised
from .job import print_style
from .solid import SECTION_NOISE_MM, edge_defects, float32_defects, manifold_of, section_polys


@dataclass
class MeshReport:
    """Measured properties of the meshes of one job (mm, mm³)."""

    bodies: list[dict] = field(default_factory=list)
    intersection_volume_mm3: float = 0.0
    min_clearance_mm: float | None = None
    required_clearance_mm: float = 0.0
    problems: list[str] = field(default_factory=list)
    sweep: dict | None = None  # pinned: collision sweep along the deployment path

    @property
    def ok(self) -> bool:
        return not self.problems

    def to_dict(self) -> dict:
        return {
            "ok": self.ok,
            "bodies": self.bodies,
            "intersection_volume_mm3": self.intersection_volume_mm3,
            "min_clearance_mm": self.min_clearance_mm,
            "required_clearance_mm": self.required_clearance_mm,
            "problems": self.problems,
            "deployment_sweep": self.sweep,
        }


OVERLAP_MM3 = 1e-6  # a piece of shared volume above this is an overlap


def shared_volume(a, b) -> tuple[float, float]:
    """The volume two manifolds share, in all and in its largest connected piece (mm³). Bodies that meet face
    to face (a strip in its tile's pocket) share slivers of round-off that add up with the print's size: a 16x16
    ellipse at 340 mm, 1.3e-6 mm³ in 606 pieces about 3e-10 mm thick; an overlap is judged piece by piece."""
    x = a ^ b
    if x.is_empty():
        return 0.0, 0.0
    return float(x.volume()), max(float(p.volume()) for p in x.decompose())


def check_meshes(r: Realised, vol_rtol: float = 1e-9) -> MeshReport:
    """Watertight, consistently wound, positive volume, on the bed, no two bodies
    sharing volume, and clearances between bodies that may move apart."""
    import manifold3d as m3d

    job, pr = r.job, r.job.printer
    rep = MeshReport()
    bx, by, bz = pr.bed_mm
    eps, worst = 1e-6, 0.0
    for k, (bed, ms, tms) in enumerate(zip(job.beds, r.manifolds, r.meshes), 1):
        snaps = r.snaps[k - 1] if r.snaps else [0.0] * len(bed)
        for b, m, tm, snap in zip(bed, ms, tms, snaps):
            lo, hi = tm.bounds
            info = {
                "bed": k,
                "name": b.name,
                "kind": b.kind,
                "watertight": bool(tm.is_watertight),
                "winding_consistent": bool(tm.is_winding_consistent),
                "volume_mm3": float(tm.volume),
                "manifold_volume_mm3": float(m.volume()),
                "triangles": int(len(tm.faces)),
                "bounds_mm": [lo.round(4).tolist(), hi.round(4).tolist()],
            }
            info["float32_edge_defects"] = float32_defects(tm)
            info["outlines_snapped_to_mm"] = snap  # 0: as designed; else the float32 grid it needed
            rep.bodies.append(info)
            if info["float32_edge_defects"]:
                rep.problems.append(
                    f"{b.name}: {info['float32_edge_defects']} edges not shared by exactly two faces "
                    "once written with float32 coordinates"
                )
            if not (info["watertight"] and info["winding_consistent"]):
                rep.problems.append(f"{b.name}: mesh not watertight or not consistently wound")
            if (
                not tm.volume > 0
                or abs(tm.volume - m.volume()) > vol_rtol * max(1.0, m.volume()) + 1e-6
            ):
                rep.problems.append(
                    f"{b.name}: volume {tm.volume:.6g} mm³ disagrees with the solid"
                )
            if (lo < -eps).any() or hi[0] > bx + eps or hi[1] > by + eps or hi[2] > bz + eps:
                rep.problems.append(f"{b.name}: outside the {bx:g} x {by:g} x {bz:g} mm bed")
        # bodies printed together never share volume
        if len(ms) > 1:
            if print_style(job.style).body_per_material:
                inter, piece = shared_volume(ms[0], ms[1])
            else:  # many small disjoint parts: their union loses no volume
                inter = piece = (
                    sum(m.volume() for m in ms)
                    - m3d.Manifold.batch_boolean(ms, m3d.OpType.Add).volume()
                )
            rep.intersection_volume_mm3 = max(rep.intersection_volume_mm3, float(inter))
            worst = max(worst, float(piece))
    if worst > OVERLAP_MM3:
        rep.problems.append(f"bodies overlap by {worst:.3g} mm³")
    print_style(job.style).clearances(r, rep)
    return rep


@dataclass
class TileCheck:
    """Printed tile outlines recovered from the mesh against the closed state."""

    state: int
    tolerance_mm: float
    max_deviation_mm: float
    max_overlap_mm2: float
    tiles: int
    ok: bool

    def to_dict(self) -> dict:
        return dict(self.__dict__)


def check_printed_tiles(r: Realised, tiles_mesh=None) -> TileCheck:
    """Recover each tile's outline from the printed tile mesh (section at the
    bare mid-plane, grown back by the shrink), and compare with the closed state:
    every recovered vertex within ``printer.tolerance_mm`` of its design tile
    outline and vice versa (Hausdorff), and no two recovered tiles overlapping.

    For pinned tiles the ear discs around the pivots are excluded on both sides
    (they are round by design). ``tiles_mesh`` (a trimesh, e.g. re-read from the
    STL) replaces the in-memory solid when given.
    """
    job = r.job
    style = print_style(job.style)
    if style.tiles is None:
        raise FabricationError(f"the {job.style} style prints no tiles")
    plan, pr = job.plan, job.printer
    dx, dy = job.shift
    man, z, mask = style.tiles(r, tiles_mesh)
    # mesh sections carry float noise (near-duplicate vertices where booleans meet);
    # the mitre growth would turn such a zero-length edge into a spike of up to
    # MITRE_LIMIT x the shrink, so drop vertices that deviate less than SECTION_NOISE_MM
    parts = list(shapely.simplify(np.array(section_polys(man, z), dtype=object), SECTION_NOISE_MM))
    design = shapely.transform(shapely.polygons(plan.corners), lambda c: c + np.array([dx, dy]))
    grown = (
        list(printgeom.grow_back(np.array(parts, dtype=object), plan.shrink_mm)) if parts else []
    )
    if mask is not None:
        design = np.array([g.difference(mask) for g in design], dtype=object)
        grown = [g.difference(mask) for g in grown]
    grown = [g for g in grown if not g.is_empty and g.area > 1e-6]
    # match recovered parts to design tiles by containment of a representative point
    tree = shapely.STRtree(design)
    dev = 0.0
    matched = set()
    for g in grown:
        pt = g.representative_point()
        hits = tree.query(pt, predicate="intersects")
        if len(hits) == 0:
            dev = np.inf
            continue
        t = int(hits[0])
        matched.add(t)
        dev = max(dev, shapely.hausdorff_distance(g, design[t]))
    # pinned tiles may come back in several pieces after masking; every tile must be seen
    if len(matched) != len(plan.tiles):
        dev = np.inf
    overlap = 0.0
    if len(grown) > 1:
        t2 = shapely.STRtree(grown)
        i, j = t2.query(grown, predicate="intersects")
        sel = i < j
        if sel.any():
            g = np.array(grown, dtype=object)
            overlap = float(shapely.area(shapely.intersection(g[i[sel]], g[j[sel]])).max())
    tol = pr.tolerance_mm
    ok = bool(dev <= tol and overlap <= tol * tol)
    return TileCheck(
        state=job.state,
        tolerance_mm=tol,
        max_deviation_mm=float(dev),
        max_overlap_mm2=overlap,
        tiles=len(matched),
        ok=ok,
    )


def read_back_files(files: dict[str, bytes]) -> dict[str, dict]:
    """Every STL/3MF as written, re-read by trimesh (vertices welded, as slicers
    do) and by manifold3d: watertight, every edge used by exactly two faces, one
    valid manifold per body. This, not the in-memory solid, is what the manifest reports."""
    import trimesh

    from .threemf import read_volumes

    out = {}
    for name, data in sorted(files.items()):
        ext = name.rsplit(".", 1)[-1]
        if ext not in ("stl", "3mf"):
            continue
        if ext == "3mf":  # one object of several volumes (parts): each volume is a closed body
            geoms = [trimesh.Trimesh(v, f, process=True) for _, _, _, v, f in read_volumes(data)]
        else:
            # trimesh.load is annotated as any Geometry (a Scene for some formats); an STL loads as one Trimesh
            geoms = [
                cast(trimesh.Trimesh, trimesh.load(io.BytesIO(data), file_type=ext, process=True))
            ]
        bad_edges, watertight, m3d_ok, volume = 0, True, True, 0.0
        for g in geoms:
            bad_edges += edge_defects(g.vertices, g.faces)
            watertight &= bool(g.is_watertight and g.is_winding_consistent)
            man = manifold_of(g)
            m3d_ok &= man.status().name == "NoError" and not man.is_empty()
            volume += float(g.volume)
        out[name] = {
            "meshes": len(geoms),
            "watertight": watertight,
            "edges_not_shared_by_two_faces": bad_edges,
            "manifold3d_ok": bool(m3d_ok),
            "volume_mm3": volume,
            "ok": bool(watertight and bad_edges == 0 and m3d_ok),
        }
    return out
