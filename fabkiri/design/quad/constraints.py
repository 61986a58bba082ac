"""Constraint families with vectorised residuals and analytic sparse Jacobians.

Every family maps the node array ``x`` (shape ``(n, 2)``, normalised units:
the initial tile edge is 1) to a residual vector ``r`` and its Jacobian
``J = ∂r/∂vec(x)`` as a CSR matrix, ``vec(x)[2*i + d] = x[i, d]``. The node
array holds the deployed nodes first and, when a closed-state outline is
controlled by a target curve, the pattern vertices of that closed state after
them (see :class:`ClosedGrid`).

Families (docs/algorithm.md#constraints): edge pairs and angle rings of each closed state
(contractibility in state 1, reconfigurability in state 2), hinge sums
(rigid deployability), opposite-side equalities and notch pairs (parallelogram
holes, §2.9), boundary-tip shape matching, non-overlap at every hinge and tile
convexity (inequalities ``g >= 0``), reflection symmetry, and closed-state
outline control (rectangle angle sums, width/height ratio, congruent closed
grid matched to a curve).
"""

from __future__ import annotations

import numpy as np
from scipy import sparse

from ...errors import InputError
from ...pattern.geometry import signed_angle, wrap_angle
from ..core.stencils import (
    TIP_SIDE,
    TWO_PI,
    Family,
    Stencils,
    corner_angle,
    corner_convexity,
    cross_term,
    cross_value,
    jac,
    regularizer_pairs,
    sqlen_diff,
    sqlen_value,
)
from ..targets.families import inside_polygon, nearest_chords, outline_match, shape_match
from .closed_families import ClosedGrid, outline_ratio, rectangle_outline

# the solver's one import point: the families defined here and those of the modules split from this one
__all__ = [
    "TIP_SIDE",
    "TWO_PI",
    "ClosedGrid",
    "Family",
    "Stencils",
    "angle_sums",
    "convexity",
    "corner_angle",
    "corner_convexity",
    "cross_term",
    "cross_value",
    "edge_pairs",
    "hinge_sums",
    "hole_opposite_sides",
    "inside_polygon",
    "jac",
    "least_edges",
    "nearest_chords",
    "non_overlap",
    "notch_pairs",
    "outline_match",
    "outline_ratio",
    "rectangle_outline",
    "regularizer_pairs",
    "rings",
    "shape_match",
    "sqlen_diff",
    "sqlen_value",
    "symmetry",
]


# ------------------------------------------------------------- families
def edge_pairs(st: Stencils, state: int, nv: int, hinges: np.ndarray | None = None) -> Family:
    fold = st.folds[state]
    sel = np.arange(st.n_hinges) if hinges is None else hinges
    h = st.hinge_node[sel]
    a, b = fold.fold_ends[sel, 0], fold.fold_ends[sel, 1]

    def fn(x):
        r, nodes, g = sqlen_diff(x, h, a, h, b)
        return r, (nodes, g)

    return Family(
        f"edge_pairs_{state}", "eq", fn, 2, nv=nv, res=lambda x: sqlen_value(x, h, a, h, b)
    )


def notch_pairs(st: Stencils, state: int, nv: int) -> Family:
    """Edge pairs at hinges whose folded gap in ``state`` is the exterior (parallelogram mode)."""
    fold = st.folds[state]
    ext = st.gap_face[np.arange(st.n_hinges), fold.fold_gap] < 0
    fam = edge_pairs(st, state, nv, np.flatnonzero(ext))
    fam.name = f"notch_pairs_{state}"
    return fam


def hole_opposite_sides(st: Stencils, nv: int) -> Family:
    """Parallelogram holes: opposite sides equal (2 rows per hole)."""
    hn = st.hole_nodes
    p = np.concatenate([hn[:, 0], hn[:, 1]])
    q = np.concatenate([hn[:, 1], hn[:, 2]])
    u = np.concatenate([hn[:, 2], hn[:, 3]])
    v = np.concatenate([hn[:, 3], hn[:, 0]])

    def fn(x):
        r, nodes, g = sqlen_diff(x, p, q, u, v)
        return r, (nodes, g)

    return Family("hole_opposite_sides", "eq", fn, 2, nv=nv)


def angle_sums(
    name: str,
    tiles: np.ndarray,
    t: np.ndarray,
    k: np.ndarray,
    target: np.ndarray,
    nv: int,
    kind: str = "eq",
) -> Family:
    """Σ_j θ_{t[i,j]}(k[i,j]) - target[i] (wrapped), ``t``/``k`` of shape ``(m, q)``."""
    m, q = t.shape
    tt, kk = t.ravel(), k.ravel()
    n = tiles.shape[1]
    v, a, b = tiles[tt, kk], tiles[tt, (kk + 1) % n], tiles[tt, (kk + n - 1) % n]

    def fn(x):
        th, nodes, g = corner_angle(x, tiles, tt, kk)
        r = wrap_angle(th.reshape(m, q).sum(1) - target)
        return r, (nodes.reshape(m, 3 * q), g.reshape(m, 3 * q, 2))

    def res(x):  # corner_angle's θ without its gradients
        th = np.mod(signed_angle(x[a] - x[v], x[b] - x[v]), TWO_PI)
        return wrap_angle(th.reshape(m, q).sum(1) - target)

    return Family(name, kind, fn, 0, nv=nv, res=res)


def rings(st: Stencils, state: int, nv: int) -> Family:
    rg = st.folds[state].rings
    return angle_sums(
        f"rings_{state}", st.tiles, rg[..., 0], rg[..., 1], np.full(len(rg), TWO_PI), nv
    )


