"""Monte-Carlo tolerance analysis of the fabricated tiles (``fabkiri tolerance``).

Model (stated, not measured):

* **cut error**: every edge of every tile lies off its design line along its
  normal by an independent N(0, ``kerf_sd``) (kerf and beam-position scatter);
  the tile's corners are where its four displaced edge lines meet (to first
  order, exact for parallel shifts of straight edges);
* **hinge error**: where a hinge joins tile A and tile B, the pivot sits off
  each tile's (cut) corner by an independent 2D N(0, ``hinge_sd``) (tape or
  strip placement);
* the same fabricated tiles are assembled in closed state 1, the deployed state
  and closed state 2: each keeps its design rotation in that state and the
  translations are the least-squares fit of all pivot pairs (the tile graph's
  Laplacian, factorised once, every sample solved at once).

Measured per sample and state: the **closure gap** (largest distance between
the two pivot copies of a hinge after the fit: what the tape must stretch or
the loop fails to close by); in the closed states, along every seam (two tile
edges that lie together there) the **overlap** (area by which the tiles
overlap, largest and total) and the **seam gap** (widest opening), both to first
order in the errors; deployed, the **outline error** (largest distance of the
boundary points to the
design's outline, after the best rigid alignment; the design's own fit to its
target, when stored, adds to it at most).
The **most sensitive tiles** are those whose own error size correlates most
with the sample's worst closure gap.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import shapely
from scipy import sparse
from scipy.sparse.linalg import splu

from ..errors import InputError
from ..pattern import geometry
from ..pattern.model import Pattern
from .deploy import closed_states

STATES = ("closed state 1", "deployed", "closed state 2")
PERCENTILES = (50, 90, 95, 99)


@dataclass(frozen=True)
class ToleranceResult:
    n: int
    seed: int
    kerf_sd_mm: float
    hinge_sd_mm: float
    scale: float
    tile_size_mm: float
    gap: dict[str, np.ndarray]  # state -> (N,) largest hinge gap, mm
    overlap_max: dict[str, np.ndarray]  # closed state -> (N,) largest pair overlap, mm²
    overlap_total: dict[str, np.ndarray]  # closed state -> (N,) summed overlap, mm²
    seam_gap: dict[
        str, np.ndarray
    ]  # closed state -> (N,) widest opening between edges meant to lie flush, mm
    outline: np.ndarray  # (N,) deployed outline error, mm
    outline_reference: str  # what the outline error is measured from
    outline_fit_mm: (
        float | None
    )  # the design's own distance to its target (design.report.fit), if stored
    sensitivity: np.ndarray  # (T,) correlation of each tile's error size with the worst gap
    tile_gap_mean: np.ndarray  # (T,) mean over samples of the largest gap at the tile's hinges
    time_s: float = 0.0

    def _dist(self, a: np.ndarray) -> dict:
        p = np.percentile(a, PERCENTILES)
        return {
            "mean": float(a.mean()),
            "sd": float(a.std()),
            "max": float(a.max()),
            **{f"p{q}": float(v) for q, v in zip(PERCENTILES, p)},
        }

    def most_sensitive(self, k: int = 5) -> list[dict]:
        order = np.argsort(-self.sensitivity, kind="stable")[:k]
        return [
            {
                "tile": int(t),
                "correlation": round(float(self.sensitivity[t]), 4),
                "mean_gap_at_tile_mm": float(self.tile_gap_mean[t]),
            }
            for t in order
        ]

    def to_dict(self) -> dict:
        return {
            "format": "fabkiri.tolerance",
            "version": 1,
            "units": "mm",
            "model": {
                "kerf_sd_mm": self.kerf_sd_mm,
                "hinge_sd_mm": self.hinge_sd_mm,
                "samples": self.n,
                "seed": self.seed,
                "scale": self.scale,
                "tile_size_mm": self.tile_size_mm,
                "cut": "each tile edge offset along its normal by N(0, kerf_sd)",
                "hinge": "each pivot off its tile corner by a 2D N(0, hinge_sd)",
                "assembly": "design rotations per state, least-squares translations over all hinges",
            },
            "closure_gap_mm": {s: self._dist(v) for s, v in self.gap.items()},
            "seam_gap_mm": {s: self._dist(v) for s, v in self.seam_gap.items()},
            "overlap_max_mm2": {s: self._dist(v) for s, v in self.overlap_max.items()},
            "overlap_total_mm2": {s: self._dist(v) for s, v in self.overlap_total.items()},
            "deployed_outline_mm": {
                **self._dist(self.outline),
                "reference": self.outline_reference,
                "design_fit_to_target_mm": self.outline_fit_mm,
            },
            "most_sensitive_tiles": self.most_sensitive(),
            "time_s": round(self.time_s, 3),
        }


def corner_shift(corners: np.ndarray, offsets: np.ndarray) -> np.ndarray:
    """Corner displacements ``(..., 4, 2)`` when edge k (corner k -> k+1) moves by ``offsets[..., k]``
    along its outward normal: corner k solves n_{k-1}·d = o_{k-1}, n_k·d = o_k."""
    e = np.roll(corners, -1, axis=-2) - corners
    n = np.stack([e[..., 1], -e[..., 0]], -1)  # outward for CCW tiles
    n = n / np.linalg.norm(n, axis=-1, keepdims=True)
    n_prev = np.roll(n, 1, axis=-2)
    o_prev = np.roll(offsets, 1, axis=-1)
    det = n_prev[..., 0] * n[..., 1] - n_prev[..., 1] * n[..., 0]
    det = np.where(np.abs(det) > 1e-12, det, 1e-12)  # a straight corner: no unique meet point
    dx = (o_prev * n[..., 1] - offsets * n_prev[..., 1]) / det
    dy = (n_prev[..., 0] * offsets - n[..., 0] * o_prev) / det
    return np.stack([dx, dy], -1)


class _Assembly:
    """Least-squares tile translations for many samples: L τ = Dᵀ m, tile 0 held."""

    def __init__(self, A: np.ndarray, B: np.ndarray, n_tiles: int):
        H = len(A)
        D = sparse.csr_matrix(
            (np.r_[np.ones(H), -np.ones(H)], (np.r_[np.arange(H), np.arange(H)], np.r_[A, B])),
            shape=(H, n_tiles),
        )
        self.D = D
        self.lu = splu((D.T @ D).tocsc()[1:, 1:])

    def residual(self, mismatch: np.ndarray) -> np.ndarray:
        """``mismatch`` (N, H, 2) = pivot_B - pivot_A before moving; returns the gaps (N, H) after."""
        N, H, _ = mismatch.shape
        rhs = (self.D.T @ mismatch.transpose(1, 0, 2).reshape(H, -1))[1:]
        tau = np.zeros((self.D.shape[1], N * 2))
        tau[1:] = self.lu.solve(np.ascontiguousarray(rhs))
        move = (self.D @ tau).reshape(H, N, 2).transpose(1, 0, 2)  # τ_A - τ_B per hinge
        r = mismatch - move
        return np.hypot(r[..., 0], r[..., 1])


def seam_edges(corners: np.ndarray, eps: float) -> np.ndarray:
    """``(S, 4)`` rows (tile i, edge k, tile j, edge l): edges of two tiles that lie together (antiparallel,
    within ``eps`` of each other, sharing more than ``eps`` of length) in this closed state."""
    polys = shapely.polygons(corners)
    i, j = shapely.STRtree(polys).query(polys, predicate="dwithin", distance=eps)
    keep = i < j
    i, j = np.repeat(i[keep], 16), np.repeat(j[keep], 16)
    k, l = np.tile(np.repeat(np.arange(4), 4), keep.sum()), np.tile(np.arange(4), 4 * keep.sum())
    p0, p1 = corners[i, k], corners[i, (k + 1) % 4]
    q0, q1 = corners[j, l], corners[j, (l + 1) % 4]
    u = p1 - p0
    L = np.linalg.norm(u, axis=1)
    u = u / L[:, None]
    nrm = np.stack([-u[:, 1], u[:, 0]], 1)
    off = np.maximum(np.abs(((q0 - p0) * nrm).sum(1)), np.abs(((q1 - p0) * nrm).sum(1)))
    s0, s1 = ((q0 - p0) * u).sum(1), ((q1 - p0) * u).sum(1)
    shared = np.minimum(L, np.maximum(s0, s1)) - np.maximum(0.0, np.minimum(s0, s1))
    ok = (off < eps) & (shared > eps) & (s1 < s0)
    return np.stack([i[ok], k[ok], j[ok], l[ok]], 1)


def _clipped_integrals(
    a: np.ndarray, b: np.ndarray, w: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """∫ max(0, f) and ∫ max(0, -f) over a width ``w`` where f runs linearly from ``a`` to ``b``."""
    pos = np.where((a >= 0) & (b >= 0), 0.5 * (a + b) * w, 0.0)
    neg = np.where((a <= 0) & (b <= 0), -0.5 * (a + b) * w, 0.0)
    mixed = (a * b) < 0
    span = np.where(mixed, np.abs(a) + np.abs(b), 1.0)
    pos = np.where(mixed, 0.5 * w * np.maximum(a, b) ** 2 / span, pos)
    neg = np.where(mixed, 0.5 * w * np.minimum(a, b) ** 2 / span, neg)
    return pos, neg


def seam_misfit(
    corners: np.ndarray, seams: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Per sample and seam (tile edges that should lie flush): overlap area (mm², tile j reaching into
    tile i), opening area (mm²) and largest opening (mm). First order in the errors: edge j's
    endpoints are measured from edge i's line, over the part of edge i they span."""
    i, k, j, l = seams.T
    p0, p1 = corners[:, i, k], corners[:, i, (k + 1) % 4]
    q0, q1 = corners[:, j, l], corners[:, j, (l + 1) % 4]
    u = p1 - p0
    L = np.linalg.norm(u, axis=-1)
    u = u / L[..., None]
    inward = np.stack([-u[..., 1], u[..., 0]], -1)
    s0, s1 = ((q0 - p0) * u).sum(-1), ((q1 - p0) * u).sum(-1)  # s1 < s0 (antiparallel)
    d0, d1 = ((q0 - p0) * inward).sum(-1), ((q1 - p0) * inward).sum(-1)
    lo, hi = np.maximum(0.0, s1), np.minimum(L, s0)
    w = np.maximum(hi - lo, 0.0)
    slope = (d0 - d1) / np.where(s0 - s1 > 0, s0 - s1, 1.0)
    a, b = d1 + slope * (lo - s1), d1 + slope * (hi - s1)
    over, open_ = _clipped_integrals(a, b, w)
    return over, open_, np.maximum(0.0, -np.minimum(a, b))


