"""The kagome (rotating-triangles) tessellation: its standard lattice, fold rules and registry entry.

Tiles are triangles joined at corner hinges; the tile graph is a honeycomb, two-coloured into *up*
and *down* triangles that turn opposite ways as the pattern deploys. Every hole is a hexagon
bounded by six triangle edges. In a closed state the hole folds at three alternate corners (its
two edges there coincide) and its other three corners meet at one point, so the six edges
coincide in pairs; the other closed state pairs them shifted by one edge.

Standard lattice, ``rows x cols`` (R x C): R horizontal rows of C triangles each. Row ``r`` (from
the bottom) lies along one line of the kagome; tile ``(r, c)`` (column from the left) is tile
index ``r * cols + c``, an up triangle when ``r + c`` is even and a down triangle otherwise, so
the colouring is a checkerboard as for quads. Neighbours in a row share a node on the line; an
up triangle ``(r, c)`` shares its apex with the down triangle ``(r + 1, c)`` above it. Corners are
CCW: up (left, right, apex), down (left, apex, right). With side ``s`` the tile turns about its
centre by ``σ_T β`` (σ = +1 up, -1 down) and the centres scale by ``cos β``:

    x(T, k; ψ) = s · [ cos β · c_T + Rot(σ_T β) o_k ],   β = 60° - ψ,

where ``c_T`` and ``o_k`` are the centre and corner offset of the regular kagome (side 1). ψ is
the deployment angle: the gaps at every hinge are 2ψ and 240° - 2ψ, so ψ = 60° is the regular
kagome (hexagonal holes, the widest open), ψ = 0 is closed state 1 and ψ = 120° closed state 2,
both a triangular tiling with a quarter of the open area.
"""

from __future__ import annotations

import numpy as np

from ....errors import InputError
from ...model import Pattern
from ...topology import STATES, FoldRule, Topology
from ..quad.lattice import centred_standard
from ..rotating import alternating_fold_rule
from ..tessellation import Tessellation, register

OPEN_DEG = 60.0  # the regular kagome; the closed states are at OPEN_DEG -/+ 60°
H = np.sqrt(3.0) / 2.0  # height of the unit triangle


def kagome_fold_rule(top: Topology, state: int) -> FoldRule:
    """Rotating triangles: in state 1 every hinge folds the gap on the ``prev`` side of its up
    (even) tile, in state 2 the other gap; every hexagonal hole folds at three alternate corners."""
    return alternating_fold_rule(
        top, state, what="rotating-triangles kagome", fold_at="three alternate corners"
    )


def _unit_corners(rows: int, cols: int) -> np.ndarray:
    """Per-tile corners ``(T, 3, 2)`` of the regular kagome of side 1 (ψ = 60°)."""
    T = rows * cols
    r, c = np.divmod(np.arange(T), cols)
    up = (r + c) % 2 == 0
    y = np.sqrt(3.0) * r
    dy = np.where(up, H, -H)
    left = np.stack([c, y], -1)
    right = np.stack([c + 1.0, y], -1)
    apex = np.stack([c + 0.5, y + dy], -1)
    # CCW: up (left, right, apex), down (left, apex, right)
    second = np.where(up[:, None], right, apex)
    third = np.where(up[:, None], apex, right)
    return np.stack([left, second, third], 1).astype(float)


def kagome_topology(rows: int, cols: int) -> tuple[np.ndarray, np.ndarray]:
    """Tiles ``(T, 3)`` and, for each node, one flat corner index ``3 * t + k`` that uses it.

    Nodes are numbered in order of first use, scanning tiles row by row and corners CCW. Corners
    of the regular kagome coincide exactly on a half-integer grid, which keys the merge.
    """
    _check_size(rows, cols)
    corners = _unit_corners(rows, cols).reshape(-1, 2)
    # x is a multiple of 1/2 and y of √3/2: integer keys, no rounding tolerance needed
    key = np.stack([np.rint(2 * corners[:, 0]), np.rint(corners[:, 1] / H)], -1).astype(np.int64)
    _, first, inverse = np.unique(key, axis=0, return_index=True, return_inverse=True)
    order = np.argsort(first)
    rank = np.empty_like(order)
    rank[order] = np.arange(len(order))
    tiles = rank[inverse.ravel()].reshape(-1, 3)
    return tiles, first[order]


def kagome_corners(rows: int, cols: int, angle: float, tile_size: float = 1.0) -> np.ndarray:
    """Per-tile corners ``(T, 3, 2)`` of the standard kagome at deployment angle ψ (radians)."""
    _check_size(rows, cols)
    unit = _unit_corners(rows, cols)
    centre = unit.mean(axis=1)
    r, c = np.divmod(np.arange(rows * cols), cols)
    sigma = np.where((r + c) % 2 == 0, 1.0, -1.0)
    beta = np.radians(OPEN_DEG) - angle
    off = unit - centre[:, None, :]
    th = (sigma * beta)[:, None]
    cs, sn = np.cos(th), np.sin(th)
    rx = cs * off[..., 0] - sn * off[..., 1]
    ry = sn * off[..., 0] + cs * off[..., 1]
    return tile_size * (np.cos(beta) * centre[:, None, :] + np.stack([rx, ry], -1))


