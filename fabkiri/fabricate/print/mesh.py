"""The print front door: a closed state to printable solids, checked, as files.

:func:`build_job` asks the style's strategy object (:mod:`.printjob`, one module
per style in :mod:`.styles`) for the bodies; :func:`realise_job` makes their
solids (:mod:`.solid`); :mod:`.meshchecks` and :mod:`.topfaces` check them;
:func:`job_files` and :func:`manifest` give the bytes written. Three styles:

* ``strips`` – one flat flexible strip per hinge (for laser-cut tiles), laid
  out on as many print beds as needed, each part named by its hinge;
* ``tiles-and-strips`` – rigid tiles with the strips recessed flush into
  pockets, two bodies for two materials;
* ``pinned`` – print-in-place pin joints, the two coincident hinges of a node
  stacked coaxially on four ear levels (see :mod:`.printgeom`).
"""

from __future__ import annotations

import itertools
from collections.abc import Iterable
from dataclasses import replace

import numpy as np

from ...errors import FabricationError
from ...pattern.model import Pattern
from ...verify.printmanifest import PrintManifest
from . import geometry as printgeom
from .build import PrintJob, Realised, scaled
from .checks import MeshReport, TileCheck, check_meshes, check_printed_tiles, read_back_files
from .job import STYLES, print_style
from .printers import Printer
from .solid import Body, Prism, bed_grid, float32_defects, realise, to_trimesh
from .styles.pinned import pinned_scale_range, sweep_pinned
from .topfaces import verify_printed_tiles

__all__ = [
    "STYLES",
    "Body",
    "MeshReport",
    "Prism",
    "PrintJob",
    "Realised",
    "TileCheck",
    "build_job",
    "check_meshes",
    "check_printed_tiles",
    "export_3mf",
    "job_files",
    "manifest",
    "pinned_scale_range",
    "print_plan",
    "read_back_files",
    "realise_job",
    "scaled",
    "sweep_pinned",
    "verify_printed_tiles",
]


def build_job(
    pattern: Pattern, style: str, state: int, printer: Printer, advise_scale: float | None = None
) -> PrintJob:
    """The print job of a style; with ``advise_scale`` (the scale the pattern was
    given at) a refused job says, where the style can, what would print (pinned:
    the scales that print on this bed)."""
    chosen = print_style(style)
    try:
        return chosen.build(pattern, state, printer)
    except FabricationError as exc:
        if chosen.advise is None or advise_scale is None:
            raise
        raise FabricationError(
            f"{exc}; {chosen.advise(pattern, state, printer, advise_scale)}"
        ) from None


def _realise_clean(body: Body, grid: float):
    """The body (or its first variant) whose float32 mesh is a closed 2-manifold, each
    tried as designed and then with its outlines snapped to the float32 ``grid`` (which
    merges vertices a file would weld; the exact solid is kept whenever it writes
    cleanly); the last one tried if none is (the mesh check then reports it)."""
    for b, g in itertools.product((body, *body.variants), (0.0, grid)):
        m = realise(b, g)
        if m.status().name != "NoError" or m.is_empty():
            raise FabricationError(f"body {b.name} came out empty or invalid ({m.status().name})")
        tm = to_trimesh(m)
        if float32_defects(tm) == 0:
            break
    return b, m, tm, g


def realise_job(job: PrintJob) -> Realised:
    grid = bed_grid(job.printer)
    done = [[_realise_clean(b, grid) for b in bed] for bed in job.beds]
    beds = [[replace(b, variants=()) for b, *_ in bed] for bed in done]
    job = replace(job, beds=beds)
    return Realised(
        job,
        [[d[1] for d in bed] for bed in done],
        [[d[2] for d in bed] for bed in done],
        [[d[3] for d in bed] for bed in done],
    )


# ----------------------------------------------------------------- writing


def export_3mf(scene) -> bytes:
    """A trimesh scene as a plain 3MF, one object per geometry, reproducible bytes
    (:func:`.threemf.objects_3mf`; print jobs write projects with :func:`job_files`)."""
    from .threemf import objects_3mf

    return objects_3mf(
        {name: (np.asarray(g.vertices), np.asarray(g.faces)) for name, g in scene.geometry.items()}
    )


def _parts(bed: list[Body], tms: list) -> list:
    from .threemf import Part

    return [
        Part(b.name, b.material, np.asarray(tm.vertices), np.asarray(tm.faces))
        for b, tm in zip(bed, tms)
    ]


def job_files(r: Realised, stem: str, preview: bool = True) -> dict[str, bytes]:
    """File name -> bytes of every file of a job: per bed one 3MF project (one
    object, one volume per body, see :mod:`.threemf`) and a preview PNG, and
    STLs (per body kind for tiles-and-strips, per bed otherwise)."""
    import trimesh

    from .preview import preview_png
    from .threemf import LayerChange, project_3mf

    job = r.job
    files: dict[str, bytes] = {}
    for k, (bed, tms) in enumerate(zip(job.beds, r.meshes), 1):
        suffix = "" if len(job.beds) == 1 else f"-bed{k}"
        changes = [LayerChange(z, kind, m) for z, kind, m in job.layer_changes]
        files[f"{stem}{suffix}.3mf"] = project_3mf(
            f"{stem}{suffix}", _parts(bed, tms), job.printer, changes
        )
        if preview:
            files[f"{stem}{suffix}.png"] = preview_png(
                bed, r.manifolds[k - 1], job.printer, f"{stem}{suffix} ({job.style})"
            )
        if print_style(job.style).body_per_material:
            for b, tm in zip(bed, tms):
                files[f"{stem}_{b.kind}.stl"] = tm.export(file_type="stl")
        else:  # disjoint bodies: their concatenation is still a closed 2-manifold
            both = trimesh.util.concatenate(tms)  # a Trimesh; trimesh annotates it as a Geometry
            files[f"{stem}{suffix}.stl"] = both.export(file_type="stl")  # type: ignore[call-arg]  # Geometry's needs a file
    return files


