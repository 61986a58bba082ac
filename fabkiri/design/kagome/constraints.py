"""Inverse-design constraints of kagome (rotating-triangles) kirigami and the dimension of its families.

Derivation (docs/kagome.md): a hexagonal hole with corners ``v0..v5`` folds in a closed state at
three alternate corners, say ``v0, v2, v4``. Folding at ``v0`` lays the hole edge ``v5 v0`` on the
edge ``v0 v1``, so their far ends meet only if the two edges are equal; the three other corners
``v1, v3, v5`` then meet at one point, where the six tile angles they carry must fill a full turn.
Per hole and state: three **edge pairs** (one per fold corner) and one **ring** (angle sum 2π). A
boundary hinge whose folded gap is the exterior adds its **notch pair**, so every hinge carries one
edge pair per state, exactly as for quads. The other closed state folds at ``v1, v3, v5``: its
pairs are the shifted ones, and with both states the six edges of every hole are equal.

Families are the quad families' residual forms (squared-length differences, wrapped angle sums),
in normalised units (the deployed tile edge is 1), built from the topology's fold rules rather than
from the quad lattice stencils, with analytic sparse Jacobians.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import sparse

from ...pattern.geometry import cross2, dot2
from ...pattern.model import Pattern
from ..core.stencils import TWO_PI, Family, sqlen_diff, sqlen_value
from ..quad.constraints import angle_sums


def edge_pair_family(pattern: Pattern, state: int) -> Family:
    """½(ℓ(h, a)² - ℓ(h, b)²) = 0 at every hinge ``h``: its two edges bounding the folded gap."""
    top = pattern.topology
    fold = top.fold(state)
    h = top.hinge_node
    a, b = fold.fold_ends[:, 0], fold.fold_ends[:, 1]

    def fn(x):
        r, nodes, g = sqlen_diff(x, h, a, h, b)
        return r, (nodes, g)

    return Family(
        f"edge_pairs_{state}", "eq", fn, 2, nv=top.n_nodes, res=lambda x: sqlen_value(x, h, a, h, b)
    )


def ring_family(pattern: Pattern, state: int) -> Family:
    """Σ of the six tile angles at a hole's three merge corners - 2π = 0, one row per hole."""
    top = pattern.topology
    rg = top.fold(state).rings
    return angle_sums(
        f"rings_{state}", top.tiles, rg[..., 0], rg[..., 1], np.full(len(rg), TWO_PI), top.n_nodes
    )


def families(pattern: Pattern, states: tuple[int, ...] = (1, 2)) -> list[Family]:
    """Contractibility (state 1) and reconfigurability (state 2): edge pairs and rings."""
    out = []
    for s in states:
        out += [edge_pair_family(pattern, s), ring_family(pattern, s)]
    return out


def alternating_sums(pattern: Pattern) -> Family:
    """Σ of a hole's edge vectors on up tiles = 0 (2 rows per hole): the hole's loop stays closed
    when up tiles turn by +ω and down tiles by -ω (``Σ_c Rot(σ_c ω) e_c = 0`` for every ω)."""
    top = pattern.topology
    K = top.n_holes
    w = (top.tile_color[top.hole_tiles] == 0).astype(float)  # (K, 6): edge c -> c+1 on an up tile
    n0, n1 = top.hole_nodes, np.roll(top.hole_nodes, -1, axis=1)
    # linear: row 2k + d takes +w at (n1, d) and -w at (n0, d)
    nodes = np.concatenate([n1, n0], 1)  # (K, 12)
    sign = np.concatenate([w, -w], 1)
    rows = 2 * np.arange(K)[:, None, None] + np.arange(2)[None, :, None]  # (K, 2, 1)
    R = np.broadcast_to(rows, (K, 2, 12)).ravel()
    C = (2 * nodes[:, None, :] + np.arange(2)[None, :, None]).ravel()
    V = np.broadcast_to(sign[:, None, :], (K, 2, 12)).ravel()
    J = sparse.csr_matrix((V, (R, C)), shape=(2 * K, 2 * top.n_nodes))

    def fn(x):
        return ((x[n1] - x[n0]) * w[..., None]).sum(1).ravel(), J

    return Family("alternating_sums", "eq", fn, 1, nv=top.n_nodes)


def fold_gap_angles(pattern: Pattern, state: int, x: np.ndarray):
    """Angle of every hinge's folded gap in ``state`` (rad) and its gradient (nodes h, a, b)."""
    top = pattern.topology
    fold = top.fold(state)
    h = top.hinge_node
    # gap 0 turns from A's edge onto B's (ends (prev_A, next_B)), gap 1 from B's onto A's
    first = np.where(fold.fold_gap == 0, fold.fold_ends[:, 0], fold.fold_ends[:, 1])
    second = np.where(fold.fold_gap == 0, fold.fold_ends[:, 1], fold.fold_ends[:, 0])
    A = x[first] - x[h]
    B = x[second] - x[h]
    th = np.mod(np.arctan2(cross2(A, B), dot2(A, B)), TWO_PI)
    ga = np.stack([A[:, 1], -A[:, 0]], -1) / (A * A).sum(1, keepdims=True)
    gb = np.stack([-B[:, 1], B[:, 0]], -1) / (B * B).sum(1, keepdims=True)
    return th, np.stack([h, first, second], -1), np.stack([-(ga + gb), ga, gb], 1)


