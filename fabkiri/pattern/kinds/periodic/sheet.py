"""Periodic quad patterns: a tube's sheet, its seam and the seam map of every state.

A tube of ``C`` tile columns is stored as a planar pattern of ``C + 1`` columns whose last column is a
copy of the first (see docs/tubes.md). The copy column carries the seam: the hinges and holes between
column ``C - 1`` and the copy are the tube's seam hinges and seam holes, so the topology, the closed
states and every planar constraint apply unchanged. What makes the sheet a tube is the **seam map**,
the rigid motion taking the first column's tiles onto the copy's, corner by corner:

- in the deployed state it is a pure translation (a cylinder) or a rotation about an apex (a cone);
- in each closed state it must be a pure translation, so the sheet rolls into a cylinder in that state.

The seam is metadata on the pattern, ``lattice["seam"]``: the tube's column count and, for each row,
the pair ``(tile of the first column, its copy)``; corners correspond in order. It round-trips through
pattern.json with the rest of the lattice record.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ....errors import InputError, PatternError
from ... import geometry
from ...model import Pattern

SEAM_KINDS = ("cylinder", "cone")  # the deployed seam map: translation, or rotation about an apex


@dataclass(frozen=True)
class Seam:
    """Which tiles the seam identifies.

    ``pairs`` is ``(R, 2)``: tile of the first column, its copy in the seam column (corner ``k`` of one
    is corner ``k`` of the other). ``columns`` counts the tube's own columns (the copy excluded);
    ``deployed`` names the deployed seam map (``"cylinder"`` or ``"cone"``); ``closed`` the closed
    states' (``"cylinder"``: a pure translation, the issue's contract; ``"cone"``: a rotation about an
    apex, allowed only with a cone deployed seam, docs/tubes.md "cone in every state").
    """

    pairs: np.ndarray
    columns: int
    deployed: str = "cylinder"
    closed: str = (
        "cylinder"  # "cone": the closed seams turn as the deployed one (a rigid cone tube)
    )

    @property
    def first(self) -> np.ndarray:
        return self.pairs[:, 0]

    @property
    def copy(self) -> np.ndarray:
        return self.pairs[:, 1]

    def to_dict(self) -> dict:
        out = {
            "columns": int(self.columns),
            "deployed": self.deployed,
            "pairs": self.pairs.tolist(),
        }
        return out if self.closed == "cylinder" else {**out, "closed": self.closed}

    def state_kind(self, state) -> str:
        """``"cylinder"`` or ``"cone"``: what the seam map of ``state`` ("deployed", 1 or 2) must be."""
        return self.deployed if state == "deployed" else self.closed

    def node_pairs(self, tiles: np.ndarray) -> np.ndarray:
        """``(m, 2)`` distinct (first-column node, copy node) pairs identified by the seam."""
        pairs = np.stack([tiles[self.first].ravel(), tiles[self.copy].ravel()], -1)
        return np.unique(pairs, axis=0)


def seam_of(pattern: Pattern) -> Seam | None:
    """The pattern's seam (None for a planar pattern); a malformed record raises one-line PatternError."""
    rec = (pattern.lattice or {}).get("seam")
    if rec is None:
        return None
    if not isinstance(rec, dict) or "pairs" not in rec or "columns" not in rec:
        raise PatternError("lattice.seam must be an object with 'columns' and 'pairs'")
    try:
        pairs = np.array(rec["pairs"], dtype=np.int64)
    except (TypeError, ValueError):
        raise PatternError(
            "lattice.seam.pairs must be [first-column tile, copy tile] pairs"
        ) from None
    if pairs.ndim != 2 or pairs.shape[1] != 2 or len(pairs) == 0:
        raise PatternError(
            f"lattice.seam.pairs must be (rows, 2) tile pairs, got shape {pairs.shape}"
        )
    bad = (pairs < 0) | (pairs >= pattern.n_tiles)
    if bad.any():
        raise PatternError(
            f"lattice.seam.pairs names tile {int(pairs[bad][0])}, but the pattern has "
            f"{pattern.n_tiles} tiles"
        )
    if len(np.unique(pairs)) != pairs.size:
        raise PatternError("lattice.seam.pairs uses a tile twice")
    kind = rec.get("deployed", "cylinder")
    if kind not in SEAM_KINDS:
        raise PatternError(f"lattice.seam.deployed must be {' or '.join(SEAM_KINDS)}, not {kind!r}")
    closed = rec.get("closed", "cylinder")
    if closed not in SEAM_KINDS or (closed == "cone" and kind != "cone"):
        raise PatternError(
            f"lattice.seam.closed must be cylinder, or cone with a cone deployed seam, not {closed!r}"
        )
    columns = rec["columns"]
    if not isinstance(columns, int) or columns < 2 or columns % 2:
        raise PatternError(f"lattice.seam.columns must be an even count >= 2, got {columns!r}")
    return Seam(pairs=pairs, columns=columns, deployed=kind, closed=closed)


