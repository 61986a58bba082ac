"""The standard rotating-squares quad lattice (docs/algorithm.md#lattice).

Tile ``(r, c)`` (row from the bottom, column from the left) is tile index
``r * cols + c``; its corners are BL, BR, TR, TL (counter-clockwise). At
deployment angle ψ the tile sits at

    x(T, k; ψ) = s · [ a(ψ) (c + ½, r + ½) + Rot(-σ_T ψ) (δx_k - ½, δy_k - ½) ]

with a(ψ) = cos ψ + sin ψ, σ_T = +1 on even tiles ((r + c) even) and -1 on odd
ones, and s the tile size in mm. ψ = 0 is closed state 1, ψ = π/4 the standard
deployed state (square holes), ψ = π/2 closed state 2.
"""

from __future__ import annotations

import numpy as np

from ....errors import InputError
from ...model import Pattern

DX = np.array([0.0, 1.0, 1.0, 0.0])
DY = np.array([0.0, 0.0, 1.0, 1.0])


def quad_topology(rows: int, cols: int) -> tuple[np.ndarray, np.ndarray]:
    """Tiles ``(T, 4)`` and, for each node, one (tile, corner) that uses it.

    Nodes are numbered in order of first use, scanning tiles row by row and
    corners BL, BR, TR, TL.
    """
    _check_size(rows, cols)
    T = rows * cols
    r, c = np.divmod(np.arange(T), cols)
    parent = np.arange(4 * T)  # corner id 4*t+k -> representative corner id
    even = (r + c) % 2 == 0
    # horizontal neighbours (r, c)|(r, c+1): even left tile joins TR≡TL, odd BR≡BL
    left = np.flatnonzero(c < cols - 1)
    k_left = np.where(even[left], 2, 1)
    k_right = np.where(even[left], 3, 0)
    parent[4 * (left + 1) + k_right] = 4 * left + k_left
    # vertical neighbours (r, c)|(r+1, c): even lower tile joins TL≡BL, odd TR≡BR
    low = np.flatnonzero(r < rows - 1)
    k_low = np.where(even[low], 3, 2)
    k_up = np.where(even[low], 0, 1)
    parent[4 * (low + cols) + k_up] = 4 * low + k_low
    # a corner is merged at most once and always into an earlier tile's corner,
    # which is itself never merged further (it belongs to the lower/left tile)
    rep = parent[parent]
    uniq, first_index, inverse = np.unique(rep, return_index=True, return_inverse=True)
    order = np.argsort(first_index)  # number nodes by first appearance
    rank = np.empty_like(order)
    rank[order] = np.arange(len(order))
    tiles = rank[inverse].reshape(T, 4)
    return tiles, uniq[order]


def quad_corners(rows: int, cols: int, angle: float, tile_size: float = 1.0) -> np.ndarray:
    """Per-tile corners ``(T, 4, 2)`` of the standard pattern at angle ψ (radians)."""
    _check_size(rows, cols)
    T = rows * cols
    r, c = np.divmod(np.arange(T), cols)
    sigma = np.where((r + c) % 2 == 0, 1.0, -1.0)
    a = np.cos(angle) + np.sin(angle)
    centre = a * np.stack([c + 0.5, r + 0.5], -1)
    off = np.stack([DX - 0.5, DY - 0.5], -1)  # (4, 2)
    th = -sigma[:, None] * angle
    cs, sn = np.cos(th), np.sin(th)
    rx = cs * off[None, :, 0] - sn * off[None, :, 1]
    ry = sn * off[None, :, 0] + cs * off[None, :, 1]
    return tile_size * (centre[:, None, :] + np.stack([rx, ry], -1))


def standard_pattern(
    rows: int, cols: int, *, tile_size: float = 10.0, angle_deg: float = 45.0, name: str = ""
) -> Pattern:
    """The standard rotating-squares pattern, centred on the origin, in mm.

    It carries no contracted states; compute them with
    :func:`fabkiri.mechanics.contract.with_contracted_states`.
    """
    if not np.isfinite(tile_size) or tile_size <= 0:
        raise InputError(f"tile size must be a positive length in mm, got {tile_size}")
    if not np.isfinite(angle_deg) or not 0.0 <= angle_deg <= 90.0:
        raise InputError(f"deployment angle must lie in [0, 90] degrees, got {angle_deg}")
    tiles, rep = quad_topology(rows, cols)
    corners = quad_corners(rows, cols, np.radians(angle_deg), tile_size)
    return centred_standard(
        "quad",
        tiles,
        corners.reshape(-1, 2)[rep],
        rows,
        cols,
        angle_deg,
        tile_size,
        name or f"standard {rows}x{cols}",
    )


def centred_standard(
    kind: str,
    tiles: np.ndarray,
    nodes: np.ndarray,
    rows: int,
    cols: int,
    angle_deg: float,
    tile_size: float,
    name: str,
) -> Pattern:
    """A kind's standard pattern from its nodes, centred on the origin (bounding-box centre), with
    the lattice record every standard pattern carries."""
    lo, hi = nodes.min(0), nodes.max(0)
    return Pattern(
        nodes=nodes - 0.5 * (lo + hi),
        tiles=tiles,
        name=name,
        lattice={
            "kind": kind,
            "rows": rows,
            "cols": cols,
            "angle_deg": float(angle_deg),
            "tile_size": float(tile_size),
        },
        kind=kind,
    )


def _check_size(rows: int, cols: int) -> None:
    if int(rows) != rows or int(cols) != cols or rows < 1 or cols < 1:
        raise InputError(f"a lattice needs at least 1x1 tiles, got {rows}x{cols}")
