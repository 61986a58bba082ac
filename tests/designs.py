"""Non-standard test designs made on the spot (shared by tests and bench/).

:func:`reconfigurable_design` perturbs the standard pattern by a smooth random
field and projects it back (sparse least squares) onto the reconfigurability
constraints of both closed states (docs/algorithm.md#edge-pairs-and-rings).
The result closes in both states but, generically, is not rigid-deployable:
the kind of design the elastic deployment path is for. It is a test fixture,
not the inverse-design solver.
"""

from __future__ import annotations

import numpy as np
from fabkiri.pattern import geometry
from fabkiri.pattern.kinds.quad.lattice import standard_pattern
from fabkiri.pattern.model import Pattern
from scipy import sparse
from scipy.optimize import least_squares


def _residuals(pattern: Pattern, x: np.ndarray, rigid: bool = False) -> np.ndarray:
    top = pattern.topology
    angles = geometry.corner_angles(x[top.tiles])
    out = []
    if rigid:  # hinge sums θA + θB = π (docs/algorithm.md#rigid-deployability)
        A, B = top.hinge_tiles.T
        cA, cB = top.hinge_corner.T
        out.append(geometry.wrap_angle(angles[A, cA] + angles[B, cB] - np.pi) * pattern.tile_size)
    h = x[top.hinge_node]
    for s in (1, 2):
        fold = top.fold(s)
        la = np.linalg.norm(x[fold.fold_ends[:, 0]] - h, axis=1)
        lb = np.linalg.norm(x[fold.fold_ends[:, 1]] - h, axis=1)
        out.append(la - lb)
        if top.n_holes:
            ring = angles[fold.rings[..., 0], fold.rings[..., 1]].sum(axis=1) - 2 * np.pi
            out.append(geometry.wrap_angle(ring) * pattern.tile_size)
    return np.concatenate(out)


def _sparsity(pattern: Pattern, rigid: bool = False) -> sparse.csr_matrix:
    top = pattern.topology
    rows, cols = [], []
    r0 = 0
    if rigid:
        both = top.tiles[top.hinge_tiles].reshape(top.n_hinges, 8)
        for k in range(8):
            rows.append(np.arange(top.n_hinges))
            cols.append(both[:, k])
        r0 = top.n_hinges
    for s in (1, 2):
        fold = top.fold(s)
        nodes = np.stack([top.hinge_node, fold.fold_ends[:, 0], fold.fold_ends[:, 1]], -1)
        for k in range(3):
            rows.append(r0 + np.arange(len(nodes)))
            cols.append(nodes[:, k])
        r0 += len(nodes)
        if top.n_holes:
            ring_tiles = fold.rings[..., 0]  # (K, 4)
            ring_nodes = top.tiles[ring_tiles].reshape(
                len(ring_tiles), -1
            )  # every corner of the 4 tiles
            for k in range(ring_nodes.shape[1]):
                rows.append(r0 + np.arange(len(ring_nodes)))
                cols.append(ring_nodes[:, k])
            r0 += len(ring_nodes)
    rows = np.concatenate(rows)
    cols = np.concatenate(cols)
    rr = np.concatenate([rows, rows])
    cc = np.concatenate([2 * cols, 2 * cols + 1])
    return sparse.csr_matrix((np.ones(len(rr)), (rr, cc)), shape=(r0, 2 * len(pattern.nodes)))


def reconfigurable_design(
    rows: int,
    cols: int,
    *,
    seed: int = 0,
    amplitude: float = 0.08,
    waves: float = 1.5,
    tile_size: float = 10.0,
    rigid: bool = False,
) -> Pattern:
    """A reconfigurable, generically non-rigid pattern near the standard one.

    ``amplitude`` is the size of the smooth perturbation in tile sizes before
    the projection, ``waves`` roughly its number of waves across the pattern.
    ``rigid`` adds the hinge sums (docs/algorithm.md#rigid-deployability): the result is then a
    reconfigurable, rigid-deployable design other than the standard one.
    """
    base = standard_pattern(rows, cols, tile_size=tile_size)
    rng = np.random.default_rng(seed)
    x0 = base.nodes
    span = np.ptp(x0, axis=0).max()
    u = x0 / span * np.pi
    field = np.zeros_like(x0)
    for _ in range(4):  # a few low-frequency modes: a smooth distortion
        k = rng.normal(size=2) * waves
        phase = rng.uniform(0, 2 * np.pi)
        field += rng.normal(size=2) * np.sin(u @ k + phase)[:, None]
    x_start = x0 + amplitude * tile_size * field / np.abs(field).max()
    sparsity = _sparsity(base, rigid)

    def fun(flat):
        return _residuals(base, flat.reshape(-1, 2), rigid)

    sol = least_squares(
        fun,
        x_start.ravel(),
        jac_sparsity=sparsity,
        method="trf",
        x_scale=tile_size,
        ftol=1e-15,
        xtol=1e-15,
        gtol=1e-15,
        max_nfev=200,
    )
    return Pattern(
        nodes=sol.x.reshape(-1, 2),
        tiles=base.tiles,
        name=f"{'rigid ' if rigid else ''}reconfigurable {rows}x{cols} seed {seed}",
        lattice=base.lattice,
    )