def hinge_sums(st: Stencils, nv: int) -> Family:
    return angle_sums(
        "hinge_sums", st.tiles, st.hinge_tiles, st.hinge_corner, np.full(st.n_hinges, np.pi), nv
    )


def non_overlap(st: Stencils, nv: int) -> Family:
    """Both gap angles at every hinge in [0, π]: g1, g2 >= 0 (docs/algorithm.md#non-overlap)."""
    tl = st.tiles
    A, B = st.hinge_tiles.T
    cA, cB = st.hinge_corner.T
    h = st.hinge_node
    prevA, nextA = tl[A, (cA + 3) % 4], tl[A, (cA + 1) % 4]
    prevB, nextB = tl[B, (cB + 3) % 4], tl[B, (cB + 1) % 4]
    hh = np.concatenate([h, h])
    aa = np.concatenate([prevA, prevB])
    bb = np.concatenate([nextB, nextA])

    def fn(x):
        g, nodes, gr = cross_term(x, hh, aa, bb)
        return g, (nodes, gr)

    return Family("non_overlap", "ineq", fn, 2, nv=nv, res=lambda x: cross_value(x, hh, aa, bb))


def convexity(st: Stencils, nv: int, margin: float = 0.0) -> Family:
    """Deployed tiles stay convex and counter-clockwise."""
    return corner_convexity("convexity", st.tiles, nv, margin)


def least_edges(st: Stencils, nv: int, floor: float, margin: float = 0.5) -> Family:
    """No tile edge shorter than ``floor`` (node units): ``|e_k|² / floor² - 1 >= 0``, one row per tile edge
    ``e_k`` (corner ``k`` to ``k + 1``).

    Convexity allows a needle (two corners nearly coinciding, ``cross >= 0`` still) and no file reader takes
    an edge of under a micrometre. The rows are scaled so that a collapsed edge violates its row by 1, more
    than any other row's violation in tile units, so the step limit bars the collapse; with ``margin`` they
    act only on an edge below ``√(1 + margin) floor``."""
    quads = st.tiles
    p, q = quads.ravel(), np.roll(quads, -1, 1).ravel()
    inv = 1.0 / (floor * floor)

    def values(x):
        E = x[q] - x[p]
        return E, (E * E).sum(1) * inv - 1.0

    def fn(x):
        E, g = values(x)
        return g, (np.stack([p, q], -1), np.stack([-2.0 * inv * E, 2.0 * inv * E], 1))

    return Family(
        "least_edges",
        "ineq",
        fn,
        0,
        meta={"margin": margin, "floor": floor},
        nv=nv,
        res=lambda x: values(x)[1],
    )


def symmetry(st: Stencils, base: np.ndarray, axis: str, nv: int) -> Family:
    """Reflection symmetry about the x axis (y -> -y) or the y axis (x -> -x).

    Nodes are paired with their mirror images in the standard deployed state
    ``base`` (centred). Mirror pairs give two linear rows; on-axis nodes one.
    """
    S = np.array([1.0, -1.0]) if axis == "x" else np.array([-1.0, 1.0])
    mirrored = base * S
    from ...kdtree import KDTree

    d, partner = KDTree(base).query(mirrored)
    scale = np.linalg.norm(base[st.tiles[0, 1]] - base[st.tiles[0, 0]])
    if (d > 1e-6 * scale).any():
        raise InputError(
            f"symmetry {axis}: the lattice has no mirror image of itself about the {axis} axis"
        )
    # the mirror must map tiles to tiles and keep the fold states (primal stays primal)
    for s in (1, 2):
        fold = st.folds[s]
        ends = {(int(h), int(e)) for h, e in zip(st.hinge_node.repeat(2), fold.fold_ends.ravel())}
        mapped = {(int(partner[h]), int(partner[e])) for h, e in ends}
        if ends != mapped:
            which = "columns" if axis == "y" else "rows"
            raise InputError(
                f"symmetry {axis} swaps the primal and dual closed states for an odd number of {which}; "
                f"use an even number of {which}"
            )
    idx = np.arange(len(base))
    pair = idx < partner
    on_axis = idx == partner
    i, j = idx[pair], partner[pair]
    comp = 1 if axis == "x" else 0  # coordinate that must vanish on the axis
    rows_p = len(i)
    m = 2 * rows_p + int(on_axis.sum())
    r_i = np.concatenate(
        [
            np.arange(rows_p) * 2,
            np.arange(rows_p) * 2 + 1,
            np.arange(rows_p) * 2,
            np.arange(rows_p) * 2 + 1,
            2 * rows_p + np.arange(on_axis.sum()),
        ]
    )
    c_i = np.concatenate([2 * j, 2 * j + 1, 2 * i, 2 * i + 1, 2 * idx[on_axis] + comp])
    vals = np.concatenate(
        [
            np.ones(rows_p),
            np.ones(rows_p),
            -S[0] * np.ones(rows_p),
            -S[1] * np.ones(rows_p),
            np.ones(on_axis.sum()),
        ]
    )
    J = sparse.csr_matrix((vals, (r_i, c_i)), shape=(m, 2 * nv))

    def fn(x):
        return J @ x.reshape(-1), J

    return Family(f"symmetry_{axis}", "eq", fn, 1, nv=nv)


def exact_fits(fits: list[Family]) -> list[Family]:
    """The fit rows an exact fit drives to zero (not the soft outline rows, whose minimum is not zero)."""
    return [f for f in fits if not f.meta.get("soft")]