def tube_tiles(pattern: Pattern, seam: Seam) -> np.ndarray:
    """Indices of the tube's own tiles (every tile but the seam copies)."""
    keep = np.ones(pattern.n_tiles, bool)
    keep[seam.copy] = False
    return np.flatnonzero(keep)


def flat_sheet(pattern: Pattern, seam: Seam) -> Pattern:
    """The tube's tiles once each, as a planar pattern (tiles renumbered in tube order: row by row, the
    copy column left out) with the stored closed states: the sheet that is cut, and that cut files are
    verified against."""
    keep = tube_tiles(pattern, seam)
    used, tiles = np.unique(pattern.tiles[keep], return_inverse=True)
    closed = {s: Y[keep] for s, Y in pattern.contracted.items()}
    lattice = {k: v for k, v in (pattern.lattice or {}).items() if k != "seam"}
    if "cols" in lattice:
        lattice["cols"] = seam.columns
    return Pattern(
        nodes=pattern.nodes[used],
        tiles=tiles.reshape(-1, pattern.tiles.shape[1]),
        contracted=closed,
        parity=pattern.parity,
        name=f"{pattern.name or 'tube'} (flat sheet)",
        lattice=lattice,
        kind=pattern.kind,
    )


@dataclass(frozen=True)
class SeamMap:
    """The seam map of one state: the best rigid motion first column -> copy, and how far from it.

    ``rotation`` (rad) and ``translation`` (mm) are the least-squares rigid fit; ``rigid_dev`` is the
    largest corner distance from it (mm); ``translation_dev`` the largest corner distance from the best
    *pure translation* (mm), which is what a closed state must bring to zero.
    """

    rotation: float
    translation: np.ndarray
    rigid_dev: float
    translation_dev: float
    worst_tile: int

    @property
    def period(self) -> float:
        """Length of the translation (mm): the tube's circumference when the map is a translation."""
        return float(np.linalg.norm(self.translation))


def seam_map(corners: np.ndarray, seam: Seam) -> SeamMap:
    """The seam map of per-tile corners ``(T, 4, 2)`` of any state."""
    P = corners[seam.first].reshape(-1, 2)
    Q = corners[seam.copy].reshape(-1, 2)
    d = Q - P
    t = d.mean(0)
    dev_t = np.linalg.norm(d - t, axis=1)
    theta, shift = geometry.kabsch(P, Q)
    dev_r = np.linalg.norm(geometry.rotate(P, theta) + shift - Q, axis=1)
    n = corners.shape[1]
    worst = int(seam.copy[int(np.argmax(dev_t)) // n])
    return SeamMap(
        rotation=float(theta),
        translation=shift,
        rigid_dev=float(dev_r.max()),
        translation_dev=float(dev_t.max()),
        worst_tile=worst,
    )


def lattice_seam(
    rows: int, cols: int, deployed: str = "cylinder", closed: str = "cylinder"
) -> Seam:
    """The seam of a standard lattice of ``rows x (cols + 1)`` tiles: column 0 and its copy, column ``cols``."""
    r = np.arange(rows)
    width = cols + 1
    return Seam(
        pairs=np.stack([r * width, r * width + cols], -1),
        columns=cols,
        deployed=deployed,
        closed=closed,
    )


def check_tube_size(rows: int, cols: int) -> None:
    """A tube needs an even column count (so the copy column has the first column's parity) and 2 rows."""
    if cols < 2 or cols % 2:
        raise InputError(
            f"a tube needs an even number of columns >= 2 (the seam copy column must have the "
            f"first column's colour), got {cols}"
        )
    if rows < 2:
        raise InputError(f"a tube needs at least 2 rows, got {rows}")


def with_seam(pattern: Pattern, seam: Seam) -> Pattern:
    """The pattern with ``seam`` recorded in its lattice metadata (checked against the pattern)."""
    from dataclasses import replace

    out = replace(pattern, lattice={**(pattern.lattice or {}), "seam": seam.to_dict()})
    seam_of(out)
    return out


def standard_tube(
    rows: int, cols: int, *, tile_size: float = 10.0, angle_deg: float = 45.0, name: str = ""
) -> Pattern:
    """The standard rotating-squares tube of ``rows x cols`` tiles (``cols`` even), as a planar sheet of
    ``cols + 1`` columns whose last column is the seam copy of the first."""
    from ..quad.lattice import standard_pattern

    check_tube_size(rows, cols)
    sheet = standard_pattern(
        rows,
        cols + 1,
        tile_size=tile_size,
        angle_deg=angle_deg,
        name=name or f"standard tube {rows}x{cols}",
    )
    return with_seam(sheet, lattice_seam(rows, cols))
