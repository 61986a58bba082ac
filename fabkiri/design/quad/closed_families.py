"""Closed-state outline families: rectangular outlines, width/height ratio and the congruent closed grid."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ...pattern.geometry import wrap_angle
from ..core.stencils import Family, Stencils, corner_angle, corner_convexity, sqlen_diff


def _boundary_vertex_groups(st: Stencils, state: int):
    """Boundary pattern vertices of ``state``: grid coordinate -> list of (tile, corner)."""
    phi = st.phi[state].reshape(-1, 2)
    M, N = st.rows, st.cols
    on = (phi[:, 0] == 0) | (phi[:, 0] == N) | (phi[:, 1] == 0) | (phi[:, 1] == M)
    key = phi[:, 1] * (N + 1) + phi[:, 0]
    sel = np.flatnonzero(on)
    order = np.argsort(key[sel], kind="stable")
    sel = sel[order]
    keys, start = np.unique(key[sel], return_index=True)
    groups = np.split(sel, start[1:])
    return keys, groups


def rectangle_outline(st: Stencils, state: int, nv: int) -> Family:
    """Closed state ``state`` has a rectangular outline: boundary vertex angle sums π (π/2 at corners)."""
    keys, groups = _boundary_vertex_groups(st, state)
    M, N = st.rows, st.cols
    q = max(len(g) for g in groups)
    t = np.zeros((len(groups), q), dtype=np.int64)
    k = np.zeros((len(groups), q), dtype=np.int64)
    mask = np.zeros((len(groups), q), dtype=bool)
    for i, g in enumerate(groups):
        t[i, : len(g)] = g // 4
        k[i, : len(g)] = g % 4
        mask[i, : len(g)] = True
    gx, gy = keys % (N + 1), keys // (N + 1)
    corner = ((gx == 0) | (gx == N)) & ((gy == 0) | (gy == M))
    target = np.where(corner, np.pi / 2, np.pi)
    tiles = st.tiles
    m = len(groups)

    def fn(x):
        th, nodes, g = corner_angle(x, tiles, t.ravel(), k.ravel())
        th = th.reshape(m, q) * mask
        g = g.reshape(m, q, 3, 2) * mask[:, :, None, None]
        r = wrap_angle(th.sum(1) - target)
        return r, (nodes.reshape(m, 3 * q), g.reshape(m, 3 * q, 2))

    return Family(f"rectangle_{state}", "eq", fn, 0, nv=nv)


def _side_edges(st: Stencils, state: int, which: str):
    phi = st.phi[state]
    N = st.cols
    nxt = np.roll(phi, -1, axis=1)
    if which == "bottom":
        sel = (phi[..., 1] == 0) & (nxt[..., 1] == 0)
    else:  # right
        sel = (phi[..., 0] == N) & (nxt[..., 0] == N)
    t, k = np.nonzero(sel)
    return st.tiles[t, k], st.tiles[t, (k + 1) % 4]


def outline_ratio(st: Stencils, state: int, ratio: float, nv: int) -> Family:
    """Σ bottom edge lengths - ρ Σ right edge lengths = 0 in closed state ``state``."""
    bu, bv = _side_edges(st, state, "bottom")
    ru, rv = _side_edges(st, state, "right")

    def fn(x):
        Eb = x[bv] - x[bu]
        Er = x[rv] - x[ru]
        lb = np.linalg.norm(Eb, axis=1)
        lr = np.linalg.norm(Er, axis=1)
        r = np.array([lb.sum() - ratio * lr.sum()])
        nodes = np.concatenate([bu, bv, ru, rv])[None, :]
        ub, ur = Eb / lb[:, None], Er / lr[:, None]
        g = np.concatenate([-ub, ub, ratio * ur, -ratio * ur])[None]
        return r, (nodes, g)

    return Family(f"ratio_{state}", "eq", fn, 1, nv=nv)


@dataclass(eq=False)
class ClosedGrid:
    """Pattern vertices of one closed state appended to the node array.

    In a closed state every tile corner sits on a vertex of the (M+1)×(N+1)
    pattern grid; tile T's corner k at ``phi[T, k]``. Requiring each tile to be
    congruent there (4 edges + 1 diagonal) makes the grid a realisation of the
    closed state, so its outline can be matched to a target curve.
    """

    state: int
    offset: int  # index of grid vertex 0 in the node array
    vertex: np.ndarray  # (T, 4) node index of each tile corner's grid vertex
    boundary: np.ndarray  # node indices of the boundary grid vertices
    boundary_side: np.ndarray
    n_vertices: int

    @classmethod
    def build(cls, st: Stencils, state: int, offset: int) -> ClosedGrid:
        M, N = st.rows, st.cols
        phi = st.phi[state]
        vid = phi[..., 1] * (N + 1) + phi[..., 0]
        gx, gy = (g.ravel() for g in np.meshgrid(np.arange(N + 1), np.arange(M + 1)))
        # sides: bottom row (incl. BL corner) B, right column (incl. BR) R, top (incl. TR) T, left (incl. TL) L
        side = np.full(len(gx), -1)
        side[(gx == 0) & (gy > 0)] = 3
        side[(gy == M) & (gx > 0)] = 2
        side[(gx == N) & (gy < M)] = 1
        side[(gy == 0) & (gx < N)] = 0
        b = np.flatnonzero(side >= 0)
        return cls(
            state=state,
            offset=offset,
            vertex=offset + vid,
            boundary=offset + b,
            boundary_side=side[b],
            n_vertices=(M + 1) * (N + 1),
        )

    def congruence(self, st: Stencils, nv: int) -> Family:
        tl = st.tiles
        vx = self.vertex
        kk = np.array([0, 1, 2, 3, 0])
        ll = np.array([1, 2, 3, 0, 2])
        p = vx[:, kk].ravel()
        q = vx[:, ll].ravel()
        u = tl[:, kk].ravel()
        v = tl[:, ll].ravel()

        def fn(x):
            r, nodes, g = sqlen_diff(x, p, q, u, v)
            return r, (nodes, g)

        return Family(f"closed_grid_{self.state}", "eq", fn, 2, nv=nv)

    def orientation(self, st: Stencils, nv: int) -> Family:
        """Closed-state tiles keep their orientation (no reflected copies): cross >= 0."""
        return corner_convexity(f"closed_convexity_{self.state}", self.vertex, nv)