def _outline_reference(pattern: Pattern, scale: float):
    """The boundary nodes and the design's outline ring (exterior of the deployed tiles' union), in mm."""
    top = pattern.topology
    boundary = np.unique(np.r_[top.free_nodes, top.hinge_node[(top.gap_face < 0).any(axis=1)]])
    eps = (
        1e-9 * pattern.tile_size * scale
    )  # joins tiles that meet at points; moves the outline by ~eps
    union = shapely.union_all(
        shapely.buffer(shapely.polygons(pattern.corners() * scale), eps, join_style="mitre")
    )
    if union.geom_type != "Polygon":  # tiles not joined into one piece: no single outline
        return boundary, None
    return boundary, shapely.LinearRing(union.exterior.coords)


def tolerance_analysis(
    pattern: Pattern,
    *,
    kerf_sd: float = 0.02,
    hinge_sd: float = 0.05,
    n: int = 1000,
    seed: int = 0,
    scale: float = 1.0,
) -> ToleranceResult:
    """Run the Monte-Carlo (see the module doc); lengths in mm at ``scale`` × the pattern."""
    import time

    _check_inputs(kerf_sd, hinge_sd, n, scale)
    t0 = time.perf_counter()
    top = pattern.topology
    T = top.n_tiles
    A, B = top.hinge_tiles.T
    deployed = pattern.corners() * scale
    closed = closed_states(pattern)  # raises if a state does not close
    states = {
        "closed state 1": closed[1] * scale,
        "deployed": deployed,
        "closed state 2": closed[2] * scale,
    }
    rng = np.random.default_rng(seed)
    edge_off = rng.normal(0.0, kerf_sd, (n, T, 4))
    piv = rng.normal(0.0, hinge_sd, (n, len(A), 2, 2))  # per hinge, per side
    # errors in the deployed frame, rotated with each tile into the other states
    d_corner = corner_shift(deployed[None], edge_off)  # (N, T, 4, 2)
    assembly = _Assembly(A, B, T)
    size = pattern.tile_size * scale
    gap, omax, otot, seam = {}, {}, {}, {}
    outline = np.zeros(n)
    tile_gap = np.zeros(T)
    ref_nodes, ring = _outline_reference(pattern, scale)
    for name, nominal_c in states.items():
        g, placed = _assemble_state(top, deployed, nominal_c, d_corner, piv, assembly)
        gap[name] = g.max(axis=1)
        tile_gap = np.maximum(tile_gap, _tile_gap_mean(g, A, B, n, T))
        if name != "deployed":
            over, _, opening = seam_misfit(placed, seam_edges(nominal_c, 1e-3 * size))
            omax[name] = over.max(axis=1, initial=0.0)
            otot[name] = over.sum(axis=1)
            seam[name] = opening.max(axis=1, initial=0.0)
        else:
            outline = _outline_error(pattern, placed, ref_nodes, ring, scale, n)
    worst = np.maximum(gap["closed state 1"], gap["closed state 2"])
    return ToleranceResult(
        n=int(n),
        seed=int(seed),
        kerf_sd_mm=float(kerf_sd),
        hinge_sd_mm=float(hinge_sd),
        scale=float(scale),
        tile_size_mm=float(size),
        gap=gap,
        overlap_max=omax,
        overlap_total=otot,
        seam_gap=seam,
        outline=outline,
        outline_reference="design outline" if ring is not None else "design points",
        outline_fit_mm=_fit_mm(pattern, scale),
        sensitivity=_sensitivity(edge_off, piv, A, B, worst),
        tile_gap_mean=tile_gap,
        time_s=time.perf_counter() - t0,
    )