def print_plan(job: PrintJob) -> str:
    """How the job prints on its printer (one line for the user), or
    :class:`FabricationError` when it cannot print there."""
    pr = job.printer
    mats = sorted({b.material for bed in job.beds for b in bed})
    if len(mats) == 1:  # the extruder the 3MF's volumes name (threemf.model_config_xml)
        return f"one material ({mats[0]}), extruder {pr.extruder_of(mats[0])}"
    if pr.extruders >= 2:
        return (
            ", ".join(f"{m} on extruder {pr.extruder_of(m)}" for m in mats)
            + " (tool changes in one print)"
        )
    if job.layer_changes:
        T, ts = pr.tile_thickness_mm, pr.strip_thickness_mm
        swaps = " and ".join(f"z = {z:.2f} mm (load {m})" for z, _, m in job.layer_changes)
        return (
            f"one extruder: {job.style} stacked ({pr.strip_material} base sheet 0-{ts:g} mm, {pr.tile_material} "
            f"tiles {ts:g}-{T:g} mm, {pr.strip_material} top strips {T:g}-{T + ts:g} mm), colour changes (M600) "
            f"in the 3MF at {swaps}"
        )
    raise FabricationError(
        f"printer {pr.name} has one extruder and {job.style} puts {' and '.join(mats)} in the same layers (the "
        f"recessed strips share the tiles' bottom and top {pr.strip_thickness_mm:g} mm), which no pause or colour "
        "change can split; use a multi-material printer (--printer prusa-xl-2t) or --style strips "
        "(flexible strips to glue onto laser-cut tiles)"
    )


def manifest(
    r: Realised,
    rep: MeshReport,
    tiles: TileCheck | None,
    pattern_name: str,
    files: Iterable[str],
    verifier=None,
    read_back: dict | None = None,
) -> str:
    """The print's manifest (:class:`~fabkiri.verify.printmanifest.PrintManifest`) as written."""
    job = r.job
    plan = job.plan
    m = PrintManifest(
        pattern=pattern_name,
        style=job.style,
        state=job.state,
        printer=job.printer.to_dict(),
        shift_mm=[round(float(v), 6) for v in job.shift],
        layout=job.layout if print_style(job.style).has_layout else None,
        layer_changes=[
            {
                "print_z_mm": round(z, 6),
                "gcode": "M600" if k == "colour-change" else "M601",
                "load": load,
            }
            for z, k, load in job.layer_changes
        ],
        beds=[[b.name for b in bed] for bed in job.beds],
        hinges=[
            {
                "hinge": h,
                "tiles": plan.hinge_tiles[h].tolist(),
                "face": plan.face(h),
                "coincides_with": _coinciding(plan.partner, h),
                "xy": [round(float(v), 6) for v in plan.hinge_xy[h] + np.asarray(job.shift)],
            }
            for h in range(plan.n_hinges)
        ],
        files=sorted(files),
        checks={
            "meshes": rep.to_dict(),
            "files": read_back,
            "tiles": tiles.to_dict() if tiles else None,
            "verifier": verifier.to_dict() if verifier is not None else None,
        },
    )
    if job.placements:
        m.placements = job.placements
        m.assembly = (
            "glue every strip with its engraved face up, as seen from above the pattern: top-face "
            "strips on the tiles, bottom-face strips under them with the engraved face against them"
        )
        m.unlabelled_hinges = job.unlabelled
    if job.pins is not None:
        m.pins = {
            "levels_mm": [list(job.pins.levels.level(k)) for k in range(job.pins.levels.count)],
            "geometry_mm": dict(job.pins.geometry.__dict__),
            "level": _pin_level_text(job.pins),
        }
    return m.to_json()


def _pin_level_text(pins) -> dict:
    """Which ear levels each hinge's place in the coaxial stack uses (quads: bottom and top hinges)."""
    n = pins.levels.count // 2
    if n == 2:  # the two places are the strip faces' (pinslots.pin_slots)
        return {"bottom_hinges": "ear levels 0-1", "top_hinges": "ear levels 2-3"}
    hinges = {
        f"place_{j}_hinges": [int(h) for h in np.flatnonzero(pins.level == 2 * j)] for j in range(n)
    }
    return {**{f"place_{j}": f"ear levels {2 * j}-{2 * j + 1}" for j in range(n)}, **hinges}


def _coinciding(partner, h: int):
    """The hinge at hinge ``h``'s point in the printed state (None if alone), or the list of them where
    more than two meet (three at a kagome merge corner)."""
    others = printgeom.coinciding(partner, h)
    return (others[0] if len(others) == 1 else others) if others else None
