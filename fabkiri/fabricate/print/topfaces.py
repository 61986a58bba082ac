"""The printed tiles' top faces as a laser layout, checked by the layout verifier.

The tile body of a tiles-and-strips print, sectioned at its bare middle, is a
plain DXF of the printed closed state; the strips spanning the gaps, measured
on the hinge mesh, are its ligaments. :func:`verify_printed_tiles` hands both
to :func:`fabkiri.verify.verify_layout`, as ``fabkiri verify --layout`` would.
"""

from __future__ import annotations

import io

import numpy as np
import shapely

from ...errors import FabricationError
from ...pattern.model import Pattern
from ...verify.manifest import CutManifest
from . import geometry as printgeom
from .build import Realised
from .solid import manifold_of, section_polys


def top_face_dxf(r: Realised, tiles_mesh=None) -> bytes:
    """The printed tiles' outlines (section of the tile body at its bare
    mid-plane, at printed size) as a plain DXF: closed LWPOLYLINEs on ``CUT``."""
    import ezdxf

    job = r.job
    if job.style != "tiles-and-strips":
        raise FabricationError("top faces as a layout exist for tiles-and-strips only")
    man = r.manifolds[0][0] if tiles_mesh is None else manifold_of(tiles_mesh)
    doc = ezdxf.new("R2010", units=ezdxf.units.MM)
    doc.layers.add("CUT", color=1)
    msp = doc.modelspace()
    for ring in man.slice(job.z_levels()["tiles"]).to_polygons():
        msp.add_lwpolyline(
            np.asarray(ring, dtype=float).tolist(),
            format="xy",
            close=True,
            dxfattribs={"layer": "CUT"},
        )
    out = io.StringIO()
    doc.write(out)
    return out.getvalue().encode("utf-8")


BRIDGE_INSET_MM = 1e-3


def printed_bridges(r: Realised) -> list[dict]:
    """The flexible material spanning each gap, measured on the hinge mesh:
    sections of the strips at the middle of their thickness, minus the tiles,
    each attributed to the hinge whose planned strip holds it."""
    job = r.job
    assert job.strips is not None  # printed bridges are measured on strip jobs only
    tiles_m, hinges_m = r.manifolds[0]
    planned = shapely.transform(job.strips.outline, lambda c: c + np.asarray(job.shift))
    feats = []
    lv = job.z_levels()
    tiles = np.array(section_polys(tiles_m, lv["tiles"]), dtype=object)
    tile_tree = shapely.STRtree(tiles)
    top = job.strips.top
    for z, face in ((lv["bottom"], np.flatnonzero(~top)), (lv["top"], np.flatnonzero(top))):
        parts = np.array(section_polys(hinges_m, z), dtype=object)
        if (
            job.layout == "stacked" and z == lv["bottom"]
        ):  # a base sheet: each bottom strip's share of it
            mine = shapely.intersection(shapely.union_all(parts), planned[~top])
            parts = np.array([g for g in shapely.get_parts(mine) if g.area > 1e-4], dtype=object)
        # only the strips printed at this level own its sections: a bottom strip may lie under a top
        # strip of a neighbouring hinge in plan, and a point in both would leave its hinge unowned
        pi, hi = shapely.STRtree(planned[face]).query(
            shapely.point_on_surface(parts), predicate="within"
        )
        hi = face[hi]
        owner = np.full(len(parts), -1)
        once = np.bincount(pi, minlength=len(parts)) == 1
        owner[pi[once[pi]]] = hi[once[pi]]
        qi, ti = tile_tree.query(parts, predicate="intersects")
        feats += _bridge_features(parts, owner, tiles, qi, ti)
    return sorted(feats, key=lambda f: f["hinge"])


def _bridge_features(parts, owner, tiles, qi, ti) -> list[dict]:
    """Each owned strip section minus the tiles it touches, drawn a hair inside;
    the differences and insets run as one vectorised call each."""
    keep = np.flatnonzero(owner >= 0)
    order = np.argsort(qi, kind="stable")  # stable: each part's tiles in query order, as before
    firsts, starts = np.unique(qi[order], return_index=True)
    span = {int(q): (lo, hi) for q, lo, hi in zip(firsts, starts, np.append(starts[1:], len(qi)))}
    cut = [
        shapely.union_all(tiles[ti[order[slice(*span[k])]]]) if k in span else None
        for k in keep.tolist()
    ]
    has = np.array([c is not None for c in cut], dtype=bool)
    bridges = parts[keep].copy()
    if has.any():
        bridges[has] = shapely.difference(
            parts[keep][has], np.array([c for c in cut if c is not None])
        )
    live = ~shapely.is_empty(bridges)
    # drawn a hair inside the bridge, so the verifier's "material minus
    # ligaments" never leaves slivers along the tile edges it shares
    cores = shapely.buffer(bridges[live], -BRIDGE_INSET_MM, join_style="mitre")
    feats = []
    for k, core in zip(keep[live], cores):
        for piece in shapely.get_parts(core):
            if piece.geom_type != "Polygon" or piece.area < 1e-4:
                continue  # slivers where a strip edge meets a tile edge
            feats.append(
                {
                    "hinge": int(owner[k]),
                    "sheet": 1,
                    "polygon": np.asarray(piece.exterior.coords)[:-1].tolist(),
                }
            )
    return feats


def verify_printed_tiles(pattern: Pattern, r: Realised, tiles_mesh=None):
    """Run the layout verifier (:func:`fabkiri.verify.verify_layout`) on the
    printed tiles' top faces: read back as an in-place layout of the printed
    closed state whose tiles were shrunk by half the gap, at the printer's
    tolerance. Returns the verifier's :class:`~fabkiri.verify.Report`."""
    import tempfile
    from pathlib import Path

    from ...verify import verify_layout

    job = r.job
    data = top_face_dxf(r, tiles_mesh)
    manifest = CutManifest(
        hinge="ligament",
        layout="in-place",
        state=job.state,
        scale=1.0,
        kerf_offset_mm=0.0,
        tile_shrink_mm=job.plan.shrink_mm,
        mitre_limit=printgeom.MITRE_LIMIT,
        hinge_features=printed_bridges(r),
        parameters={"ligaments_in_file": False},  # the hinge mesh holds them, measured as features
    )
    with tempfile.TemporaryDirectory() as d:
        path = Path(d) / "printed-top-faces.dxf"
        path.write_bytes(data)
        rep = verify_layout(pattern, path, manifest=manifest, tol_mm=job.printer.tolerance_mm)
    rep.subject = "printed tile top faces"
    rep.meta["files"] = []
    return rep