def _check_inputs(kerf_sd: float, hinge_sd: float, n: int, scale: float) -> None:
    """Refuse error sizes, scales and sample counts the model cannot take (InputError, one line)."""
    for name, v in (("--kerf-sd", kerf_sd), ("--hinge-sd", hinge_sd)):
        if not (np.isfinite(v) and v >= 0):
            raise InputError(f"{name} must be a finite number >= 0 mm, got {v}")
    if not (np.isfinite(scale) and scale > 0):
        raise InputError(f"--scale must be positive, got {scale}")
    if int(n) != n or not 2 <= n <= 1_000_000:
        raise InputError(f"--n must be a whole number of samples in 2..1000000, got {n}")


def _assemble_state(
    top,
    deployed: np.ndarray,
    nominal_c: np.ndarray,
    d_corner: np.ndarray,
    piv: np.ndarray,
    assembly: _Assembly,
) -> tuple[np.ndarray, np.ndarray]:
    """Every sample's fabricated tiles assembled in one state: the hinge gaps (N, H) and the placed corners.

    Each tile keeps its design rotation in the state (its errors turn with it); the translations are
    the least-squares fit of the pivot pairs.
    """
    A, B = top.hinge_tiles.T
    cA, cB = top.hinge_corner.T
    theta = geometry.kabsch_angles(deployed, nominal_c)  # (T,)
    c = nominal_c[None] + geometry.rotate(d_corner, theta[None, :, None])
    pa = c[:, A, cA] + geometry.rotate(piv[:, :, 0], theta[A][None])
    pb = c[:, B, cB] + geometry.rotate(piv[:, :, 1], theta[B][None])
    g = assembly.residual(pb - pa)  # (N, H)
    return g, _place(c, pa, pb, assembly)


