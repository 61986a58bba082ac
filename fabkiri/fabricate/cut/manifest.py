"""The manifest of a cut: every choice, sheet, tile and hinge, as the verifier reads it.

:func:`cut_manifest` fills a :class:`~fabkiri.verify.manifest.CutManifest` (the
one definition of ``manifest.json``, with its JSON Schema, shared with the
verifier that reads it back) from a finished :class:`~.cut.CutJob`.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np
import shapely

from ... import __version__
from ...exchange.drawing import snap
from ...verify.manifest import CutManifest
from ..gate import GATE_GROUPS
from . import hinges as hg

if TYPE_CHECKING:  # sheets.py builds the job and imports this module
    from .sheets import CutJob

PIERCE_S = 0.2  # time model: per path, for the head to travel and pierce


def sheet_names(job: CutJob) -> list[str]:
    """File stem of each sheet (``stem-sheetN`` when there are several)."""
    multi = len(job.sheets) > 1
    return [
        f"{job.options.stem}-sheet{sd.index}" if multi else job.options.stem for sd in job.sheets
    ]


def _sheet_rows(job: CutJob) -> list[dict[str, Any]]:
    """Per sheet: its files, tiles, paths, lengths and the time model's cutting time."""
    mat, formats = job.material, job.options.formats
    rows = []
    for sd, name in zip(job.sheets, sheet_names(job)):
        cut_len = sd.length("CUT")
        eng_len = sd.length("ENGRAVE") + sd.length("SCORE")
        paths = sd.count("CUT") + sd.count("ENGRAVE") + sd.count("SCORE")
        rows.append(
            {
                "index": sd.index,
                "width_mm": sd.width,
                "height_mm": sd.height,
                "dxf": f"{name}.dxf" if "dxf" in formats else None,
                "svg": f"{name}.svg" if "svg" in formats else None,
                "tiles": int((job.place.sheet == sd.index - 1).sum()),
                "cut_paths": sd.count("CUT"),
                "engrave_paths": sd.count("ENGRAVE"),
                "cut_length_mm": round(cut_len, 3),
                "engrave_length_mm": round(eng_len, 3),
                "cut_time_s": round(
                    cut_len / mat.cut_speed_mm_s
                    + eng_len / mat.engrave_speed_mm_s
                    + PIERCE_S * paths,
                    1,
                ),
            }
        )
    return rows


def _hinge_rows(job: CutJob) -> list[dict[str, Any]]:
    """Per hinge: its tiles, face, sheets, where its corners were placed, and its ligament."""
    top = job.pattern.topology
    A, B = top.hinge_tiles.T
    cA, cB = top.hinge_corner.T
    sheet_of, lig, letters = job.place.sheet, job.cutting.ligament, job.faces.letters()
    pos_a = snap(job.placed_corners[A, cA]).tolist()
    pos_b = snap(job.placed_corners[B, cB]).tolist()
    rows = []
    for h in range(top.n_hinges):
        row = {
            "hinge": h,
            "tiles": [int(A[h]), int(B[h])],
            "face": letters[h],
            "sheets": [int(sheet_of[A[h]]) + 1, int(sheet_of[B[h]]) + 1],
            "position": pos_a[h],  # on tile A's sheet
            "position_b": pos_b[h],  # on tile B's sheet
            "cross_sheet": bool(sheet_of[A[h]] != sheet_of[B[h]]),
        }
        if lig is not None:
            row["ligament_length_mm"] = round(float(lig.lengths[h]), 6)
            row["strain"] = round(float(lig.strains[h]), 6)
        rows.append(row)
    return rows


def _tile_rows(job: CutJob) -> list[dict[str, Any]]:
    """Per tile: its sheet, label and the rigid motion that placed it."""
    shifts = snap(job.place.shift).tolist()
    heights = job.label_heights
    return [
        {
            "tile": t,
            "sheet": int(job.place.sheet[t]) + 1,
            "label": str(t) if heights[t] > 0 else "",
            "label_height_mm": round(float(heights[t]), 4),
            "rotation_rad": round(float(job.place.theta[t]), 12),
            "shift_mm": shifts[t],
        }
        for t in range(len(shifts))
    ]


