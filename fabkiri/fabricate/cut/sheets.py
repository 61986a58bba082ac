"""``cut_pattern``: a pattern's closed state -> laser-cut sheets, all in memory.

Steps (docs/fabrication.md#cut-pipeline): pick the closed state, scale it, check it is
cuttable (closes, simple tiles, no overlaps), assign tape faces, apply the
hinge kind (a strategy object, :mod:`.hingekinds`), lay the parts out on
sheets, add labels and the reference square (:mod:`.labels`), and render
DXF/SVG/PNG bytes plus the manifest (:mod:`.manifest`). Nothing touches the
disk here; :mod:`fabkiri.fabricate.cut.readback` verifies and writes.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Literal

import numpy as np
import shapely

from ...errors import CheckFailed, FabricationError, InputError, Param
from ...exchange.drawing import COLORS, SheetDrawing, snap
from ...exchange.svg import STROKE_MM
from ...mechanics.contract import contract
from ...pattern.model import Pattern
from ...verify.manifest import dumps_manifest
from ...verify.physical import MARK_CORNER_FRAC, MARK_REACH_MM
from .. import fabricability as fb
from ..gate import GateResult, closes_gate
from ..gcpause import gc_paused
from . import hinges as hg
from . import layout as lay
from .formats import sheet_format, sheet_format_names
from .hingekinds import HingeKind, hinge_kind
from .hingekinds.cutting import Cutting, SheetCut
from .labels import MIN_LABEL_MM, add_notes, engrave_labels
from .manifest import cut_manifest, sheet_names
from .materials import Material
from .text import text_strokes

FORMATS = sheet_format_names()  # the built-in formats: what a cut writes by default


@dataclass
class CutOptions:
    """Everything ``fabkiri cut`` can be told. ``None`` means "from the material"."""

    material: Material
    hinge: str | None = None
    state: int = 1
    sheet: tuple[float, float] = (600.0, 400.0)
    margin: float = 5.0
    layout: str | None = None
    scale: float | Literal["auto"] | None = None  # "auto": the smallest the checks accept
    width: float | Literal["auto"] | None = None
    formats: tuple[str, ...] = FORMATS
    colors: str | None = None
    labels: bool = True
    label_height: float | None = None
    reference_mm: float = 50.0
    ligament_width: float | None = None
    turn_deg: float = 180.0
    force: bool = False
    exact: bool = (
        False  # pattern checked at the relative tier for solver output instead of the material's mm
    )
    stem: str = "pattern"
    pattern_file: str = ""
    notes: bool = True  # the NOTES layer: sheet frame, caption, reference-square size (never cut)
    stroke_mm: float = (
        STROKE_MM  # SVG stroke width: what a viewer draws; the colour says cut/score/engrave
    )


@dataclass
class CutResult:
    """The sheets, the files to write (name -> bytes) and the manifest."""

    sheets: list[SheetDrawing]
    files: dict[str, bytes]
    manifest: dict[str, Any]
    warnings: list[str] = field(default_factory=list)
    tile_regions: np.ndarray | None = None  # (T, 4, 2) label regions in sheet coordinates
    tile_sheet: np.ndarray | None = None

    def __repr__(self) -> str:  # sheets and regions are arrays, files are bytes: named, not printed
        return f"CutResult({len(self.sheets)} sheet(s), files {sorted(self.files)}, {len(self.warnings)} warning(s))"

    def manifest_bytes(self) -> bytes:
        """The manifest as written (:func:`fabkiri.verify.manifest.dumps_manifest`)."""
        return dumps_manifest(self.manifest).encode("utf-8")


@dataclass(eq=False)
class CutJob:
    """One cut as it is built: the choices made and the geometry so far (mm)."""

    pattern: Pattern
    options: CutOptions
    kind: HingeKind
    layout: str
    colors: str
    scale: float
    gated: GateResult
    faces: hg.FaceAssignment
    cutting: Cutting
    place: lay.Placement
    placed_corners: np.ndarray  # (T, 4, 2) tile corners as placed
    Q: np.ndarray  # (T, 4, 2) label regions as placed
    sheets: list[SheetDrawing]
    ref: tuple[int, np.ndarray] | None  # sheet and corners of the reference square
    spacing: float  # between parts on the sheet
    warnings: list[str]
    hinge_features: list[dict] = field(default_factory=list)
    label_heights: np.ndarray = field(default_factory=lambda: np.zeros(0))  # tile IDs (0: left out)
    corner_heights: np.ndarray | None = None  # corner labels

    @property
    def material(self) -> Material:
        return self.options.material

    @property
    def label_h(self) -> float:
        return self.options.label_height or self.options.material.label_height_mm


def _resolve(options: CutOptions) -> tuple[HingeKind, str, str]:
    mat = options.material
    kind = hinge_kind(options.hinge or mat.hinge)
    layout = options.layout or kind.default_layout
    if layout not in lay.LAYOUTS:
        raise InputError(f"layout must be one of {', '.join(lay.LAYOUTS)}, got {layout!r}")
    kind.check_layout(layout)
    colors = options.colors or mat.colors
    if colors not in COLORS:
        raise InputError(f"colour preset must be one of {', '.join(COLORS)}, got {colors!r}")
    if options.state not in (1, 2):
        raise InputError(Param("state"), f" must be 1 or 2, got {options.state}")
    W, H = options.sheet
    if not (np.isfinite(W) and np.isfinite(H) and W > 0 and H > 0):
        raise InputError(f"sheet size must be positive, got {W}x{H}")
    if not (np.isfinite(options.margin) and options.margin >= 0):
        raise InputError(f"margin must be >= 0 mm, got {options.margin}")
    if options.scale is not None and options.width is not None:
        raise InputError("give ", Param("scale"), " or ", Param("width"), ", not both")
    for f in options.formats:
        if sheet_format(f) is None:
            raise InputError(f"unknown format {f!r} (known: {', '.join(sheet_format_names())})")
    if options.reference_mm < 0:
        raise InputError(f"reference square size must be >= 0, got {options.reference_mm}")
    return kind, layout, colors


def closed_states(pattern: Pattern) -> dict[int, np.ndarray]:
    """Both closed states: the stored ones, the missing ones contracted."""
    out = {}
    for s in (1, 2):
        out[s] = pattern.contracted[s] if s in pattern.contracted else contract(pattern, s).corners
    return out


def _check_tiles(corners: np.ndarray, state: int) -> np.ndarray:
    polys = shapely.polygons(corners)
    bad = np.flatnonzero(~shapely.is_valid(polys))
    if len(bad):
        raise FabricationError(
            f"tile {int(bad[0])} is self-intersecting (a bow-tie) in closed state {state}; "
            "it cannot be cut"
        )
    cw = np.flatnonzero(shapely.is_ccw(shapely.get_exterior_ring(polys)) == False)  # noqa: E712
    if len(cw):
        raise FabricationError(f"tile {int(cw[0])} is mirrored (clockwise) in closed state {state}")
    # overlaps are the verifier gate's business ("state N: no overlaps"), checked before this
    return polys


def _scale(raw: np.ndarray, options: CutOptions, kind: str) -> float:
    """mm in the file per mm of the pattern: given, from ``--width``, or the smallest
    the material accepts (``auto``)."""
    mat = options.material
    if (
        options.scale == "auto" or options.width == "auto"
    ):  # the smallest size the checks below accept
        need = fb.cut_minimum(raw, mat, kind)
        if need.scale is None:
            raise CheckFailed(
                Param("scale" if options.scale == "auto" else "width", "auto"),
                f": {mat.name} with {kind} hinges: ",
                *need.advice_parts(),
            )
        return need.scale
    if options.width is not None:
        width = float(options.width)  # "auto" was taken above
        span = float(raw[..., 0].max() - raw[..., 0].min())
        if not width > 0:
            raise InputError(Param("width"), f" must be positive, got {options.width}")
        return width / span
    scale = 1.0 if options.scale is None else float(options.scale)
    if not (np.isfinite(scale) and scale > 0):
        raise InputError(Param("scale"), f" must be positive, got {options.scale}")
    return scale


# where parts go, by layout: (corners, parts, spacing, sheet, margin) -> Placement
_PLACERS = {
    "in-place": lambda corners, parts, spacing, sheet, margin: lay.in_place(corners, sheet, margin),
    "exploded": lay.exploded,
    "nested": lambda corners, parts, spacing, sheet, margin: lay.nested(
        parts, spacing, sheet, margin
    ),
}


def _reference(
    place: lay.Placement,
    parts: np.ndarray,
    options: CutOptions,
    sheet_wh: tuple[float, float],
    spacing: float,
) -> tuple[int, tuple[int, np.ndarray] | None]:
    """The sheet count and where the uncompensated reference square goes (beside
    the parts' bounding boxes), or ``None`` without one."""
    tidx = np.arange(len(parts))
    n_sheets = place.n_sheets
    boxes = []
    part_bounds = shapely.bounds(parts)
    for s in range(n_sheets):
        sel = place.sheet == s
        pts = place.apply(
            tidx[sel],
            np.stack(
                [
                    part_bounds[sel, :2],
                    part_bounds[sel, 2:],
                    part_bounds[sel][:, [0, 3]],
                    part_bounds[sel][:, [2, 1]],
                ],
                1,
            ),
        )
        boxes.append(np.concatenate([pts.reshape(-1, 2).min(0), pts.reshape(-1, 2).max(0)]))
    if not options.reference_mm > 0:
        return n_sheets, None
    rs, ll = lay.place_reference(
        boxes, options.reference_mm, sheet_wh, options.margin, max(5.0, spacing)
    )
    r = options.reference_mm
    return max(n_sheets, rs + 1), (rs, snap(ll + np.array([[0, 0], [r, 0], [r, r], [0, r]])))


def _draw(job: CutJob) -> None:
    """The cut linework of every sheet (by the hinge kind) and the reference square."""
    place = job.place
    top = job.pattern.topology
    for s in range(place.n_sheets):
        on = np.flatnonzero(place.sheet == s)
        sheet = SheetCut(s, on, place, place.sheet, top.hinge_tiles, job.placed_corners, job.Q)
        job.hinge_features += job.kind.draw(job.sheets[s], sheet, job.cutting)
    if job.ref is not None:
        rs, sq = job.ref
        opts = job.options
        job.sheets[rs].add("CUT", sq, True)
        cap_h = min(5.0, opts.reference_mm / 8)
        for p in text_strokes(f"{opts.reference_mm:g} MM", cap_h, sq.mean(0)) if opts.notes else []:
            job.sheets[rs].add("NOTES", p, False)


def _labels(job: CutJob) -> None:
    """Tile IDs, corner labels and tape marks (ENGRAVE), counting what did not fit."""
    top = job.pattern.topology
    omitted, job.label_heights, job.corner_heights = engrave_labels(
        job.sheets,
        job.Q,
        job.place.sheet,
        top.hinge_tiles,
        top.hinge_corner,
        job.faces.letters(),
        job.kind,
        job.label_h,
        job.cutting.label_margin,
    )
    if omitted:
        job.warnings.append(
            f"{omitted} label(s) left out: no room for {MIN_LABEL_MM:g} mm text inside the tile"
        )


def _files(job: CutJob) -> dict[str, bytes]:
    """Every file the options ask for: the per-sheet formats sheet by sheet (DXF and SVG), then those
    of the whole cut (the PNG preview), in the registry's order (:mod:`.sheetformats`)."""
    opts = job.options
    asked = [
        f
        for f in map(sheet_format, sheet_format_names())
        if f is not None and f.name in opts.formats
    ]
    files: dict[str, bytes] = {}
    for sd, name in zip(job.sheets, sheet_names(job)):
        for f in asked:
            if f.per_sheet:
                files[f"{name}{f.suffix}"] = f.write(job, [sd])
    for f in asked:
        if not f.per_sheet:
            files[f"{opts.stem}{f.suffix}"] = f.write(job, job.sheets)
    return files


def _cut_job(pattern: Pattern, options: CutOptions) -> CutJob:
    """Size, gate, hinge kind and layout of a cut: everything before anything is drawn."""
    mat = options.material
    kind, layout, colors = _resolve(options)
    states = closed_states(pattern)
    state = options.state
    raw = states[state]
    scale = _scale(raw, options, kind.name)
    # the verifier must find both closed states at the material's tolerance (in the file's mm)
    gated = closes_gate(
        pattern,
        None if options.exact else mat.tolerance_mm,
        scale=scale,
        force=options.force,
        action="cut",
    )
    warnings = list(gated.warnings)
    corners = raw * scale
    tile_polys = _check_tiles(corners, state)
    faces = hg.assign_faces(pattern, states)
    if faces.conflicts:
        warnings.append(
            f"{faces.conflicts} pair(s) of coincident hinges share a tape face "
            "(an odd cycle of coincidences)"
        )
    cutting = kind.prepare(
        pattern, corners, tile_polys, mat, state=state, scale=scale, options=options
    )
    warnings.extend(cutting.warnings)
    fb.check_webs(cutting.regions, mat, kind.name, cutting.corners, scale)
    sheet_wh = (float(options.sheet[0]), float(options.sheet[1]))
    spacing = 2 * mat.kerf_mm + 0.5 * mat.thickness_mm
    place = _PLACERS[layout](cutting.corners, cutting.parts, spacing, sheet_wh, options.margin)
    tidx = np.arange(pattern.topology.n_tiles)
    n_sheets, ref = _reference(place, cutting.parts, options, sheet_wh, spacing)
    sheets = [
        SheetDrawing(index=k + 1, width=sheet_wh[0], height=sheet_wh[1]) for k in range(n_sheets)
    ]
    return CutJob(
        pattern,
        options,
        kind,
        layout,
        colors,
        scale,
        gated,
        faces,
        cutting,
        place,
        place.apply(tidx, cutting.corners),
        place.apply(tidx, cutting.regions),
        sheets,
        ref,
        spacing,
        warnings,
        label_heights=np.zeros(len(tidx)),
    )


def _assembly(job: CutJob, files: dict[str, bytes]) -> list[dict]:
    """Tape pieces numbered in join order, and their map (``assembly.png``) when legible."""
    from .. import assembly as asm

    pattern, Q, sheet_of = job.pattern, job.Q, job.place.sheet
    pieces = asm.tape_pieces(
        pattern, Q, sheet_of, job.faces.letters(), job.kind, MARK_CORNER_FRAC, MARK_REACH_MM
    )
    if "png" in job.options.formats and 0 < len(pieces) <= asm.MAP_MAX_PIECES:
        by_sheet = [Q[sheet_of == s] for s in range(job.place.n_sheets)]
        files["assembly.png"] = asm.map_png(
            by_sheet,
            pieces,
            asm.tape_shapes(pattern, Q, pieces, MARK_CORNER_FRAC, MARK_REACH_MM),
            job.options.stem,
        )
    return pieces


@gc_paused
def cut_pattern(pattern: Pattern, options: CutOptions) -> CutResult:
    """Build every sheet, file and the manifest for ``pattern`` in memory."""
    job = _cut_job(pattern, options)
    _draw(job)
    if options.labels:
        _labels(job)
    if options.notes:
        mat, o = job.material, options
        add_notes(
            job.sheets,
            lambda i, n: (
                f"{o.stem} {i}/{n} {mat.name} {job.kind.name} state {o.state} kerf {mat.kerf_mm:g}"
            ),
            options.margin,
        )
    files = _files(job)
    pieces = _assembly(job, files)
    manifest = cut_manifest(job, files, pieces)
    return CutResult(
        sheets=job.sheets,
        files=files,
        manifest=manifest,
        warnings=job.warnings,
        tile_regions=job.Q,
        tile_sheet=job.place.sheet,
    )
