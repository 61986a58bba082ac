"""Constraint families with vectorised residuals and analytic sparse Jacobians.

Every family maps the node array ``x`` (shape ``(n, 2)``, normalised units:
the initial tile edge is 1) to a residual vector ``r`` and its Jacobian
``J = ∂r/∂vec(x)`` as a CSR matrix, ``vec(x)[2*i + d] = x[i, d]``. The node
array holds the deployed nodes first and, when a closed-state outline is
controlled by a target curve, the pattern vertices of that closed state after
them (see :class:`ClosedGrid`).

Families (algorithm spec §2): edge pairs and angle rings of each closed state
(contractibility in state 1, reconfigurability in state 2), hinge sums
(rigid deployability), opposite-side equalities and notch pairs (parallelogram
holes, §2.9), boundary-tip shape matching, non-overlap at every hinge and tile
convexity (inequalities ``g >= 0``), reflection symmetry, and closed-state
outline control (rectangle angle sums, width/height ratio, congruent closed
grid matched to a curve).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy import sparse

from ..errors import InputError, SolveError
from ..pattern.geometry import cross2, dot2, signed_angle, wrap_angle
from ..pattern.lattice import DX, DY
from ..pattern.model import Pattern
from .targets import Target

TWO_PI = 2.0 * np.pi

# side (0 B, 1 R, 2 T, 3 L) of a free corner by tile parity and corner (spec §2.6)
TIP_SIDE = np.array([[3, 0, 1, 2], [0, 1, 2, 3]])


def jac(m: int, nvar_nodes: int, nodes: np.ndarray, grads: np.ndarray) -> sparse.csr_matrix:
    """CSR Jacobian from per-row node indices ``(m, k)`` and gradients ``(m, k, 2)``."""
    k = nodes.shape[1] if nodes.ndim == 2 else 0
    # every row has exactly 2k entries: build the CSR arrays directly (skips the COO constructor's checks,
    # the main cost at small sizes); nodes repeated in a row are summed in place
    cols = (2 * nodes[:, :, None] + np.arange(2)[None, None, :]).reshape(-1)
    vals = np.array(grads, dtype=float).reshape(-1)  # a copy: sum_duplicates reorders it in place
    indptr = np.arange(0, 2 * k * m + 1, max(2 * k, 1)) if k else np.zeros(m + 1, dtype=np.intp)
    J = sparse.csr_matrix((vals, cols, indptr), shape=(m, 2 * nvar_nodes))
    J.sum_duplicates()
    return J


def corner_angle(x: np.ndarray, tiles: np.ndarray, t: np.ndarray, k: np.ndarray):
    """Interior angle of CCW tiles ``t`` at corner ``k`` and its gradient.

    Returns ``θ (m,)``, nodes ``(m, 3)`` = (corner, next, prev) and gradients
    ``(m, 3, 2)``; θ turns the edge to ``next`` onto the edge to ``prev``.
    """
    n = tiles.shape[1]  # corners per tile
    v = tiles[t, k]
    a = tiles[t, (k + 1) % n]
    b = tiles[t, (k + n - 1) % n]
    A = x[a] - x[v]
    B = x[b] - x[v]
    cr = A[:, 0] * B[:, 1] - A[:, 1] * B[:, 0]
    dt = A[:, 0] * B[:, 0] + A[:, 1] * B[:, 1]
    th = np.mod(np.arctan2(cr, dt), TWO_PI)
    ga = np.stack([A[:, 1], -A[:, 0]], -1) / (A * A).sum(1, keepdims=True)
    gb = np.stack([-B[:, 1], B[:, 0]], -1) / (B * B).sum(1, keepdims=True)
    return th, np.stack([v, a, b], -1), np.stack([-(ga + gb), ga, gb], 1)


def cross_value(x: np.ndarray, h: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """g = cross(x_a - x_h, x_b - x_h) (``cross_term`` without the gradient)."""
    return cross2(x[a] - x[h], x[b] - x[h])


def cross_term(x: np.ndarray, h: np.ndarray, a: np.ndarray, b: np.ndarray):
    """g = cross(x_a - x_h, x_b - x_h) with its gradient (nodes h, a, b)."""
    A = x[a] - x[h]
    B = x[b] - x[h]
    g = A[:, 0] * B[:, 1] - A[:, 1] * B[:, 0]
    ga = np.stack([B[:, 1], -B[:, 0]], -1)
    gb = np.stack([-A[:, 1], A[:, 0]], -1)
    return g, np.stack([h, a, b], -1), np.stack([-(ga + gb), ga, gb], 1)


def sqlen_value(x: np.ndarray, p: np.ndarray, q: np.ndarray, u: np.ndarray, v: np.ndarray) -> np.ndarray:
    """½(|x_q - x_p|² - |x_v - x_u|²)."""
    E = x[q] - x[p]
    F = x[v] - x[u]
    return 0.5 * ((E * E).sum(1) - (F * F).sum(1))


def sqlen_diff(x: np.ndarray, p: np.ndarray, q: np.ndarray, u: np.ndarray, v: np.ndarray):
    """½(|x_q - x_p|² - |x_v - x_u|²) with its gradient (nodes p, q, u, v)."""
    E = x[q] - x[p]
    F = x[v] - x[u]
    r = 0.5 * ((E * E).sum(1) - (F * F).sum(1))
    return r, np.stack([p, q, u, v], -1), np.stack([-E, E, F, -F], 1)


@dataclass
class Family:
    """One constraint family: ``kind`` is 'eq', 'ineq', 'fit' or 'reg'."""

    name: str
    kind: str
    # callable x -> (r, J): J is a sparse matrix or, for the usual per-row stencil, a pair ``(nodes (m, k),
    # gradients (m, k, 2))`` that becomes CSR only when asked (residual-only calls skip it)
    fn: object
    dim: int = 2  # residual units: length**dim (2: squared-length forms, 1: lengths, 0: angles)
    meta: dict = field(default_factory=dict)
    nv: int = 0  # nodes in the node array (Jacobian columns / 2)
    # optional x -> r without the gradients (inequalities are checked far more often than they are active)
    res: object = None

    def __call__(self, x: np.ndarray):
        """Residuals ``r`` and their Jacobian (CSR)."""
        r, J = self.fn(x)
        if isinstance(J, tuple):
            J = jac(len(r), self.nv, *J)
        return r, J

    def residual(self, x: np.ndarray) -> np.ndarray:
        """Residuals only (no Jacobian assembly)."""
        return self.fn(x)[0] if self.res is None else self.res(x)


# ------------------------------------------------------------------ stencils
@dataclass(eq=False)
class Stencils:
    """Index arrays of a standard quad lattice pattern, used by every family."""

    rows: int
    cols: int
    tiles: np.ndarray
    n_nodes: int
    hinge_node: np.ndarray
    hinge_tiles: np.ndarray
    hinge_corner: np.ndarray
    folds: dict  # state -> FoldRule
    hole_nodes: np.ndarray
    gap_face: np.ndarray
    tip_nodes: np.ndarray
    tip_side: np.ndarray
    tip_tile: np.ndarray
    tip_corner: np.ndarray
    phi: dict  # state -> (T, 4, 2) integer pattern-grid coordinates of every tile corner

    @classmethod
    def from_pattern(cls, pattern: Pattern) -> Stencils:
        lat = pattern.lattice or {}
        rows, cols = int(lat.get("rows", 0)), int(lat.get("cols", 0))
        if rows * cols != pattern.n_tiles or pattern.parity != 0:
            raise SolveError("inverse design needs a standard quad lattice pattern (rows x cols, parity 0)")
        top = pattern.topology
        T = top.n_tiles
        r, c = np.divmod(np.arange(T), cols)
        par = (r + c) % 2
        k = np.arange(4)
        P = np.stack([c[:, None] + DX[None, :], r[:, None] + DY[None, :]], -1).astype(np.int64)
        kq = (k[None, :] - 1 + 2 * par[:, None]) % 4
        Q = np.stack([c[:, None] + DX[kq], r[:, None] + DY[kq]], -1).astype(np.int64)
        tiles = top.tiles
        use_t = np.full(top.n_nodes, -1)
        use_k = np.full(top.n_nodes, -1)
        use_t[tiles.ravel()] = np.repeat(np.arange(T), 4)
        use_k[tiles.ravel()] = np.tile(k, T)
        tips = top.free_nodes
        tt, tk = use_t[tips], use_k[tips]
        side = TIP_SIDE[par[tt], tk]
        return cls(rows=rows, cols=cols, tiles=tiles, n_nodes=top.n_nodes, hinge_node=top.hinge_node,
                   hinge_tiles=top.hinge_tiles, hinge_corner=top.hinge_corner,
                   folds={s: top.fold(s) for s in (1, 2)}, hole_nodes=top.hole_nodes, gap_face=top.gap_face,
                   tip_nodes=tips, tip_side=side, tip_tile=tt, tip_corner=tk, phi={1: P, 2: Q})

    @property
    def n_hinges(self) -> int:
        return len(self.hinge_node)


# ------------------------------------------------------------- families
def edge_pairs(st: Stencils, state: int, nv: int, hinges: np.ndarray | None = None) -> Family:
    fold = st.folds[state]
    sel = np.arange(st.n_hinges) if hinges is None else hinges
    h = st.hinge_node[sel]
    a, b = fold.fold_ends[sel, 0], fold.fold_ends[sel, 1]

    def fn(x):
        r, nodes, g = sqlen_diff(x, h, a, h, b)
        return r, (nodes, g)

    return Family(f"edge_pairs_{state}", "eq", fn, 2, nv=nv, res=lambda x: sqlen_value(x, h, a, h, b))


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


def angle_sums(name: str, tiles: np.ndarray, t: np.ndarray, k: np.ndarray, target: np.ndarray, nv: int,
               kind: str = "eq") -> Family:
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
    return angle_sums(f"rings_{state}", st.tiles, rg[..., 0], rg[..., 1], np.full(len(rg), TWO_PI), nv)


def hinge_sums(st: Stencils, nv: int) -> Family:
    return angle_sums("hinge_sums", st.tiles, st.hinge_tiles, st.hinge_corner, np.full(st.n_hinges, np.pi), nv)


def non_overlap(st: Stencils, nv: int) -> Family:
    """Both gap angles at every hinge in [0, π]: g1, g2 >= 0 (spec §2.7)."""
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


def corner_convexity(name: str, quads: np.ndarray, nv: int, margin: float = 0.0) -> Family:
    """cross(next - v, prev - v) - margin >= 0 at every corner of CCW ``quads`` (node indices)."""
    v = quads.ravel()
    a = np.roll(quads, -1, 1).ravel()
    b = np.roll(quads, 1, 1).ravel()

    def fn(x):
        g, nodes, gr = cross_term(x, v, a, b)
        return g - margin, (nodes, gr)

    return Family(name, "ineq", fn, 2, meta={"quads": quads}, nv=nv,
                  res=lambda x: cross_value(x, v, a, b) - margin)


def convexity(st: Stencils, nv: int, margin: float = 0.0) -> Family:
    """Deployed tiles stay convex and counter-clockwise."""
    return corner_convexity("convexity", st.tiles, nv, margin)


def shape_match(nodes: np.ndarray, sides: np.ndarray, target: Target, nv: int, name: str = "shape") -> Family:
    """Signed distance of boundary tips to their arc of the target (normalised units)."""

    project = target.projector(sides)

    def fn(x):
        _, _, d, g = project(x[nodes])
        return d, (nodes[:, None], g[:, None, :])

    return Family(name, "fit", fn, 1, meta={"nodes": nodes, "sides": sides, "target": target}, nv=nv)


# weights of the outline rows against the tip rows (weight 1): every chord midpoint, and target samples
# (OUTLINE_SAMPLES per tip, each row weighted so all samples together count as much as the tips)
CHORD_WEIGHT = 1.0
OUTLINE_SAMPLES = 4
SAMPLE_WEIGHT = 1.0


def outline_match(order: np.ndarray, target: Target, nv: int, name: str = "shape_outline",
                  samples: int = OUTLINE_SAMPLES) -> Family:
    """The whole tip polygon against the target, not just its vertices (``shape_match``): soft rows.

    * the midpoint of every chord between consecutive tips (``order``: tips in boundary order), signed
      distance to the whole target curve — a chord that cuts a corner or spans an uncovered stretch has its
      midpoint far from the curve;
    * target samples (``samples`` per tip, uniform in arc length, plus every sharp vertex of a polyline target:
      corners and cusps), signed distance to their nearest chord (positive when the target is outside the tip
      polygon) — a star point or heart cusp that no tip reaches pulls the nearest chord's tips towards it.

    Their minimum is not zero (a chord cannot follow a curve), so the exact-fit projection leaves them out
    (``meta["soft"]``).
    """
    order = np.asarray(order, dtype=np.int64)
    E = len(order)
    a_idx, b_idx = order, np.roll(order, -1)
    whole = target.projector(np.full(E, -1))
    pts = _outline_samples(target, samples * E)
    ws = SAMPLE_WEIGHT * np.sqrt(1.0 / samples)

    def fn(x):
        A, B = x[a_idx], x[b_idx]
        _, _, dm, gm = whole(0.5 * (A + B))
        e = B - A
        ee = np.maximum(dot2(e, e), 1e-300)
        j, tj, fj, dj = nearest_chords(pts, A, B)
        # the sign from the tip polygon itself (inside: negative), not from the nearest chord's normal, which
        # flips between the two chords of a tip; the gradient moves the foot (1-t) a + t b towards the sample
        side = np.where(inside_polygon(pts, A, B), -1.0, 1.0)
        off = pts - fj
        ej = e[j]
        nrm = np.stack([ej[:, 1], -ej[:, 0]], -1) / np.sqrt(ee[j])[:, None]
        unit = np.where((dj > 1e-300)[:, None], off / np.maximum(dj, 1e-300)[:, None], nrm)
        g = side[:, None] * unit
        ga = -g * (1.0 - tj)[:, None]
        gb = -g * tj[:, None]
        r = np.concatenate([CHORD_WEIGHT * dm, ws * side * dj])
        nodes = np.concatenate([np.stack([a_idx, b_idx], -1), np.stack([a_idx[j], b_idx[j]], -1)])
        grads = np.concatenate([CHORD_WEIGHT * 0.5 * np.stack([gm, gm], 1), ws * np.stack([ga, gb], 1)])
        return r, (nodes, grads)

    return Family(name, "fit", fn, 1, meta={"nodes": order, "target": target, "soft": True}, nv=nv)


def _chord_feet(pts: np.ndarray, A: np.ndarray, B: np.ndarray):
    """Foot parameter, foot point and distance of each point to each paired chord A -> B (broadcasting)."""
    e = B - A
    ee = np.maximum(dot2(e, e), 1e-300)
    t = np.clip(dot2(pts - A, e) / ee, 0.0, 1.0)
    foot = A + t[..., None] * e
    return t, foot, np.sqrt(dot2(pts - foot, pts - foot))


NEAREST_CANDIDATES = 8  # chords tried per point before the exactness bound is checked


def nearest_chords(pts: np.ndarray, A: np.ndarray, B: np.ndarray):
    """For every point its nearest chord (lowest index on a tie), foot parameter, foot point and distance.

    Exact, in O((K + E) log E) instead of the K x E distance table: the chords with the nearest midpoints are
    measured first, and a point is settled when its best distance is below the next midpoint's distance less
    the longest half chord (no other chord can come closer); the rest (rare) are measured against every chord.
    """
    from scipy.spatial import cKDTree

    E = len(A)
    k = min(NEAREST_CANDIDATES, E)
    mid = 0.5 * (A + B)
    half = 0.5 * float(np.sqrt(dot2(B - A, B - A)).max(initial=0.0))
    dk, cand = cKDTree(mid).query(pts, k=k + 1 if k < E else k)
    bound = dk[:, k] - half if k < E else np.full(len(pts), np.inf)
    cand = np.sort(cand[:, :k], axis=1)  # argmin keeps the first minimum: the lowest index, as a full table
    t, foot, dist = _chord_feet(pts[:, None, :], A[cand], B[cand])
    best = np.argmin(dist, axis=1)
    rows = np.arange(len(pts))
    j, tj, fj, dj = cand[rows, best], t[rows, best], foot[rows, best], dist[rows, best]
    open_ = np.flatnonzero(~(dj < bound))
    if len(open_):
        t, foot, dist = _chord_feet(pts[open_, None, :], A[None], B[None])
        b = np.argmin(dist, axis=1)
        r = np.arange(len(open_))
        j[open_], tj[open_], fj[open_], dj[open_] = b, t[r, b], foot[r, b], dist[r, b]
    return j, tj, fj, dj


def inside_polygon(pts: np.ndarray, A: np.ndarray, B: np.ndarray) -> np.ndarray:
    """Points inside the closed polygon with edges A -> B (even-odd crossings of a ray to +x).

    Only the (point, edge) pairs whose edge straddles the point's height are formed: with the points sorted
    by height each edge's are one contiguous run, so the work is the number of crossings, not K x E.
    """
    order = np.argsort(pts[:, 1], kind="stable")
    ys = pts[order, 1]
    ay, by = A[:, 1], B[:, 1]
    # edge straddles py iff min(ay, by) <= py < max(ay, by), as (ay > py) != (by > py)
    lo = np.searchsorted(ys, np.minimum(ay, by), side="left")
    hi = np.searchsorted(ys, np.maximum(ay, by), side="left")
    n = np.maximum(hi - lo, 0)
    edge = np.repeat(np.arange(len(A)), n)
    start = np.repeat(np.cumsum(n) - n, n)
    p = order[np.repeat(lo, n) + np.arange(int(n.sum())) - start]
    ax, bx = A[edge, 0], B[edge, 0]
    py = pts[p, 1]
    xc = ax + (py - ay[edge]) * (bx - ax) / (by[edge] - ay[edge])
    hits = np.bincount(p[pts[p, 0] < xc], minlength=len(pts))
    return hits % 2 == 1


def _outline_samples(target: Target, n: int) -> np.ndarray:
    """``n`` points uniform in the target's parameter (chord length) and its sharp polyline vertices."""
    pts = target.point(np.linspace(0.0, 1.0, n, endpoint=False))
    if target.kind == "polyline":
        P = target.points
        d0, d1 = P - np.roll(P, 1, 0), np.roll(P, -1, 0) - P
        turn = np.abs(np.arctan2(cross2(d0, d1), dot2(d0, d1)))
        pts = np.vstack([pts, P[turn > np.radians(20.0)]])
    return pts