def standard_kagome(
    rows: int, cols: int, *, tile_size: float = 10.0, angle_deg: float = OPEN_DEG, name: str = ""
) -> Pattern:
    """The standard kagome pattern (``tile_size`` = triangle side in mm), centred on the origin.

    It carries no contracted states; compute them with
    :func:`fabkiri.mechanics.contract.with_contracted_states`.
    """
    if not np.isfinite(tile_size) or tile_size <= 0:
        raise InputError(f"tile size must be a positive length in mm, got {tile_size}")
    if not np.isfinite(angle_deg) or not 0.0 <= angle_deg <= 2 * OPEN_DEG:
        raise InputError(
            f"kagome deployment angle must lie in [0, {2 * OPEN_DEG:g}] degrees, got {angle_deg}"
        )
    tiles, rep = kagome_topology(rows, cols)
    corners = kagome_corners(rows, cols, np.radians(angle_deg), tile_size)
    return centred_standard(
        "kagome",
        tiles,
        corners.reshape(-1, 2)[rep],
        rows,
        cols,
        angle_deg,
        tile_size,
        name or f"standard kagome {rows}x{cols}",
    )


def trimmed_kagome(
    rows: int, cols: int, keep: np.ndarray, *, tile_size: float = 10.0, name: str = ""
) -> Pattern:
    """The standard R x C kagome cut down to the tiles ``keep`` (indices ``r * cols + c``), deployed
    (ψ = 60°) and centred: a lattice cut to an outline. Its lattice record names the block it was cut
    from (``trimmed_from``) and the tiles kept, not ``rows``/``cols`` (whose counts it does not have).
    The kept tiles must be one piece (:class:`~fabkiri.errors.PatternError` otherwise)."""
    if not np.isfinite(tile_size) or tile_size <= 0:
        raise InputError(f"tile size must be a positive length in mm, got {tile_size}")
    keep = np.unique(np.asarray(keep, dtype=np.int64))
    if len(keep) == 0 or keep[0] < 0 or keep[-1] >= rows * cols:
        raise InputError(f"kept tiles must be among the {rows}x{cols} lattice's, got {len(keep)}")
    tiles, rep = kagome_topology(rows, cols)
    nodes = kagome_corners(rows, cols, np.radians(OPEN_DEG), tile_size).reshape(-1, 2)[rep]
    used, inv = np.unique(tiles[keep], return_inverse=True)
    x = nodes[used]
    return Pattern(
        nodes=x - 0.5 * (x.min(0) + x.max(0)),
        tiles=inv.reshape(-1, 3),
        name=name or f"kagome {rows}x{cols} trimmed to {len(keep)} tiles",
        lattice={
            "kind": "kagome",
            "trimmed_from": [int(rows), int(cols)],
            "keep": keep.tolist(),
            "angle_deg": OPEN_DEG,
            "tile_size": float(tile_size),
        },
        kind="kagome",
    )


def kagome_counts(rows: int, cols: int) -> tuple[int, int, int]:
    """Holes, free corners and hinges bordering no hole of the standard R x C kagome, counted on its
    brick-wall tile graph: between rows r and r+1 the up tiles (r, c), r + c even, join the row
    above, and two consecutive such links bound one hexagonal hole (tiles c..c+2 of both rows).
    A row's end tiles outside every hole hang on one hinge that borders no hole."""
    starts = [np.arange(r % 2, cols - 2, 2) for r in range(rows - 1)]  # first column of each hole
    links = sum(len(range(r % 2, cols, 2)) for r in range(rows - 1))
    hinges = rows * (cols - 1) + links
    holes = sum(len(s) for s in starts)
    covered = np.zeros((rows, cols - 1), dtype=bool) if cols > 1 else np.zeros((rows, 0), bool)
    for r, s in enumerate(starts):  # a hole covers the in-row hinges c..c+1 of rows r and r+1
        for d in (0, 1):
            covered[r, s + d] = True
            covered[r + 1, s + d] = True
    link_holes = [len(s) for s in starts]  # a link borders a hole when its row gap has one
    holeless = int((~covered).sum()) + sum(
        len(range(r % 2, cols, 2)) for r, n in enumerate(link_holes) if n == 0
    )
    return holes, 3 * rows * cols - 2 * hinges, holeless


def _check_size(rows: int, cols: int) -> None:
    if int(rows) != rows or int(cols) != cols or rows < 1 or cols < 1:
        raise InputError(f"a kagome lattice needs at least 1x1 tiles, got {rows}x{cols}")
    if rows > 2 and cols < 2:  # rows r and r+1 join at (r, c) with r + c even only
        raise InputError(
            f"a kagome lattice of more than 2 rows needs 2 columns to be one piece, got "
            f"{rows}x{cols}"
        )


KAGOME = register(
    Tessellation(
        kind="kagome",
        arity=3,
        hole_arity=6,
        states=STATES,
        fold_rule=kagome_fold_rule,
        standard=standard_kagome,
        boundary_sides=("B", "R", "T", "L"),
        rigid_family=False,
        lattice_counts=kagome_counts,
        hinges_border_holes=False,
        deploy_driver="homotopy",  # no checkerboard mechanism: interpolate each tile's motion
    )
)
