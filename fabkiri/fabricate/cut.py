"""``cut_pattern``: a pattern's closed state -> laser-cut sheets, all in memory.

Steps (fabrication spec §6.2): pick the closed state, scale it, check it is
cuttable (closes, simple tiles, no overlaps), assign tape faces, apply the
hinge kind, lay the parts out on sheets, add labels and the reference square,
and render DXF/SVG/PNG bytes plus the manifest. Nothing touches the disk
here; :mod:`fabkiri.fabricate.readback` verifies and writes.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import shapely

from .. import __version__
from ..errors import CheckFailed, FabricationError, InputError
from ..mechanics.contract import contract
from ..pattern import fabricability as fab
from ..pattern.model import Pattern
from ..verify.physical import MARK_CORNER_FRAC, MARK_REACH_MM, tape_mark_chords, tape_reach
from . import fabricability as fb
from . import hinges as hg
from . import layout as lay
from .drawing import COLORS, SheetDrawing, snap
from .dxf import DXF_VERSION, dxf_bytes
from .gate import GATE_GROUPS, closes_gate
from .gcpause import gc_paused
from .materials import HINGE_KINDS, Material
from .preview import png_bytes
from .svg import STROKE_MM, svg_bytes
from .text import supported, text_strokes, text_strokes_many, text_width

FORMATS = ("dxf", "svg", "png")
MIN_LABEL_MM = 0.8  # below this a label is not legible; it is left out (and counted)
PIERCE_S = 0.2  # time model: per path, for the head to travel and pierce
FEATURE_PAD_MM = 1e-4  # ligament spans listed in the manifest are this much wider than the free span
ID_FRAC = 0.45  # tile IDs fit the tile scaled by this about its centroid


def _incentre(tri: np.ndarray) -> np.ndarray:
    """Incentres of triangles ``(N, 3, 2)``: the anchor that leaves the most room for a label."""
    a = np.linalg.norm(tri[:, 1] - tri[:, 2], axis=1)
    b = np.linalg.norm(tri[:, 2] - tri[:, 0], axis=1)
    c = np.linalg.norm(tri[:, 0] - tri[:, 1], axis=1)
    w = np.stack([a, b, c], 1)
    return (w[:, :, None] * tri).sum(1) / np.maximum(w.sum(1), 1e-300)[:, None]


@dataclass
class CutOptions:
    """Everything ``fabkiri cut`` can be told. ``None`` means "from the material"."""

    material: Material
    hinge: str | None = None
    state: int = 1
    sheet: tuple[float, float] = (600.0, 400.0)
    margin: float = 5.0
    layout: str | None = None
    scale: float | str | None = None  # "auto": the smallest the checks accept
    width: float | str | None = None
    formats: tuple[str, ...] = FORMATS
    colors: str | None = None
    labels: bool = True
    label_height: float | None = None
    reference_mm: float = 50.0
    ligament_width: float | None = None
    turn_deg: float = 180.0
    force: bool = False
    exact: bool = False  # pattern checked at the relative tier for solver output instead of the material's mm
    stem: str = "pattern"
    pattern_file: str = ""
    notes: bool = True  # the NOTES layer: sheet frame, caption, reference-square size (never cut)
    stroke_mm: float = STROKE_MM  # SVG stroke width: what a viewer draws; the colour says cut/score/engrave


ROW_LISTS = ("tiles", "hinges", "hinge_features", "assembly_pieces")  # manifest lists written one row per line


@dataclass
class CutResult:
    """The sheets, the files to write (name -> bytes) and the manifest."""

    sheets: list[SheetDrawing]
    files: dict[str, bytes]
    manifest: dict[str, Any]
    warnings: list[str] = field(default_factory=list)
    tile_regions: np.ndarray | None = None  # (T, 4, 2) label regions in sheet coordinates
    tile_sheet: np.ndarray | None = None

    def manifest_bytes(self) -> bytes:
        """The manifest as JSON: indented, but each row of the long lists on one line.

        (One row per line reads well and lets json's C encoder write the thousands of
        rows of a large pattern; ``indent`` alone runs the pure-Python encoder.)
        """
        m = dict(self.manifest)
        rows = {}
        for k in ROW_LISTS:
            if isinstance(m.get(k), list) and m[k]:
                rows[k] = m[k]
                m[k] = f"\u0000rows {k}"
        text = json.dumps(m, indent=1, ensure_ascii=False)
        for k, v in rows.items():
            at = f'\n "{k}": ' + json.dumps(m[k], ensure_ascii=False)
            body = ",\n".join("  " + json.dumps(r, ensure_ascii=False) for r in v)
            if text.count(at) != 1:  # cannot happen: a top-level key is written once
                raise RuntimeError(f"manifest key {k!r} not found once")
            text = text.replace(at, f'\n "{k}": [\n{body}\n ]')
        return (text + "\n").encode("utf-8")


def _resolve(options: CutOptions) -> tuple[str, str, str]:
    mat = options.material
    kind = options.hinge or mat.hinge
    if kind not in HINGE_KINDS:
        raise InputError(f"hinge kind must be one of {', '.join(HINGE_KINDS)}, got {kind!r}")
    layout = options.layout or ("exploded" if kind == "separate" else "in-place")
    if layout not in lay.LAYOUTS:
        raise InputError(f"layout must be one of {', '.join(lay.LAYOUTS)}, got {layout!r}")
    if kind in ("tape", "ligament") and layout != "in-place":
        raise InputError(f"{kind} hinges are cut in place; --layout {layout} is for --hinge separate")
    if kind == "separate" and layout == "in-place":
        raise InputError("separate tiles are offset by half the kerf and would overlap in place; "
                         "use --layout exploded or nested")
    colors = options.colors or mat.colors
    if colors not in COLORS:
        raise InputError(f"colour preset must be one of {', '.join(COLORS)}, got {colors!r}")
    if options.state not in (1, 2):
        raise InputError(f"--state must be 1 or 2, got {options.state}")
    W, H = options.sheet
    if not (np.isfinite(W) and np.isfinite(H) and W > 0 and H > 0):
        raise InputError(f"sheet size must be positive, got {W}x{H}")
    if not (np.isfinite(options.margin) and options.margin >= 0):
        raise InputError(f"margin must be >= 0 mm, got {options.margin}")
    if options.scale is not None and options.width is not None:
        raise InputError("give --scale or --width, not both")
    for f in options.formats:
        if f not in FORMATS:
            raise InputError(f"unknown format {f!r} (known: {', '.join(FORMATS)})")
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
        raise FabricationError(f"tile {int(bad[0])} is self-intersecting (a bow-tie) in closed state {state}; "
                               "it cannot be cut")
    cw = np.flatnonzero(shapely.is_ccw(shapely.get_exterior_ring(polys)) == False)  # noqa: E712
    if len(cw):
        raise FabricationError(f"tile {int(cw[0])} is mirrored (clockwise) in closed state {state}")
    # overlaps are the verifier gate's business ("state N: no overlaps"), checked before this
    return polys


def _add_labels(sheets, sheet_of_label: np.ndarray, tile_of_label: np.ndarray, pts: np.ndarray, counts: np.ndarray,
                label: np.ndarray) -> None:
    """Open strokes (``pts`` split by ``counts``, stroke j of label ``label[j]``) onto their labels'
    sheets, in order, grouped by tile."""
    if not len(counts):
        return
    on = np.asarray(sheet_of_label)[label]
    tile = np.asarray(tile_of_label)[label]
    point_sheet = np.repeat(on, counts)
    for s in np.unique(on).tolist():
        sheets[s].add_many("ENGRAVE", pts[point_sheet == s], counts[on == s], tile[on == s])


def _fit_labels(Q, tiles, texts, anchors, region, hmax, margin):
    """Fit text boxes; re-check containment in the tile with shapely (non-convex tiles) and shrink."""
    ratio = np.array([text_width(t) for t in texts])
    h = lay.fit_heights(anchors, ratio, np.full(len(texts), hmax), region, margin)
    h = np.where(h >= MIN_LABEL_MM, h, 0.0)
    if len(h):
        tile_polys = shapely.buffer(shapely.polygons(Q[tiles]), -margin + 1e-9, join_style="mitre")
        for _ in range(8):
            w = ratio * h
            boxes = shapely.box(anchors[:, 0] - w / 2, anchors[:, 1] - h / 2, anchors[:, 0] + w / 2,
                                anchors[:, 1] + h / 2)
            bad = (h > 0) & ~shapely.covers(tile_polys, boxes)
            if not bad.any():
                break
            h[bad] *= 0.7
            h[bad & (h < MIN_LABEL_MM)] = 0.0
    return h


@gc_paused
def cut_pattern(pattern: Pattern, options: CutOptions) -> CutResult:
    """Build every sheet, file and the manifest for ``pattern`` in memory."""
    mat = options.material
    kind, layout, colors = _resolve(options)
    warnings: list[str] = []
    states = closed_states(pattern)
    state = options.state
    raw = states[state]
    if options.scale == "auto" or options.width == "auto":  # the smallest size the checks below accept
        need = fb.cut_minimum(raw, mat, kind)
        if need.scale is None:
            raise CheckFailed(f"--{'scale' if options.scale == 'auto' else 'width'} auto: {mat.name} with "
                              f"{kind} hinges: {need.advice()}")
        scale = need.scale
    elif options.width is not None:
        span = float(raw[..., 0].max() - raw[..., 0].min())
        if not options.width > 0:
            raise InputError(f"--width must be positive, got {options.width}")
        scale = options.width / span
    else:
        scale = 1.0 if options.scale is None else float(options.scale)
        if not (np.isfinite(scale) and scale > 0):
            raise InputError(f"--scale must be positive, got {options.scale}")

    # the verifier must find both closed states at the material's tolerance (in the file's mm)
    gated = closes_gate(pattern, None if options.exact else mat.tolerance_mm, scale=scale, force=options.force,
                        action="cut")
    pattern_report = gated.report
    warnings += gated.warnings

    corners = raw * scale
    tile_polys = _check_tiles(corners, state)
    top = pattern.topology
    T, Hn = top.n_tiles, top.n_hinges
    A, B = top.hinge_tiles.T
    cA, cB = top.hinge_corner.T
    faces = hg.assign_faces(pattern, states)
    if faces.conflicts:
        warnings.append(f"{faces.conflicts} pair(s) of coincident hinges share a tape face "
                        "(an odd cycle of coincidences)")
    letters = faces.letters()
    kerf = mat.kerf_mm
    label_h = options.label_height or mat.label_height_mm

    # ---- hinge kind: parts (for placement), label regions, offsets
    lig = None
    strips = None
    shrink = 0.0
    offset = 0.0
    if kind == "tape":
        # corners a solver left apart by less than the tolerance are one node of the linework
        eps = 0.5 * mat.tolerance_mm
        corners = hg.snap_corners(corners, eps, hg.closure_pairs(pattern, state))
        corners = hg.snap_corners(hg.snap_to_edges(corners, eps), eps, hg.closure_pairs(pattern, state))
        regions = corners
        parts = shapely.polygons(corners)
        label_margin = 0.5 + kerf / 2
    elif kind == "ligament":
        shrink = mat.gap_mm / 2
        offset = mat.kerf_offset_mm
        try:
            regions = hg.shrink_tiles(corners, shrink)
        except FabricationError as exc:
            lost = np.flatnonzero((fab.shrunk_edges(corners, shrink) <= fab.EDGE_EPS_MM).any(-1))
            raise fb.lost_edge(corners, mat, kind, scale, int(lost[0])) from exc
        lig = hg.ligament_design(pattern, corners, regions, gap=mat.gap_mm, width_max=mat.ligament_width_mm,
                                 min_web=mat.min_web_mm, kerf=kerf, strain_limit=mat.strain_limit,
                                 turn_rad=np.radians(options.turn_deg), width=options.ligament_width)
        warnings.extend(lig.warnings)
        strips = hg.ligament_strips(lig.apex, lig.width_mm, embed=max(0.5, lig.width_mm))
        parts = shapely.polygons(corners)
        label_margin = 0.5
    else:
        offset = mat.kerf_offset_mm
        regions = corners
        parts = hg.kerf_outset(tile_polys, offset)
        label_margin = 0.5

    fb.check_webs(regions, mat, kind, corners, scale)

    # ---- layout
    sheet_wh = (float(options.sheet[0]), float(options.sheet[1]))
    spacing = 2 * kerf + 0.5 * mat.thickness_mm
    if layout == "in-place":
        place = lay.in_place(corners, sheet_wh, options.margin)
    elif layout == "exploded":
        place = lay.exploded(corners, parts, spacing, sheet_wh, options.margin)
    else:
        place = lay.nested(parts, spacing, sheet_wh, options.margin)
    tidx = np.arange(T)
    placed_corners = place.apply(tidx, corners)
    Q = place.apply(tidx, regions)
    sheet_of = place.sheet

    # content boxes -> reference square
    n_sheets = place.n_sheets
    boxes = []
    part_bounds = shapely.bounds(parts)
    for s in range(n_sheets):
        sel = sheet_of == s
        pts = place.apply(tidx[sel], np.stack([part_bounds[sel, :2], part_bounds[sel, 2:],
                                               part_bounds[sel][:, [0, 3]], part_bounds[sel][:, [2, 1]]], 1))
        boxes.append(np.concatenate([pts.reshape(-1, 2).min(0), pts.reshape(-1, 2).max(0)]))
    ref = None
    if options.reference_mm > 0:
        rs, ll = lay.place_reference(boxes, options.reference_mm, sheet_wh, options.margin, max(5.0, spacing))
        n_sheets = max(n_sheets, rs + 1)
        r = options.reference_mm
        ref = (rs, snap(ll + np.array([[0, 0], [r, 0], [r, r], [0, r]])))

    sheets = [SheetDrawing(index=k + 1, width=sheet_wh[0], height=sheet_wh[1]) for k in range(n_sheets)]

    # ---- cut geometry per sheet
    hinge_features = []
    for s in range(place.n_sheets):
        sd = sheets[s]
        on = np.flatnonzero(sheet_of == s)
        if kind == "tape":
            rings, lines = hg.tape_linework(placed_corners[on])
            for p in lines:
                sd.add("CUT", p, False)
            for p in rings:
                sd.add("CUT", p, True)
        elif kind == "ligament":
            same = np.flatnonzero((sheet_of[A] == s) & (sheet_of[B] == s))
            shift = place.shift[on[0]]
            small = shapely.polygons(Q[on])
            moved_strips = shapely.transform(strips[same], lambda c, d=shift: c + d)
            material = shapely.union_all(np.concatenate([small, moved_strips]), grid_size=hg.GRID)
            ext, inner = hg.rings_of(hg.kerf_outset(material, offset))
            for p in inner:
                sd.add("CUT", p, True)
            for p in ext:
                sd.add("CUT", p, True)
            # the free spans: material not in any tile, from the same snapped geometry as the cut
            tiles_here = shapely.union_all(small, grid_size=hg.GRID)
            tile_tree = shapely.STRtree(small)
            free = shapely.get_parts(shapely.difference(material, tiles_here, grid_size=hg.GRID))
            free = free[shapely.area(free) > 0]
            # a span may touch two strips (then it is listed for both)
            part_i, strip_i = shapely.STRtree(moved_strips).query(free, predicate="intersects")
            order = np.lexsort((part_i, strip_i))
            part_i, strip_i = part_i[order], strip_i[order]
            owners, first, counts = np.unique(strip_i, return_index=True, return_counts=True)
            spans = np.array([free[part_i[f]] if c == 1 else shapely.union_all(free[part_i[f:f + c]],
                                                                                 grid_size=hg.GRID)
                              for f, c in zip(first, counts)], dtype=object)
            # padded so rounding never leaves a hairline of material along the strip joining the
            # two tiles, then clipped by the tiles so no tile loses a corner
            spans = shapely.buffer(spans, FEATURE_PAD_MM, join_style="mitre")
            si, ti = tile_tree.query(spans, predicate="intersects")
            rank = np.zeros(len(si), dtype=np.int64)
            for r in range(1, len(si)):
                rank[r] = rank[r - 1] + 1 if si[r] == si[r - 1] else 0
            for r in range(int(rank.max(initial=-1)) + 1):
                sel = rank == r
                spans[si[sel]] = shapely.difference(spans[si[sel]], small[ti[sel]], grid_size=hg.GRID)
            spans = shapely.normalize(spans)
            for j, geom in zip(owners, spans):
                for g in shapely.get_parts(geom):  # one entry per polygon (a span may come in parts)
                    if g.geom_type == "Polygon" and not g.is_empty:
                        hinge_features.append({"hinge": int(same[j]), "sheet": s + 1,
                                               "polygon": snap(np.asarray(g.exterior.coords)[:-1]).tolist()})
        else:
            for t in on:  # each part turned and moved as placed
                ring = np.asarray(parts[t].exterior.coords)[:-1]
                sd.add("CUT", place.apply(np.array([t]), ring[None])[0], True)
    if ref is not None:
        rs, sq = ref
        sheets[rs].add("CUT", sq, True)
        cap_h = min(5.0, options.reference_mm / 8)
        for p in text_strokes(f"{options.reference_mm:g} MM", cap_h,
                              sq.mean(0)) if options.notes else []:
            sheets[rs].add("NOTES", p, False)

    # ---- labels (ENGRAVE): tile IDs, corner labels, tape marks
    omitted = 0
    label_heights = np.zeros(T)
    hc_all = None
    if options.labels:
        cent = shapely.get_coordinates(shapely.centroid(shapely.polygons(Q)))
        id_region = cent[:, None, :] + ID_FRAC * (Q - cent[:, None, :])
        ids = [str(t) for t in range(T)]
        hid = _fit_labels(Q, tidx, ids, cent, id_region, label_h, 0.0)
        label_heights = hid
        omitted += int((hid <= 0).sum())
        _add_labels(sheets, sheet_of, tidx, *text_strokes_many(ids, hid, cent))

        cross = sheet_of[A] != sheet_of[B]
        c_tiles, c_k, c_text = [], [], []
        for h in range(Hn):
            f = letters[h]
            if kind == "separate" or cross[h]:
                c_tiles += [A[h], B[h]]
                c_k += [cA[h], cB[h]]
                c_text += [f"{B[h]}{f}", f"{A[h]}{f}"]
            elif kind == "tape":
                c_tiles.append(A[h])
                c_k.append(cA[h])
                c_text.append(f)
        if c_tiles:
            ct, ck = np.array(c_tiles), np.array(c_k)
            q = Q[ct, ck]
            q1, q0 = Q[ct, (ck + 1) % 4], Q[ct, (ck + 3) % 4]
            # corner labels fit the triangle the tape covers (its chord is the tape mark's)
            tri = np.stack([q, q + tape_reach(q, q1)[:, None] * (q1 - q),
                            q + tape_reach(q, q0)[:, None] * (q0 - q)], 1)
            anchor = _incentre(tri)
            hc = _fit_labels(Q, ct, c_text, anchor, tri, 0.6 * label_h, label_margin)
            hc_all = hc
            omitted += int((hc <= 0).sum())
            _add_labels(sheets, sheet_of[ct], ct, *text_strokes_many(c_text, hc, anchor))
        if kind == "tape" and Hn:
            # tile A's corner carries the face letter, tile B's a chord where the tape ends: one
            # mark per tile keeps the stroke count (DXF entities) down on large patterns
            same = ~cross
            mt, mk = B[same], cB[same]
            marks = tape_mark_chords(Q, mt, mk, label_margin)
            ok = np.isfinite(marks).all(axis=(1, 2))
            _add_labels(sheets, sheet_of[mt[ok]], mt[ok], marks[ok].reshape(-1, 2), np.full(int(ok.sum()), 2),
                        np.arange(int(ok.sum())))
        for sd in sheets:  # each tile's engraving together: one SVG path per tile, less head travel
            sd.sort_by_group("ENGRAVE")
        if omitted:
            warnings.append(f"{omitted} label(s) left out: no room for {MIN_LABEL_MM:g} mm text inside the tile")

    # ---- notes: sheet frame and caption
    for sd in sheets if options.notes else []:
        sd.add("NOTES", np.array([[0, 0], [sd.width, 0], [sd.width, sd.height], [0, sd.height]], float), True)
        cap = f"{options.stem} {sd.index}/{len(sheets)} {mat.name} {kind} state {state} kerf {kerf:g}"
        cap = "".join(ch if supported(ch) else "-" for ch in cap)
        ch_h = min(2.5, 0.5 * options.margin)
        if ch_h >= 1.0:
            w = ch_h * text_width(cap)
            if w > sd.width - 2 * options.margin:
                ch_h *= (sd.width - 2 * options.margin) / w
                w = ch_h * text_width(cap)
            if ch_h > 0.3:
                for p in text_strokes(cap, ch_h, (options.margin + w / 2, options.margin / 2)):
                    sd.add("NOTES", p, False)

    # ---- files
    multi = len(sheets) > 1
    names = [f"{options.stem}-sheet{sd.index}" if multi else options.stem for sd in sheets]
    files: dict[str, bytes] = {}
    for sd, name in zip(sheets, names):
        if "dxf" in options.formats:
            files[f"{name}.dxf"] = dxf_bytes(sd, colors)
        if "svg" in options.formats:
            files[f"{name}.svg"] = svg_bytes(sd, colors, options.stroke_mm)
    if "png" in options.formats:
        shown = [h for h in (label_heights, hc_all) if h is not None and (h > 0).any()]
        smallest = min((float(h[h > 0].min()) for h in shown), default=None)
        files[f"{options.stem}.png"] = png_bytes(sheets, colors, label_mm=smallest)

    # ---- assembly: tape pieces numbered in join order, and their map
    from . import assembly as asm

    pieces = asm.tape_pieces(pattern, Q, sheet_of, letters, kind, MARK_CORNER_FRAC, MARK_REACH_MM)
    if "png" in options.formats and 0 < len(pieces) <= asm.MAP_MAX_PIECES:
        by_sheet = [Q[sheet_of == s] for s in range(place.n_sheets)]
        files["assembly.png"] = asm.map_png(by_sheet, pieces, asm.tape_shapes(pattern, Q, pieces, MARK_CORNER_FRAC,
                                                                             MARK_REACH_MM), options.stem)

    # ---- manifest
    sheet_rows = []
    for sd, name in zip(sheets, names):
        cut_len = sd.length("CUT")
        eng_len = sd.length("ENGRAVE") + sd.length("SCORE")
        paths = sd.count("CUT") + sd.count("ENGRAVE") + sd.count("SCORE")
        sheet_rows.append({
            "index": sd.index, "width_mm": sd.width, "height_mm": sd.height,
            "dxf": f"{name}.dxf" if "dxf" in options.formats else None,
            "svg": f"{name}.svg" if "svg" in options.formats else None,
            "tiles": int((sheet_of == sd.index - 1).sum()),
            "cut_paths": sd.count("CUT"), "engrave_paths": sd.count("ENGRAVE"),
            "cut_length_mm": round(cut_len, 3), "engrave_length_mm": round(eng_len, 3),
            "cut_time_s": round(cut_len / mat.cut_speed_mm_s + eng_len / mat.engrave_speed_mm_s
                                + PIERCE_S * paths, 1),
        })
    hinge_rows = []
    pos_a = snap(placed_corners[A, cA]).tolist()
    pos_b = snap(placed_corners[B, cB]).tolist()
    for h in range(Hn):
        row = {"hinge": h, "tiles": [int(A[h]), int(B[h])], "face": letters[h],
               "sheets": [int(sheet_of[A[h]]) + 1, int(sheet_of[B[h]]) + 1],
               "position": pos_a[h],  # on tile A's sheet
               "position_b": pos_b[h],  # on tile B's sheet
               "cross_sheet": bool(sheet_of[A[h]] != sheet_of[B[h]])}
        if lig is not None:
            row["ligament_length_mm"] = round(float(lig.lengths[h]), 6)
            row["strain"] = round(float(lig.strains[h]), 6)
        hinge_rows.append(row)
    shifts = snap(place.shift).tolist()
    manifest = {
        "format": "fabkiri.cut", "version": 1, "units": "mm", "generator": f"fabkiri {__version__}",
        "pattern": options.pattern_file or pattern.name, "pattern_name": pattern.name,
        "hinge": kind, "state": state, "layout": layout, "scale": scale,
        "kerf_mm": kerf, "kerf_offset_mm": offset, "kerf_join": "mitre", "mitre_limit": hg.MITRE_LIMIT,
        "tile_shrink_mm": shrink, "tolerance_mm": mat.tolerance_mm,
        "parameters": {
            "sheet_mm": list(sheet_wh), "margin_mm": options.margin, "formats": list(options.formats),
            "colors": colors, "stroke_mm": options.stroke_mm, "notes": options.notes, "dxf_version": DXF_VERSION,
            "labels": options.labels,
            "label_height_mm": label_h, "label_margin_mm": label_margin, "part_spacing_mm": spacing,
            "reference_mm": options.reference_mm, "force": options.force, "turn_deg": options.turn_deg,
            "ligament_width_mm": None if lig is None else lig.width_mm,
            "time_model": f"cut_length/cut_speed + engrave_length/engrave_speed + {PIERCE_S} s per path",
        },
        "material": mat.to_dict(),
        "pattern_verification": {"ok": pattern_report.ok,
                                 "tol_mm": pattern_report.meta["tol_mm"] * scale if options.exact else mat.tolerance_mm,
                                 "gate": list(GATE_GROUPS), "failed": [c.name for c in pattern_report.checks
                                                                       if c.applies and not c.ok]},
        "reference_square": None if ref is None else {"sheet": ref[0] + 1, "size_mm": options.reference_mm,
                                                      "corners": ref[1].tolist()},
        "sheets": sheet_rows,
        "tiles": [{"tile": t, "sheet": int(sheet_of[t]) + 1,
                   "label": str(t) if label_heights[t] > 0 else "",
                   "label_height_mm": round(float(label_heights[t]), 4),
                   "rotation_rad": round(float(place.theta[t]), 12),
                   "shift_mm": shifts[t]} for t in range(T)],
        "hinges": hinge_rows,
        "hinge_features": hinge_features,
        "face_conflicts": faces.conflicts,
        "ligament": None if lig is None else {
            "width_mm": lig.width_mm, "turn_deg": float(np.degrees(lig.turn_rad)),
            "min_length_mm": float(lig.lengths.min(initial=0.0)) if Hn else 0.0,
            "max_strain": float(lig.strains.max(initial=0.0)) if Hn else 0.0,
            "strain_limit": mat.strain_limit},
        "warnings": warnings,
        "files": sorted(list(files) + ["manifest.json"]),
        "verification": None,
    }
    n_top = sum(p["face"] == "T" for p in pieces)
    manifest["assembly"] = {"joins": "tape" if pieces else None, "order": "top face first, then the bottom; "
                            "breadth-first spanning tree from tile 0, then the loop-closing joins",
                            "steps": asm.assembly_steps(kind, n_top, len(pieces) - n_top),
                            "map": "assembly.png" if "assembly.png" in files else None,
                            "map_note": None if len(pieces) <= asm.MAP_MAX_PIECES else
                            f"no map: {len(pieces)} pieces are more than {asm.MAP_MAX_PIECES} legible numbers"}
    manifest["assembly_pieces"] = pieces
    manifest["bill_of_materials"] = asm.cut_bom(manifest, pieces, float(shapely.area(shapely.polygons(corners)).sum()),
                                                Hn)
    return CutResult(sheets=sheets, files=files, manifest=manifest, warnings=warnings, tile_regions=Q,
                     tile_sheet=sheet_of)