def equal_gaps(pattern: Pattern, state: int) -> Family:
    """Every folded gap of ``state`` equal to hinge 0's (H - 1 rows): under the counter-rotation
    all gaps shrink at the same rate, so they must close together."""

    def fn(x):
        th, nodes, g = fold_gap_angles(pattern, state, x)
        r = th[1:] - th[0]
        return r, (
            np.concatenate([nodes[1:], np.repeat(nodes[:1], len(r), 0)], 1),
            np.concatenate([g[1:], -np.repeat(g[:1], len(r), 0)], 1),
        )

    return Family(f"equal_gaps_{state}", "eq", fn, 0, nv=pattern.topology.n_nodes)


def rigid_families(pattern: Pattern) -> list[Family]:
    """Reconfigurability plus the counter-rotating rigid mechanism (docs/kagome.md)."""
    return families(pattern) + [
        alternating_sums(pattern),
        equal_gaps(pattern, 1),
        equal_gaps(pattern, 2),
    ]


def stacked(fams: list[Family], x: np.ndarray) -> tuple[np.ndarray, sparse.csr_matrix]:
    """All residuals and the stacked Jacobian at ``x`` (n, 2)."""
    parts = [f(x) for f in fams]
    return np.concatenate([r for r, _ in parts]), sparse.vstack([J for _, J in parts]).tocsr()


def numerical_rank(J: sparse.spmatrix, rel: float = 1e-9) -> int:
    """Rank of ``J``: singular values above ``rel`` times the largest (dense SVD)."""
    sv = np.linalg.svd(J.toarray(), compute_uv=False)
    return int((sv > rel * sv.max(initial=0.0)).sum()) if len(sv) else 0


@dataclass(frozen=True)
class FamilyCount:
    """Counts of one constraint family at one pattern (normalised units)."""

    unknowns: int  # 2 × nodes
    equations: int
    rank: int
    residual: float  # largest |r| at the point: the point lies on the family

    @property
    def dimension(self) -> int:
        """Local dimension modulo the three rigid motions (unknowns - rank - 3)."""
        return self.unknowns - self.rank - 3


def count(pattern: Pattern, states: tuple[int, ...], x: np.ndarray | None = None) -> FamilyCount:
    """Equations, Jacobian rank and local dimension of the family of ``states`` at ``x``."""
    x = pattern.nodes / pattern.tile_size if x is None else x
    r, J = stacked(families(pattern, states), x)
    return FamilyCount(2 * len(x), len(r), numerical_rank(J), float(np.abs(r).max(initial=0.0)))


def nearby_solution(
    pattern: Pattern,
    states: tuple[int, ...],
    seed: int = 0,
    step: float = 0.05,
    tol: float = 1e-13,
    max_iter: int = 50,
    fams: list[Family] | None = None,
) -> np.ndarray:
    """A generic (non-symmetric) point of the family near the standard pattern: the nodes moved
    at random by ``step`` tile edges, then projected back by minimum-norm Gauss-Newton steps.
    ``fams`` replaces the families of ``states`` (e.g. :func:`rigid_families`)."""
    fams = families(pattern, states) if fams is None else fams
    rng = np.random.default_rng(seed)
    x = pattern.nodes / pattern.tile_size
    x = x + step * rng.standard_normal(x.shape)
    for _ in range(max_iter):
        r, J = stacked(fams, x)
        if np.abs(r).max(initial=0.0) <= tol:
            return x
        dx = np.linalg.lstsq(J.toarray(), -r, rcond=1e-10)[0]
        x = x + dx.reshape(x.shape)
    r, _ = stacked(fams, x)
    raise RuntimeError(f"projection did not converge: max |r| = {np.abs(r).max():.3g}")


def linkage_mobility(pattern: Pattern, x: np.ndarray | None = None) -> int:
    """Degrees of freedom of the tiles as rigid bodies pinned at their hinges, rigid motions
    removed: ``3T - rank(hinge constraints) - 3``, from the Jacobian of the hinge equations in the
    tile poses (angle, translation) at the pattern's deployed state."""
    top = pattern.topology
    x = pattern.nodes if x is None else x
    T, H = top.n_tiles, top.n_hinges
    centres = x[top.tiles].mean(axis=1)
    A, B = top.hinge_tiles.T
    p = x[top.hinge_node]
    rows, cols, vals = [], [], []
    for side, (tile, sign) in enumerate(((A, 1.0), (B, -1.0))):
        d = p - centres[tile]  # hinge point relative to the tile's centre
        for dim in range(2):  # d/dθ of Rot(θ) d is (-d_y, d_x); translations enter directly
            r = 2 * np.arange(H) + dim
            rows += [r, r]
            cols += [3 * tile, 3 * tile + 1 + dim]
            vals += [sign * (-d[:, 1] if dim == 0 else d[:, 0]), np.full(H, sign)]
        del side
    J = sparse.csr_matrix(
        (np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))), shape=(2 * H, 3 * T)
    )
    return 3 * T - numerical_rank(J) - 3