def _tile_gap_mean(g: np.ndarray, A: np.ndarray, B: np.ndarray, n: int, T: int) -> np.ndarray:
    """Each tile's largest hinge gap, averaged over the samples (T,)."""
    at = np.zeros((n, T))
    np.maximum.at(at.T, A, g.T)
    np.maximum.at(at.T, B, g.T)
    return at.mean(axis=0)


def _outline_error(
    pattern: Pattern, placed: np.ndarray, ref_nodes: np.ndarray, ring, scale: float, n: int
) -> np.ndarray:
    """Deployed: each sample's largest distance of the aligned boundary points from the design outline
    (or, tiles not joined into one piece, from the design's own boundary points)."""
    nodes = _first_corner_nodes(pattern, placed)[:, ref_nodes]
    ref_xy = pattern.nodes[ref_nodes] * scale
    aligned = _align_many(nodes, ref_xy)
    if ring is not None:  # how far the outline moved: boundary points from the design outline
        return (
            shapely.distance(shapely.points(aligned.reshape(-1, 2)), ring)
            .reshape(n, -1)
            .max(axis=1)
        )
    return np.linalg.norm(aligned - ref_xy, axis=-1).max(axis=1)


def _sensitivity(
    edge_off: np.ndarray, piv: np.ndarray, A: np.ndarray, B: np.ndarray, worst: np.ndarray
) -> np.ndarray:
    """Per tile: the correlation of the size of its own errors (edges and pivots) with the worst gap."""
    err2 = (edge_off**2).sum(axis=2)
    np.add.at(err2.T, A, (piv[:, :, 0] ** 2).sum(-1).T)
    np.add.at(err2.T, B, (piv[:, :, 1] ** 2).sum(-1).T)
    size_t = np.sqrt(err2)
    return np.array([_corr(size_t[:, t], worst) for t in range(err2.shape[1])])