def symmetry(st: Stencils, base: np.ndarray, axis: str, nv: int) -> Family:
    """Reflection symmetry about the x axis (y -> -y) or the y axis (x -> -x).

    Nodes are paired with their mirror images in the standard deployed state
    ``base`` (centred). Mirror pairs give two linear rows; on-axis nodes one.
    """
    S = np.array([1.0, -1.0]) if axis == "x" else np.array([-1.0, 1.0])
    mirrored = base * S
    from scipy.spatial import cKDTree

    d, partner = cKDTree(base).query(mirrored)
    scale = np.linalg.norm(base[st.tiles[0, 1]] - base[st.tiles[0, 0]])
    if (d > 1e-6 * scale).any():
        raise InputError(f"symmetry {axis}: the lattice has no mirror image of itself about the {axis} axis")
    # the mirror must map tiles to tiles and keep the fold states (primal stays primal)
    for s in (1, 2):
        fold = st.folds[s]
        ends = {(int(h), int(e)) for h, e in zip(st.hinge_node.repeat(2), fold.fold_ends.ravel())}
        mapped = {(int(partner[h]), int(partner[e])) for h, e in ends}
        if ends != mapped:
            which = "columns" if axis == "y" else "rows"
            raise InputError(
                f"symmetry {axis} swaps the primal and dual closed states for an odd number of {which}; "
                f"use an even number of {which}")
    idx = np.arange(len(base))
    pair = idx < partner
    on_axis = idx == partner
    i, j = idx[pair], partner[pair]
    comp = 1 if axis == "x" else 0  # coordinate that must vanish on the axis
    rows_p = len(i)
    m = 2 * rows_p + int(on_axis.sum())
    r_i = np.concatenate([np.arange(rows_p) * 2, np.arange(rows_p) * 2 + 1,
                          np.arange(rows_p) * 2, np.arange(rows_p) * 2 + 1, 2 * rows_p + np.arange(on_axis.sum())])
    c_i = np.concatenate([2 * j, 2 * j + 1, 2 * i, 2 * i + 1, 2 * idx[on_axis] + comp])
    vals = np.concatenate([np.ones(rows_p), np.ones(rows_p), -S[0] * np.ones(rows_p), -S[1] * np.ones(rows_p),
                           np.ones(on_axis.sum())])
    J = sparse.csr_matrix((vals, (r_i, c_i)), shape=(m, 2 * nv))

    def fn(x):
        return J @ x.reshape(-1), J

    return Family(f"symmetry_{axis}", "eq", fn, 1, nv=nv)


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
        gx, gy = np.meshgrid(np.arange(N + 1), np.arange(M + 1))
        gx, gy = gx.ravel(), gy.ravel()
        # sides: bottom row (incl. BL corner) B, right column (incl. BR) R, top (incl. TR) T, left (incl. TL) L
        side = np.full(len(gx), -1)
        side[(gx == 0) & (gy > 0)] = 3
        side[(gy == M) & (gx > 0)] = 2
        side[(gx == N) & (gy < M)] = 1
        side[(gy == 0) & (gx < N)] = 0
        b = np.flatnonzero(side >= 0)
        return cls(state=state, offset=offset, vertex=offset + vid, boundary=offset + b,
                   boundary_side=side[b], n_vertices=(M + 1) * (N + 1))

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


def regularizer_pairs(st: Stencils) -> np.ndarray:
    """Tile pairs (r,c)-(r,c+2) and (r,c)-(r+2,c): same face in adjacent unit cells (spec §3)."""
    M, N = st.rows, st.cols
    idx = np.arange(M * N).reshape(M, N)
    h = np.stack([idx[:, :-2].ravel(), idx[:, 2:].ravel()], -1)
    v = np.stack([idx[:-2, :].ravel(), idx[2:, :].ravel()], -1)
    return np.concatenate([h, v]).astype(np.int64)