def _parameters(job: CutJob) -> dict[str, Any]:
    # ezdxf and the assembly map's drawing load with a cut's manifest, not with sheets.py (its options)
    from ...exchange.dxf.writer import DXF_VERSION

    o, lig = job.options, job.cutting.ligament
    return {
        "sheet_mm": [float(o.sheet[0]), float(o.sheet[1])],
        "margin_mm": o.margin,
        "formats": list(o.formats),
        "colors": job.colors,
        "stroke_mm": o.stroke_mm,
        "notes": o.notes,
        "dxf_version": DXF_VERSION,
        "labels": o.labels,
        "label_height_mm": job.label_h,
        "label_margin_mm": job.cutting.label_margin,
        "part_spacing_mm": job.spacing,
        "reference_mm": o.reference_mm,
        "force": o.force,
        "turn_deg": o.turn_deg,
        "ligament_width_mm": None if lig is None else lig.width_mm,
        "time_model": f"cut_length/cut_speed + engrave_length/engrave_speed + {PIERCE_S} s per path",
    }


def _ligament(job: CutJob) -> dict[str, Any] | None:
    lig = job.cutting.ligament
    if lig is None:
        return None
    some = job.pattern.topology.n_hinges > 0
    return {
        "width_mm": lig.width_mm,
        "turn_deg": float(np.degrees(lig.turn_rad)),
        "min_length_mm": float(lig.lengths.min(initial=0.0)) if some else 0.0,
        "max_strain": float(lig.strains.max(initial=0.0)) if some else 0.0,
        "strain_limit": job.material.strain_limit,
    }


def _assembly(job: CutJob, files: dict[str, bytes], pieces: list[dict]) -> dict[str, Any]:
    from .. import assembly as asm

    n_top = sum(p["face"] == "T" for p in pieces)
    return {
        "joins": "tape" if pieces else None,
        "order": "top face first, then the bottom; "
        "breadth-first spanning tree from tile 0, then the loop-closing joins",
        "steps": job.kind.assembly_steps(n_top, len(pieces) - n_top),
        "map": "assembly.png" if "assembly.png" in files else None,
        "map_note": None
        if len(pieces) <= asm.MAP_MAX_PIECES
        else f"no map: {len(pieces)} pieces are more than {asm.MAP_MAX_PIECES} legible numbers",
    }


def cut_manifest(job: CutJob, files: dict[str, bytes], pieces: list[dict]) -> dict[str, Any]:
    """The manifest of a finished cut as the dict written to ``manifest.json``
    (``verification`` is filled in by the read-back)."""
    o, mat, report = job.options, job.material, job.gated.report
    ref = job.ref
    m = CutManifest(
        generator=f"fabkiri {__version__}",
        pattern=o.pattern_file or job.pattern.name,
        pattern_name=job.pattern.name,
        hinge=job.kind.name,
        state=o.state,
        layout=job.layout,
        scale=job.scale,
        kerf_mm=mat.kerf_mm,
        kerf_offset_mm=job.cutting.offset,
        kerf_join="mitre",
        mitre_limit=hg.MITRE_LIMIT,
        tile_shrink_mm=job.cutting.shrink,
        tolerance_mm=mat.tolerance_mm,
        parameters=_parameters(job),
        material=mat.to_dict(),
        pattern_verification={
            "ok": report.ok,
            "tol_mm": report.meta["tol_mm"] * job.scale if o.exact else mat.tolerance_mm,
            "gate": list(GATE_GROUPS),
            "failed": [c.name for c in report.checks if c.applies and not c.ok],
        },
        reference_square=None
        if ref is None
        else {"sheet": ref[0] + 1, "size_mm": o.reference_mm, "corners": ref[1].tolist()},
        sheets=_sheet_rows(job),
        tiles=_tile_rows(job),
        hinges=_hinge_rows(job),
        hinge_features=job.hinge_features,
        face_conflicts=job.faces.conflicts,
        ligament=_ligament(job),
        warnings=job.warnings,
        files=sorted(list(files) + ["manifest.json"]),
        verification=None,
        assembly=_assembly(job, files, pieces),
        assembly_pieces=pieces,
    )
    from .. import assembly as asm

    out = m.to_dict()
    area = float(shapely.area(shapely.polygons(job.cutting.corners)).sum())
    out["bill_of_materials"] = asm.cut_bom(
        out, pieces, area, job.pattern.topology.n_hinges, job.kind
    )
    return out