def _fit_mm(pattern: Pattern, scale: float) -> float | None:
    """The design's stored fit to its target (largest distance), in mm at ``scale``."""
    fit = (((pattern.design or {}).get("report") or {}).get("fit") or {}).get("shape") or {}
    v = fit.get("max_mm")
    return None if not isinstance(v, (int, float)) else float(v) * scale


def _corr(x: np.ndarray, y: np.ndarray) -> float:
    sx, sy = x.std(), y.std()
    return (
        0.0 if sx == 0 or sy == 0 else float(((x - x.mean()) * (y - y.mean())).mean() / (sx * sy))
    )


def _place(c: np.ndarray, pa: np.ndarray, pb: np.ndarray, assembly: _Assembly) -> np.ndarray:
    """Tile corners moved by the least-squares translations."""
    N, H, _ = pa.shape
    T = c.shape[1]
    m = (pb - pa).transpose(1, 0, 2).reshape(H, -1)
    tau = np.zeros((T, N * 2))
    tau[1:] = assembly.lu.solve(np.ascontiguousarray((assembly.D.T @ m)[1:]))
    # D τ = τ_A - τ_B ≈ pb - pa: moving each tile by +τ brings pa + τ_A onto pb + τ_B
    return c + tau.reshape(T, N, 2).transpose(1, 0, 2)[:, :, None, :]


def _first_corner_nodes(pattern: Pattern, corners: np.ndarray) -> np.ndarray:
    flat = pattern.tiles.ravel()[::-1]
    out = np.empty((corners.shape[0], len(pattern.nodes), 2))
    out[:, flat] = corners.reshape(corners.shape[0], -1, 2)[:, ::-1]
    return out


def _align_many(pts: np.ndarray, ref: np.ndarray) -> np.ndarray:
    """Each sample's points rigidly aligned (Kabsch) onto ``ref``."""
    th = geometry.kabsch_angles(pts[:, None], ref[None, None])[:, 0]
    rotated = geometry.rotate(pts, th[:, None])
    return rotated - rotated.mean(axis=1, keepdims=True) + ref.mean(axis=0)
