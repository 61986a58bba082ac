"""Matching recovered tiles to the design tiles: by position in place (one rigid motion per sheet), by shape
when the tiles are separate (one per tile)."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..mechanics.contract import contract
from ..pattern.model import Pattern
from ..pattern.topology import STATES
from .hingeread import PLAIN
from .manifest import Allowances
from .matching import match_by_shape, match_in_place
from .report import Report
from .sheetread import _Recovered


@dataclass
class _Matched:
    """Recovered tiles matched to design tiles."""

    state: int  # the closed state the sheet is laid out in
    assign: np.ndarray  # design tile -> global recovered index, -1 if not found
    found_on: np.ndarray  # design tile -> sheet it was found on
    cut_shapes: np.ndarray  # (T, 4, 2) each design tile's cut shape, corners in design order
    resid_pos: np.ndarray  # in place: corner distance to the closed state
    # (sheet, cut shapes) under another, equally good labeling of a symmetric sheet: that sheet's tiles
    # take the shapes, every other tile is NaN
    labelings: list[tuple[int, np.ndarray]]
    extra_shapes: list[np.ndarray] = field(default_factory=list)  # the unmatched regions' corners

    @property
    def extra(self) -> int:
        """Recovered regions matched to no design tile."""
        return len(self.extra_shapes)


def _match_tiles(
    pattern: Pattern,
    al: Allowances,
    rec: _Recovered,
    in_place: bool,
    D: np.ndarray,
    L: float,
    tol: float,
    rep: Report,
) -> _Matched:
    """Match every sheet's quads to the design tiles: by position in place, by shape when separate."""
    T = pattern.n_tiles

    def closed(s: int) -> np.ndarray:
        Y = pattern.contracted.get(s)
        return (contract(pattern, s).corners if Y is None else Y) * al.scale

    state = al.state
    sheets = rec.sheets
    if in_place and al.hinge == PLAIN and sheets:
        # no manifest declares the state: take the closed state the sheet matches
        R0 = next(iter(sheets.values()))
        fit = {s: np.nanmax(np.append(match_in_place(closed(s), R0)[1], np.nan)) for s in STATES}
        state = min(STATES, key=lambda s: fit[s] if np.isfinite(fit[s]) else np.inf)
        rep.meta["state"] = state
    k = D.shape[1]  # the tile arity
    m = _Matched(
        state, np.full(T, -1), np.full(T, -1), np.full((T, k, 2), np.nan), np.full(T, np.nan), []
    )
    Ystate = closed(state)
    for sheet, R in sheets.items():
        if in_place:
            a, res, sh = _match_sheet_in_place(al, m, sheet, R, Ystate, T, tol)
        else:
            free = np.flatnonzero(m.assign < 0)
            a, res, sh = match_by_shape(D[free], R, L)
            a = np.where(a >= 0, free[np.maximum(a, 0)], -1)
        taken = (a >= 0) & (m.assign[np.maximum(a, 0)] < 0)
        m.extra_shapes.extend(R[~taken])
        r = np.flatnonzero(taken)
        d = a[r]
        m.assign[d] = r
        m.found_on[d] = sheet
        m.cut_shapes[d] = R[
            r[:, None], (np.arange(k)[None, :] + sh[r][:, None]) % k
        ]  # corner shift
        if in_place:
            m.resid_pos[d] = res[r]
    return m


def _match_sheet_in_place(
    al: Allowances,
    m: _Matched,
    sheet: int,
    R: np.ndarray,
    Ystate: np.ndarray,
    T: int,
    tol: float,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """One in-place sheet matched to its design tiles; a symmetric sheet also records the other
    labelings that fit as well (``m.labelings``): each sheet of a large pattern may be symmetric on its
    own, and only its tape marks say which way it was cut."""
    design_ids = (
        np.array(sorted(t for t, s in al.tile_sheet.items() if s == sheet), dtype=np.int64)
        if al.tile_sheet
        else np.arange(T)
    )
    design_ids = design_ids[design_ids < T]
    alts: list = []
    a, res, sh, _, _ = match_in_place(Ystate[design_ids], R, alternatives=alts)
    a = np.where(a >= 0, design_ids[np.maximum(a, 0)], -1)
    for aa, rr, ss in alts:  # a symmetric sheet: the other labelings as good as this one
        if (aa >= 0).sum() == len(design_ids) and np.max(rr[aa >= 0]) <= tol:
            n = R.shape[1]  # the tile arity
            C = np.full((T, n, 2), np.nan)
            k = np.flatnonzero(aa >= 0)
            C[design_ids[aa[k]]] = R[k[:, None], (np.arange(n)[None, :] + ss[k][:, None]) % n]
            m.labelings.append((sheet, C))
    return a, res, sh
