"""Reading a cut layout's sheets back: the files of every sheet, their linework and the tiles recovered.

:func:`_recover_sheets` reads each sheet, sets its reference square aside and recovers its tiles;
:func:`_layout_kind` tells an in-place layout from separate tiles (and fits the kerf of a plain file).
The checks on what was recovered are :mod:`.layout`'s.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import shapely

from ..errors import VerifyError
from ..exchange.file_formats import read_cut_file
from ..exchange.linework import Linework
from ..mechanics.contract import contract
from ..pattern import geometry
from ..pattern.kinds.tessellation import tessellation
from ..pattern.model import Pattern
from .hingeread import PLAIN
from .manifest import Allowances
from .quads import (
    MAX_FITTED_SHRINK_MM,
    UNDO_MITRE,
    _fit_offset,
    _set_reference_aside,
    quads_of,
    tiles_of,
)
from .recovery import _choose_cut, _drop_reference, dangling_ends, recover_polygons
from .report import Report


@dataclass
class _Recovered:
    """What each sheet's cut linework gave: its quads, linework, recovery methods and loose ends."""

    sheets: dict[int, np.ndarray] = field(
        default_factory=dict
    )  # sheet -> recovered quads (n, 4, 2)
    linework: dict[int, Linework] = field(default_factory=dict)
    methods: set[str] = field(default_factory=set)
    unusable: int = 0  # regions that are not quads
    dangling: list[np.ndarray] = field(default_factory=list)
    references: list[float] = field(default_factory=list)


def _recover_sheets(
    pattern: Pattern,
    al: Allowances,
    files: dict[int, Path],
    D: np.ndarray,
    L: float,
    tol: float,
    path: Path,
) -> _Recovered:
    """Read every sheet, set its reference square aside and recover its tiles as quads."""
    rec = _Recovered()
    n_lines = 0
    frame = _frame_tiles(pattern, al)
    arity = tessellation(pattern.kind).arity  # corners per tile
    for sheet, f in files.items():
        lw = _choose_cut(read_cut_file(f).cut_classes(), al, sheet, D, L, tol)
        declared = al.reference.get(sheet)
        dropped = _drop_reference(lw, declared, tol)
        rec.linework[sheet] = lw
        n_lines += len(lw.polylines)
        on = [t for t in range(pattern.n_tiles) if al.tile_sheet.get(t, 1) == sheet]
        polys, method = recover_polygons(
            lw, al, sheet, frame[on] if frame is not None else None, arity
        )
        rec.methods.add(method)
        polys = polys[shapely.area(polys) > tol**2]  # double-cut hairlines are not tiles
        search = _search_reference(al, declared, dropped)
        quads, side, bad = _tiles_and_reference(polys, arity, D, L, tol, len(on), search)
        if side is not None:
            rec.references.append(side)
        rec.unusable += bad
        rec.sheets[sheet] = quads
        rec.dangling.append(dangling_ends(lw))
    if n_lines == 0:  # a sheet may hold only the reference square, the whole layout may not
        raise VerifyError(
            f"{path}: no cut geometry (nothing on layer CUT besides the reference square)"
        )
    return rec


def _search_reference(al: Allowances, declared: np.ndarray | None, dropped: int) -> bool:
    """Whether the reference square is still to be set aside by geometry: a file without a manifest, or
    a manifest's square not found (the sheet was moved and several squares have its side). Not when the
    manifest's square was dropped or the manifest declares none on this sheet: a square left is a part,
    never a second reference."""
    return al.hinge == PLAIN or (declared is not None and not dropped)


def _tiles_and_reference(
    polys: np.ndarray,
    arity: int,
    D: np.ndarray,
    L: float,
    tol: float,
    n_tiles: int | None = None,
    search: bool = True,
) -> tuple[np.ndarray, float | None, int]:
    """The tiles (corners in the design's arity), the reference square's side (None without one) and
    how many regions are neither. The square is looked for among the quads: the tiles themselves
    when they are quads, the regions that are not tiles otherwise (not at all unless ``search``, see
    :func:`_search_reference`; ``n_tiles``: the design tiles on the sheet)."""
    tiles, ok = tiles_of(polys, arity)
    if not search:
        return tiles, None, int((~ok).sum())
    if arity == 4:
        tiles, side = _set_reference_aside(tiles, D, L, tol, n_tiles)
        return tiles, side, int((~ok).sum())
    squares, _ = quads_of(polys[~ok], 4)
    _, side = _set_reference_aside(squares, D, L, tol)
    return tiles, side, int((~ok).sum()) - (side is not None)


def _layout_kind(
    rec: _Recovered, al: Allowances, D: np.ndarray, L: float, tol: float, rep: Report
) -> tuple[bool, bool, float | None]:
    """In place or separate, a ligament sheet or not, and (plain files) the kerf offset fitted."""
    in_place = al.layout == "in-place"
    sheet_piece = any(
        m.startswith("material") for m in rec.methods
    )  # a ligament sheet: tiles in place, shrunk
    sheets = rec.sheets
    if al.layout == "auto":  # plain file: in place if the outlines tile one connected region
        allq = np.concatenate(list(sheets.values())) if sheets else np.zeros((0, D.shape[1], 2))
        if len(allq):
            u = shapely.unary_union(shapely.make_valid(shapely.polygons(allq))).buffer(tol)
            in_place = (len(shapely.get_parts(u)) == 1 and len(allq) > 1) or sheet_piece
        rep.meta["layout"] = "in-place" if in_place else "separate"
    fitted = None
    if al.hinge == PLAIN and (not in_place or sheet_piece) and sheets:
        # no manifest declares the kerf (or the gap): take the one offset the outlines share
        fitted = _fit_offset(
            np.concatenate(list(sheets.values())),
            D,
            L,
            tol,
            lo=-MAX_FITTED_SHRINK_MM if sheet_piece else 0.0,
        )
        if fitted:
            for k, R in sheets.items():
                sheets[k], bad = quads_of(
                    shapely.buffer(
                        shapely.polygons(R), -fitted, join_style="mitre", mitre_limit=UNDO_MITRE
                    ),
                    R.shape[1],
                )
                rec.unusable += bad
        rep.meta["kerf_offset_fitted_mm"] = fitted
    return in_place, sheet_piece, fitted


def _frame_tiles(pattern: Pattern, al: Allowances) -> np.ndarray | None:
    """Design tiles where the manifest placed them: Rot(rotation) (scaled closed-state tile) + shift."""
    if al.layout != "in-place" or len(al.tiles_placed) != pattern.n_tiles:
        return None
    Y = pattern.contracted.get(al.state)
    Y = (contract(pattern, al.state).corners if Y is None else Y) * al.scale
    out = np.empty_like(Y)
    for t, (th, shift) in al.tiles_placed.items():
        out[t] = geometry.rotate(Y[t], th) + shift
    return out


def _sheet_files(path: Path, al: Allowances) -> dict[int, Path]:
    """Every sheet of the layout in the same format as ``path`` (just ``path`` for one sheet)."""
    fmt = path.suffix.lower().lstrip(".")
    named = {k: v[fmt] for k, v in al.sheet_files.items() if v.get(fmt)}
    if len(named) <= 1:
        sheet = next((k for k, v in named.items() if v == path.name), 1)
        return {sheet: path}
    if path.name not in named.values():
        raise VerifyError(
            f"{path}: not one of the sheets listed in the manifest ({sorted(named.values())})"
        )
    out = {}
    for k, name in sorted(named.items()):
        f = path.parent / name
        if not f.exists():
            raise VerifyError(f"{f}: sheet {k} listed in the manifest is missing")
        out[k] = f
    return out
