"""Cut-layout verification: read a DXF or SVG back and prove it closes into both states.

The contract with the writers is docs/cut-files.md. Nothing but the geometry
and the declared allowances (manifest.json) is trusted:

1. read the ``CUT`` linework (all outlines for plain files from other tools),
   in millimetres, y up;
2. set the reference square aside, recover the tile polygons per hinge kind
   (``tape``: polygonize the noded linework; ``separate``: each closed outline
   shrunk by the kerf offset; ``ligament``: material minus hinge strips, grown
   by the tile shrink) and reduce each to its four corners;
3. match them to the design tiles (any order; one rigid motion per sheet for
   in-place layouts, one per tile for separate ones; a mirrored tile is an
   error) and check (a) congruence, (b) the in-place layout is the declared
   closed state, (c) the cut tiles reassembled by the hinge correspondence
   give the other closed state (both states for separate tiles), (d) every
   hinge is present.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np
import shapely

from ..exchange.file_formats import read_cut_file
from ..exchange.linework import Linework
from ..pattern import geometry
from ..pattern.model import Pattern
from ..pattern.topology import STATES
from .geom import leave_one_out_residual
from .hingeread import PLAIN, reading
from .layout_match import _match_tiles, _Matched
from .manifest import Allowances, CutManifest, _allowances, load_manifest
from .matching import _mirror, _shift_fit, assembled, match_by_shape
from .pattern_checks import Tolerances, closed_state_checks, fabrication_tolerances, state_check_id
from .recovery import sheet_material
from .report import Check, Report, measured
from .sheetread import _layout_kind, _recover_sheets, _sheet_files

# ------------------------------------------------------------------ entry point


def verify_layout(
    pattern: Pattern,
    layout_path: str | Path,
    manifest: CutManifest | dict[str, Any] | None = None,
    tol_mm: float = 0.05,
    tol_rad: float = 1e-6,
) -> Report:
    """Verify a cut layout (DXF or SVG) against ``pattern`` and both closed states.

    ``manifest`` None loads ``manifest.json`` beside the layout if present; a
    plain file without one is read as closed tile outlines (or, with open
    polylines, as in-place linework), without allowances. Lengths are compared
    with ``tol_mm``; angles derived from cut shapes with ``tol_mm`` / mean edge.
    """
    path = Path(layout_path)
    if manifest is None:
        manifest = load_manifest(path)
    al = _allowances(
        manifest, str(path.parent / "manifest.json") if manifest is not None else str(path)
    )
    files = _sheet_files(path, al)
    # everything is compared on the sheet, in physical mm: the design is scaled
    # up (kerf and tolerance are physical lengths, not pattern lengths)
    L = pattern.tile_size * al.scale
    tol = fabrication_tolerances(float(tol_mm), L)
    rep = Report(
        subject=str(path),
        kind="layout",
        meta={
            "tol_mm": tol.length,
            "tol_rad": tol.angle,
            "tile_size_mm": L,
            "tolerance": tol.describe(),
            "hinge": al.hinge,
            "layout": al.layout,
            "state": al.state,
            "files": [str(f) for f in files.values()],
        },
    )
    g = "layout"
    D = pattern.corners() * al.scale  # design shapes (deployed = cut shapes), sheet mm
    rec = _recover_sheets(pattern, al, files, D, L, tol.length, path)
    rep.meta["recovery"] = sorted(rec.methods)
    if rec.references:
        rep.meta["reference_square_mm"] = rec.references
    in_place, sheet_piece, fitted = _layout_kind(rec, al, D, L, tol.length, rep)
    m = _match_tiles(pattern, al, rec, in_place, D, L, tol.length, rep)
    have = m.assign >= 0
    _recovered_check(rep, m, rec.unusable, g, D, L)
    _congruence_check(rep, D, m.cut_shapes, have, tol.length, g)
    if in_place:
        _in_place_checks(rep, pattern, m, have, tol, g, len(rec.sheets))
    _reassembly_checks(
        rep, pattern, m.cut_shapes, have, [3 - m.state] if in_place else list(STATES), tol, g
    )
    # every cut runs its full length: no cut ends inside the material
    ends = np.concatenate(rec.dangling) if rec.dangling else np.zeros((0, 2))
    rep.add(_dangling_check(ends, m.cut_shapes, have, g, tol.length))
    _hinge_check(rep, pattern, al, m, have, in_place, tol.length, g)
    if sheet_piece and have.any():
        _ligament_checks(rep, pattern, al, rec.linework, m, have, fitted, g)
    elif in_place and have.any():
        _tape_mark_checks(rep, pattern, al, files, m, have, g)
    return rep


def _recovered_check(
    rep: Report, m: _Matched, unusable: int, g: str, D: np.ndarray, L: float
) -> None:
    T = len(m.assign)
    missing = np.flatnonzero(m.assign < 0)
    got = T - len(missing)
    worst = f"tile {int(missing[0])}" if len(missing) else None
    if worst is None and m.extra_shapes:  # an extra piece: the design tile it is shaped like
        like = match_by_shape(D, np.asarray(m.extra_shapes), L)[0]
        worst = f"tile {int(like[like >= 0][0])}" if (like >= 0).any() else None
    rep.add(
        Check(
            f"{g}: tiles recovered",
            ok=not len(missing) and not m.extra and not unusable,
            value=got,
            tol=T,
            unit="count",
            op="==",
            group=g,
            worst=worst,
            detail=(
                f"{got} of {T} design tiles found; missing {missing[:20].tolist()}; "
                f"{m.extra} unmatched cut regions"
                + (f" (one shaped like {worst})" if worst and not len(missing) else "")
                + f"; {unusable} regions that are not quads"
            ),
        )
    )


def _congruence_check(
    rep: Report, D: np.ndarray, cut_shapes: np.ndarray, have: np.ndarray, tol: float, g: str
) -> None:
    """(a) congruence of every cut tile with its design tile."""
    T = len(D)
    cong = np.full(T, np.nan)
    mirrored: list[int] = []
    if have.any():
        fit = leave_one_out_residual(D[have], cut_shapes[have])
        dl = np.abs(geometry.edge_lengths(cut_shapes[have]) - geometry.edge_lengths(D[have])).max(
            axis=1
        )
        cong[have] = np.maximum(fit, dl)
        bad = np.flatnonzero(have)[cong[have] > tol]
        if len(bad):
            mres, _ = _shift_fit(D[bad], _mirror(cut_shapes[bad]))
            mirrored = bad[mres <= np.maximum(tol, 0.5 * cong[bad])].tolist()
    worst_cong = int(np.nanargmax(cong)) if have.any() else None
    rep.add(
        measured(
            f"{g}: (a) cut tiles congruent to design",
            float(np.nanmax(cong)) if have.any() else np.nan,
            tol,
            "mm",
            worst=f"tile {worst_cong}" if worst_cong is not None else None,
            group=g,
            detail=(f"mirrored tiles {mirrored}; " if mirrored else "")
            + "largest corner offset from a proper rigid fit of the other corners, and edge-length change",
        )
    )


def _in_place_checks(
    rep: Report,
    pattern: Pattern,
    m: _Matched,
    have: np.ndarray,
    tol: Tolerances,
    g: str,
    n_sheets: int,
) -> None:
    """(b) in place: the sheet is the declared closed state."""
    rep.add(
        measured(
            f"{g}: (b) in place = closed state {m.state}",
            float(np.nanmax(m.resid_pos)) if have.any() else np.nan,
            tol.length,
            "mm",
            worst=f"tile {int(np.nanargmax(m.resid_pos))}" if have.any() else None,
            group=g,
            detail="corner distance to the design's closed state under one rigid motion per sheet",
        )
    )
    if not have.all() or n_sheets != 1:
        return
    # every tile found: the sheet's state (congruence is (a); the in-place fit replaces loop closure)
    skip = {
        state_check_id(m.state, k)
        for k in ("congruent-lengths", "congruent-angles", "loop-closure")
    }
    for chk in closed_state_checks(pattern, m.cut_shapes, m.state, tol):
        if chk.id in skip:
            continue
        chk.name = f"{g}: (b) sheet {chk.name}"
        chk.group = g
        chk.id = f"{g}.sheet.{chk.id}" if chk.id else ""
        rep.add(chk)


def _reassembly_checks(
    rep: Report,
    pattern: Pattern,
    cut_shapes: np.ndarray,
    have: np.ndarray,
    rebuild: list[int],
    tol: Tolerances,
    g: str,
) -> None:
    """(c) the cut tiles reassembled by the hinge correspondence give the closed states in ``rebuild``."""
    for s in rebuild:
        name = f"{g}: (c) state {s} from cut tiles"
        if not have.all():
            rep.add(
                Check(
                    f"{name}: loop closure",
                    ok=False,
                    value=None,
                    tol=tol.length,
                    unit="mm",
                    group=g,
                    detail="cannot reassemble: tiles are missing",
                    id=f"{g}.reassembled.{state_check_id(s, 'loop-closure')}",
                )
            )
            continue
        Y, split = assembled(pattern, cut_shapes, s)
        rep.add(
            measured(
                f"{name}: loop closure",
                float(split.max(initial=0.0)),
                tol.length,
                "mm",
                worst=f"hinge {int(np.argmax(split))}" if len(split) else None,
                group=g,
                detail="hinge split of the least-squares assembly of the cut tiles",
                id=f"{g}.reassembled.{state_check_id(s, 'loop-closure')}",
            )
        )
        congruent = {state_check_id(s, k) for k in ("congruent-lengths", "congruent-angles")}
        for chk in closed_state_checks(pattern, Y, s, tol):
            if chk.id in congruent:  # the cut tiles' congruence is (a)
                continue
            chk.name = f"{name}: {chk.name.split(': ', 1)[1]}"
            chk.group = g
            chk.id = f"{g}.reassembled.{chk.id}" if chk.id else ""
            rep.add(chk)


def _hinge_check(
    rep: Report,
    pattern: Pattern,
    al: Allowances,
    m: _Matched,
    have: np.ndarray,
    in_place: bool,
    tol: float,
    g: str,
) -> None:
    """(d) every hinge present: both tiles cut (in place: their hinge corners coincide; ligament: listed)."""
    top = pattern.topology
    A, B = top.hinge_tiles.T
    found_on, cut_shapes = m.found_on, m.cut_shapes
    present = have[A] & have[B]
    why = "both tiles cut"
    if in_place and present.any():
        cA, cB = top.hinge_corner.T
        ok = np.zeros(len(A), dtype=bool)
        sel = np.flatnonzero(present)
        ok[sel] = (
            np.linalg.norm(cut_shapes[A[sel], cA[sel]] - cut_shapes[B[sel], cB[sel]], axis=1) <= tol
        )
        cross = found_on[A] != found_on[B]  # split along cut lines onto two sheets
        ok |= cross
        present &= ok
        why = "both tiles cut, hinge corners coincide on the sheet"
        if (cross & present).any():
            why += f" ({int((cross & present).sum())} hinges cross sheets)"
    how = reading(al.hinge)  # None: no manifest, or a kind the verifier cannot read
    if (
        how is not None and how.declared_hinges
    ):  # a hinge is there only where its feature is declared
        listed = {int(f.get("hinge", -1)) for f in al.hinge_features if f.get("polygon")}
        h_idx = np.arange(len(A))
        split = np.isin(h_idx, list(al.cross_sheet)) & (found_on[A] != found_on[B])
        present &= np.isin(h_idx, list(listed)) | split
        why += ", a ligament listed"
        if split.any():
            why += f" or the hinge declared split across sheets ({int(split.sum())}, to be joined by hand)"
    absent = np.flatnonzero(~present)
    rep.add(
        Check(
            f"{g}: (d) every hinge present",
            ok=not len(absent),
            value=int(len(absent)),
            tol=0,
            unit="count",
            group=g,
            worst=f"hinge {int(absent[0])}" if len(absent) else None,
            detail=f"{len(absent)} of {len(A)} hinges missing ({why})" if len(absent) else why,
        )
    )


def _ligament_checks(
    rep: Report,
    pattern: Pattern,
    al: Allowances,
    linework: dict[int, Linework],
    m: _Matched,
    have: np.ndarray,
    fitted: float | None,
    g: str,
) -> None:
    """Ligaments present and uncut, sheet by sheet (a ligament sheet)."""
    from .physical import ligament_check

    A, B = pattern.topology.hinge_tiles.T
    shrink = al.tile_shrink if al.hinge != PLAIN else -(fitted or 0.0)
    kerf = al.kerf_offset if al.hinge != PLAIN else 0.0
    cores = np.full(len(m.cut_shapes), None, dtype=object)
    cores[have] = shapely.buffer(
        shapely.polygons(m.cut_shapes[have]),
        -shrink,
        join_style="mitre",
        mitre_limit=al.mitre_limit,
    )
    for sheet, lw in linework.items():
        on = have & (m.found_on == sheet)
        hinges = np.flatnonzero(on[A] & on[B] & ~np.isin(np.arange(len(A)), list(al.cross_sheet)))
        if not len(hinges):
            continue
        c = cores.copy()
        c[~on] = None
        material = sheet_material(lw, kerf)
        if not al.ligaments_in_file and len(shapely.get_parts(material)) >= on.sum():
            continue  # declared: the ligaments are not in this file (the printed top faces)
        rep.add(ligament_check(pattern, material, c, on, list(lw.polylines), hinges, g))


def _tape_mark_checks(
    rep: Report,
    pattern: Pattern,
    al: Allowances,
    files: dict[int, Path],
    m: _Matched,
    have: np.ndarray,
    g: str,
) -> None:
    """Tape marks at the hinges (an in-place tape layout). A symmetric sheet matches the design in several
    equally good ways (``m.labelings``), which put the hinges at different corners; its marks say which
    one was cut, so the best of them is reported."""
    from .physical import tape_mark_check

    how = reading(al.hinge)  # None: no manifest, or a kind the verifier cannot read
    marks_kind = how is not None and how.tape_marks  # the kind's hinges carry tape marks
    if not (al.hinge == PLAIN or marks_kind):
        return
    marks = {}
    for sheet, f in files.items():
        read = read_cut_file(f, "ENGRAVE")
        if read.layer_found:
            marks[sheet] = read.polylines
    if not marks:
        return  # no named engrave layer (a colour-only file): marks cannot be told from cuts
    hs, marked, room, turned = _marked_labeling(
        pattern, m.cut_shapes, m.labelings, have, m.found_on, marks
    )
    if not len(hs) or not (marks_kind and al.labels) and marked.sum() < 0.5 * len(hs):
        return  # no tape hinges on one sheet, or a layout without tape marks (the manifest does not say)
    chk = tape_mark_check(hs, marked, room, g)
    if turned:
        chk.detail += (
            f" (sheet(s) {turned} symmetric: hinges placed by the labeling their marks fit best)"
        )
    rep.add(chk)


def _marked_labeling(
    pattern: Pattern,
    cut_shapes: np.ndarray,
    labelings: Sequence[tuple[int, np.ndarray]],
    have: np.ndarray,
    found_on: np.ndarray,
    marks: dict,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, list[int]]:
    """:func:`~.physical.mark_status` sheet by sheet, each sheet on its own hinges and marks: under the
    matched labeling, or, where that leaves a hinge with room unmarked and the sheet is symmetric, under the
    labeling whose hinges carry the most marks (the first on a tie). Also the sheets so relabelled."""
    from .physical import mark_status

    parts, turned = [], []
    for sheet in np.unique(found_on[have]).tolist():
        on = have & (found_on == sheet)
        mine = {sheet: marks[sheet]} if sheet in marks else {}
        best = mark_status(pattern, cut_shapes, on, found_on, mine)
        others = [L for s, L in labelings if s == sheet]
        if others and (best[2] & ~best[1]).any():
            tries = [best, *(mark_status(pattern, L, on, found_on, mine) for L in others)]
            k = max(range(len(tries)), key=lambda i: (int(tries[i][1].sum()), -i))
            best = tries[k]
            if k:
                turned.append(int(sheet))
        parts.append(best)
    if not parts:
        return np.zeros(0, np.int64), np.zeros(0, bool), np.zeros(0, bool), turned
    hs, marked, room = (np.concatenate(x) for x in zip(*parts))
    order = np.argsort(hs, kind="stable")
    return hs[order], marked[order], room[order], turned


def _dangling_check(
    ends: np.ndarray, cut_shapes: np.ndarray, have: np.ndarray, g: str, tol: float
) -> Check:
    """A cut that stops in the material: a slit short of its end leaves two tiles joined, a stray
    cut weakens a part. Names the tiles nearest the first such end."""
    worst, detail = None, "every cut line ends on another cut"
    if len(ends):
        ids = np.flatnonzero(have)
        where = []
        if len(ids):
            polys = shapely.polygons(cut_shapes[ids])
            d = shapely.distance(polys[None, :], shapely.points(ends[:1])[:, None])[0]
            near = ids[np.argsort(d)[:2]]
            where = [int(t) for t, dd in zip(near, np.sort(d)[:2]) if dd <= max(10 * tol, 1.0)]
        if len(where) == 2:
            worst = f"tiles {where[0]}/{where[1]}"
            detail = (
                f"the slit between tiles {where[0]} and {where[1]} stops short: they stay joined"
            )
        elif where:
            worst = f"tile {where[0]}"
            detail = f"a cut ends inside tile {where[0]}"
        else:
            detail = "a cut ends in the material"
        detail += f" ({len(ends)} cut ends in the material, first at ({ends[0, 0]:.4g}, {ends[0, 1]:.4g}) mm)"
    return Check(
        f"{g}: cuts run their full length",
        ok=not len(ends),
        value=int(len(ends)),
        tol=0,
        unit="count",
        group=g,
        worst=worst,
        detail=detail,
    )
