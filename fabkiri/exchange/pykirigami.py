"""PyKirigami (github.com/andy-qhjiang/PyKirigami) model folders: export and import.

PyKirigami's PyBullet simulator reads a folder ``data/<model>/`` of plain text:

* ``vertices.txt``: one line per tile, ``x1 y1 z1 x2 y2 z2 ...`` (the start
  configuration: here closed state 1);
* ``target.txt``: the same for the configuration the tiles are pulled to
  (here the deployed state);
* ``constraints.txt``: one line per joint, ``tile_a corner_a tile_b corner_b type``,
  0-based; type 1 joins the bottom faces, 2 the top, 3 both (what its auto
  detection picks for a planar 2D -> 2D deployment, and what we write).

Its loader rejects a constraint whose two corners lie more than 0.05 units
apart in either file, or whose indices are out of range, or a duplicate.
Its examples use unit tiles, so coordinates are written in units of the mean
tile edge by default (``unit_mm``); no blank lines or comments (the loader
would read a blank line as an empty tile).
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from .. import limits
from ..errors import PatternError
from ..pattern.kinds.tessellation import kind_of_arity
from ..pattern.model import Pattern
from .file_formats import PatternFormat, register_format
from .pattern_json import _read_text

FILES = ("vertices.txt", "constraints.txt", "target.txt")
JOINT_BOTH_FACES = 3


def _tile_lines(corners: np.ndarray) -> str:
    T, n = corners.shape[:2]
    xyz = np.concatenate([corners, np.zeros((T, n, 1))], axis=2).reshape(T, 3 * n)
    return "".join(" ".join(repr(float(v)) for v in row) + "\n" for row in xyz)


def constraint_rows(pattern: Pattern) -> np.ndarray:
    """``(H, 5)``: tile A, its hinge corner, tile B, its hinge corner, type (both faces)."""
    top = pattern.topology
    A, B = top.hinge_tiles.T
    cA, cB = top.hinge_corner.T
    return np.stack([A, cA, B, cB, np.full(len(A), JOINT_BOTH_FACES)], 1).astype(np.int64)


def pykirigami_files(
    pattern: Pattern, start: np.ndarray, unit_mm: float | None = None
) -> dict[str, str]:
    """The three files: ``start`` (per-tile corners, e.g. closed state 1) and the deployed target."""
    unit = float(unit_mm or pattern.tile_size)
    rows = constraint_rows(pattern)
    return {
        "vertices.txt": _tile_lines(np.asarray(start, dtype=float) / unit),
        "target.txt": _tile_lines(pattern.corners() / unit),
        "constraints.txt": "".join(" ".join(str(v) for v in r) + "\n" for r in rows.tolist()),
    }


def _read_tiles(path: Path) -> np.ndarray:
    rows: list[list[float]] = []
    for k, line in enumerate(_read_text(path).splitlines(), 1):
        try:
            vals = [float(v) for v in line.split()]
        except ValueError:
            raise PatternError(f"{path}: line {k}: not numbers") from None
        n = len(vals) // 3
        if len(vals) % 3 or kind_of_arity(n) is None or (rows and len(vals) != len(rows[0])):
            raise PatternError(
                f"{path}: line {k}: {len(vals)} values; fabkiri reads quads (12 values) "
                f"or kagome triangles (9), all of one kind"
            )
        rows.append(vals)
    if not rows:
        raise PatternError(f"{path}: no tiles")
    a = np.asarray(rows).reshape(len(rows), -1, 3)
    if np.abs(a[..., 2]).max() > 0:
        raise PatternError(f"{path}: z != 0; fabkiri patterns are planar")
    return a[..., :2]


def read_pykirigami(folder: str | os.PathLike, unit_mm: float = 1.0) -> Pattern:
    """A pattern from a PyKirigami folder: the target is the deployed state, its tiles' corners
    joined into nodes by the constraints; ``vertices.txt`` becomes closed state 1."""
    d = Path(folder)
    missing = [f for f in FILES if not (d / f).is_file()]
    if missing:
        raise PatternError(f"{d}: not a PyKirigami model folder (missing {', '.join(missing)})")
    start = _read_tiles(d / "vertices.txt") * unit_mm
    target = _read_tiles(d / "target.txt") * unit_mm
    if start.shape != target.shape:
        raise PatternError(f"{d}: vertices.txt has {len(start)} tiles, target.txt {len(target)}")
    T, n = target.shape[:2]
    parent = np.arange(n * T)

    def root(i: int) -> int:
        while parent[i] != i:
            parent[i] = parent[parent[i]]
            i = parent[i]
        return i

    for k, line in enumerate(_read_text(d / "constraints.txt").splitlines(), 1):
        parts = line.split()
        if not parts:
            continue
        try:
            a, ca, b, cb = (int(v) for v in parts[:4])
        except ValueError:
            raise PatternError(f"{d / 'constraints.txt'}: line {k}: not integers") from None
        if not (0 <= a < T and 0 <= b < T and 0 <= ca < n and 0 <= cb < n):
            raise PatternError(f"{d / 'constraints.txt'}: line {k}: index out of range")
        parent[root(n * a + ca)] = root(n * b + cb)
    roots = np.array([root(i) for i in range(n * T)])
    uniq, first, inverse = np.unique(roots, return_index=True, return_inverse=True)
    rank = np.empty(len(uniq), dtype=np.int64)
    rank[np.argsort(first)] = np.arange(len(uniq))  # nodes numbered by first corner, tile by tile
    tiles = rank[inverse]
    nodes = np.zeros((len(uniq), 2))
    nodes[tiles] = target.reshape(
        -1, 2
    )  # joined corners coincide in the target (the loader checks it)
    return Pattern(
        nodes=nodes,
        tiles=tiles.reshape(T, n),
        contracted={1: start},
        name=d.name,
        kind=kind_of_arity(n) or "quad",
        design={"source": {"pykirigami": d.name, "unit_mm": unit_mm}},
    )


def _start(state: str) -> int:
    return (
        1 if state == "deployed" else int(state)
    )  # a model starts closed, pulled to the deployed target


def _write(pattern: Pattern, state: str, unit: float | None) -> dict[str, str]:
    return pykirigami_files(pattern, pattern.contracted[_start(state)], unit or pattern.tile_size)


def _said(pattern: Pattern, state: str, output: str, unit: float | None) -> str:
    return (
        f"wrote {output}/vertices.txt (closed state {_start(state)}), target.txt (deployed), constraints.txt "
        f"({pattern.topology.n_hinges} joints); 1 unit = {unit or pattern.tile_size:.6g} mm"
    )


register_format(
    PatternFormat(
        "pykirigami",
        directory=True,
        read=lambda path, scale: limits.check_pattern(
            read_pykirigami(path, unit_mm=scale), str(path)
        ),
        write=_write,
        closed_states=lambda state: (_start(state),),
        said=_said,
        takes_unit=True,
    )
)
