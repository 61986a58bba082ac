"""The target curve: a closed curve in mm with projection, signed distance and the
four-arc split used for boundary matching (docs/algorithm.md#shape-matching).

A :class:`Target` is a closed counter-clockwise curve, either a periodic cubic
spline (smooth shapes, user splines) or a polyline (polygons, stars, user
polylines). The parameter ``u`` runs over ``[0, 1)`` proportionally to chord
length. Four split parameters cut the curve into the arcs B, R, T, L (in CCW
order, from the BL corner to the BR corner, and so on); each boundary tip of a
pattern is matched to the arc of its side (the table in docs/algorithm.md#shape-matching).

Signed distance is positive outside, negative inside; its gradient with the
foot point held fixed is the unit outward direction (envelope theorem).
"""

from __future__ import annotations

import copy
import math
from dataclasses import dataclass

import numpy as np

from ...errors import InputError
from ...kdtree import KDTree
from ...pattern.geometry import dot2
from ..core.spline import PeriodicCubic
from .projector import _OFFSETS, Projector, _clip, _length

SIDES = ("B", "R", "T", "L")  # CCW order of the arcs; side index 0..3


@dataclass(eq=False, init=False)
class Target:
    """A closed CCW target curve in mm split into four arcs.

    ``points`` are the spline knots or polyline vertices (not repeated at the
    end); ``corners`` the parameters of the BL, BR, TR, TL split points, CCW
    (given as None: the default split, :meth:`_default_corners`).
    """

    name: str
    kind: str  # "spline" | "polyline"
    points: np.ndarray
    corners: np.ndarray
    source: dict

    # written out (not the dataclass's) because ``corners`` may be given as None but is an array once made
    def __init__(
        self,
        name: str,
        kind: str,
        points: np.ndarray,
        corners: np.ndarray | None = None,
        source: dict | None = None,
    ) -> None:
        self.name, self.kind, self.points = name, kind, points
        self.source = {} if source is None else source
        self._build(corners)

    def _build(self, corners: np.ndarray | None) -> None:
        """Validate and orient the curve, parametrise it by arc length and set the four corners."""
        pts = np.asarray(self.points, dtype=float)
        if pts.ndim != 2 or pts.shape[1] != 2 or len(pts) < 3:
            raise InputError(f"target {self.name!r}: needs at least 3 points [x, y]")
        if not np.isfinite(pts).all():
            raise InputError(f"target {self.name!r}: non-finite coordinate")
        if np.linalg.norm(pts[0] - pts[-1]) < 1e-12 * max(1.0, np.abs(pts).max()):
            pts = pts[:-1]
        seg = np.linalg.norm(np.roll(pts, -1, 0) - pts, axis=1)
        if (seg <= 1e-12 * seg.max()).any():
            keep = seg > 1e-12 * seg.max()
            pts, seg = pts[keep], seg[keep]
        if len(pts) < 3:
            raise InputError(f"target {self.name!r}: needs at least 3 distinct points")
        area = 0.5 * float(
            np.sum(pts[:, 0] * np.roll(pts[:, 1], -1) - np.roll(pts[:, 0], -1) * pts[:, 1])
        )
        if abs(area) < 1e-12 * seg.sum() ** 2:
            raise InputError(f"target {self.name!r}: the curve encloses no area")
        if area < 0:
            pts = pts[::-1].copy()
            seg = np.linalg.norm(np.roll(pts, -1, 0) - pts, axis=1)
        self.points = pts
        knots = np.concatenate([[0.0], np.cumsum(seg)]) / seg.sum()
        self._u = knots  # (K+1,) parameter of each point, closing point at 1
        self._h = float(np.diff(knots).min())
        if self.kind == "spline":
            closed = np.vstack([pts, pts[:1]])
            self._spline = PeriodicCubic.interpolate(knots, closed)
        elif self.kind != "polyline":
            raise InputError(f"target kind must be 'spline' or 'polyline', not {self.kind!r}")
        self._dense_u = self._sample_params()
        dense = self.point(self._dense_u)
        _check_simple(dense, self.name)
        self._dense = dense
        self._bbox = (dense.min(0), dense.max(0))  # the curve is fixed after construction
        c = np.mod(
            np.asarray(self._default_corners() if corners is None else corners, dtype=float), 1.0
        )
        if c.shape != (4,):
            raise InputError(f"target {self.name!r}: needs exactly 4 corner parameters")
        # rotate so the sequence BL, BR, TR, TL is increasing from BL
        c = np.mod(c - c[0], 1.0) + c[0]
        if not (np.diff(c) > 0).all():
            raise InputError(f"target {self.name!r}: corners BL, BR, TR, TL must be in CCW order")
        self.corners = c
        self._arc_trees: tuple | None = (
            None  # (corners, arc tree, arc params, lift, curve tree), on first use
        )
        self._frame = (
            self,
            1.0,
            np.zeros(2),
        )  # (owner, a, b): this curve is a · owner + b, owner has the trees

    # ----------------------------------------------------------- evaluation
    def _sample_params(self, per_interval: int = 8) -> np.ndarray:
        u = self._u
        f = np.linspace(0.0, 1.0, per_interval, endpoint=False)
        return (u[:-1, None] + f[None, :] * np.diff(u)[:, None]).ravel()

    def point(self, u: np.ndarray) -> np.ndarray:
        u = np.mod(np.asarray(u, dtype=float), 1.0)
        if self.kind == "spline":
            return self._spline(u)
        i = self._segment(u)
        a = self.points[i]
        b = self.points[(i + 1) % len(self.points)]
        w = ((u - self._u[i]) / (self._u[i + 1] - self._u[i]))[..., None]
        return a + w * (b - a)

    def _segment(self, u: np.ndarray) -> np.ndarray:
        """The polyline segment of each parameter ``u`` in [0, 1]."""
        return _clip(np.searchsorted(self._u, u, side="right") - 1, 0, len(self.points) - 1)

    def tangent(self, u: np.ndarray) -> np.ndarray:
        """Unit tangent (CCW direction)."""
        u = np.mod(np.asarray(u, dtype=float), 1.0)
        if self.kind == "spline":
            d = self._spline(u, 1)
        else:
            i = self._segment(u)
            d = self.points[(i + 1) % len(self.points)] - self.points[i]
        return d / _length(d)[..., None]

    def sample(self, n: int = 400) -> np.ndarray:
        return self.point(np.linspace(0.0, 1.0, n, endpoint=False))

    @property
    def dense(self) -> np.ndarray:
        return self._dense

    @property
    def bbox(self) -> tuple[np.ndarray, np.ndarray]:
        return self._bbox[0].copy(), self._bbox[1].copy()

    @property
    def size(self) -> float:
        lo, hi = self.bbox
        return float((hi - lo).max())

    @property
    def area(self) -> float:
        d = self._dense
        return 0.5 * float(np.sum(d[:, 0] * np.roll(d[:, 1], -1) - np.roll(d[:, 0], -1) * d[:, 1]))

    def arc_range(self, side: int) -> tuple[float, float]:
        """Parameter interval ``[a, b]`` (b may exceed 1) of arc B, R, T or L."""
        c = self.corners
        a = c[side]
        b = c[(side + 1) % 4] + (1.0 if side == 3 else 0.0)
        return float(a), float(b)

    def corner_points(self) -> np.ndarray:
        return self.point(self.corners)

    # ------------------------------------------------------------ transform
    def transformed(self, scale: float = 1.0, shift=(0.0, 0.0), name: str | None = None) -> Target:
        """A scaled and shifted copy with the same corners.

        A similarity keeps the curve simple and its arc-length parameters, so the copy reuses them: the
        spline is the same piecewise cubic with scaled coefficients (no refit, no re-validation).
        """
        if not (np.isfinite(scale) and scale > 0):
            raise InputError(f"target {self.name!r}: scale must be positive, got {scale}")
        shift = np.asarray(shift, dtype=float)
        new = copy.copy(self)
        new.name = name or self.name
        new.points = self.points * scale + shift
        new.corners = self.corners.copy()
        new.source = dict(self.source)
        if self.kind == "spline":
            c = self._spline.c * scale
            c[-1] += shift  # the constant term of each piece carries the shift
            new._spline = PeriodicCubic(c, self._spline.x)
        new._dense = self._dense * scale + shift
        new._bbox = (self._bbox[0] * scale + shift, self._bbox[1] * scale + shift)
        owner, a, b = self._frame
        new._frame = (
            owner,
            a * scale,
            b * scale + shift,
        )  # a similarity keeps nearest samples: share the trees
        new._arc_trees = (
            None  # used only if the copy's corners are changed and it builds trees of its own
        )
        return new

    def centred(self) -> Target:
        """The same curve shifted so that its bounding box's centre is the origin (``transformed``)."""
        lo, hi = self.bbox
        return self.transformed(shift=-0.5 * (lo + hi))

    def scaled_to(self, size: float) -> Target:
        """Scaled about its bounding-box centre to ``size`` (larger dimension) and centred on the origin."""
        lo, hi = self.bbox
        s = size / float((hi - lo).max())
        return Target(
            self.name,
            self.kind,
            (self.points - 0.5 * (lo + hi)) * s,
            corners=self.corners.copy(),
            source=dict(self.source),
        )

    def mirror_error(self, axis: str) -> float:
        """How far the curve is from symmetric about the x or y axis (relative to its size)."""
        d = self._dense
        m = d * (np.array([1.0, -1.0]) if axis == "x" else np.array([-1.0, 1.0]))
        dist, _ = KDTree(d).query(m)
        # dense polyline points are not mirror images of each other; compare with the spacing
        spacing = np.linalg.norm(np.diff(d, axis=0), axis=1).max()
        return float(max(0.0, dist.max() - spacing)) / self.size

    # ----------------------------------------------------------- projection
    def _arc_index(self):
        """``(tree, params, lift, whole, whole_params, a, b)``: one KD-tree over samples of all four arcs, arc
        ``s`` lifted to height ``s · lift``, and a tree of the whole curve, both in the frame of the curve
        this one is a similar copy of (points there are ``(p - b) / a``).

        A query lifted the same way finds the nearest sample of its own arc in one call: any two points
        of the curve are closer than ``lift``, so a sample of another arc never wins (four trees cost four
        queries). Copies made by :meth:`transformed` share the trees (building them cost more than the
        whole 8x8 solve's projections).
        """
        owner, a, b = self._frame
        if owner._arc_trees is None or not np.array_equal(owner._arc_trees[0], self.corners):
            if not np.array_equal(
                owner.corners, self.corners
            ):  # corners reassigned on a copy: own trees
                self._frame = owner, a, b = self, 1.0, np.zeros(2)
            lift = 4.0 * max(owner.size, 1e-300)
            pts, params = [], []
            # seeds for the foot: 8 samples per interval, but about 2048 at most (a 1024-knot circle need
            # not seed Newton from 8192; the tree's build was most of a small design's set-up)
            seeds = owner._sample_params(int(np.clip(np.ceil(2048 / (len(owner._u) - 1)), 1, 8)))
            for s in range(4):
                lo, hi = owner.arc_range(s)
                uu = np.mod(seeds - lo, 1.0) + lo
                us = np.concatenate([uu[uu <= hi], [lo, hi]])
                pts.append(np.column_stack([owner.point(us), np.full(len(us), s * lift)]))
                params.append(us)
            owner._arc_trees = (
                owner.corners.copy(),
                KDTree(np.vstack(pts)),
                np.concatenate(params),
                lift,
                KDTree(owner.point(seeds)),
                seeds,
            )
        _, tree, us, lift, whole, whole_u = owner._arc_trees
        return tree, us, lift, whole, whole_u, a, b

    def project(self, p: np.ndarray, side: np.ndarray | None = None):
        """Foot points on the arcs of ``side`` (or the whole curve).

        Returns ``(u, foot, d, n)``: foot parameter, foot point, signed distance
        (positive outside) and its gradient with respect to ``p``.
        """
        p = np.asarray(p, dtype=float).reshape(-1, 2)
        return self.projector(np.full(len(p), -1) if side is None else side)(p)

    def projector(self, side: np.ndarray) -> Projector:
        """:meth:`project` for points on fixed arcs ``side`` (-1: the whole curve), with the per-arc
        bounds and lifted queries worked out once (a constraint family projects the same tips every call)."""
        return Projector(self, np.asarray(side, dtype=np.int64).reshape(-1))

    def signed_distance(self, p: np.ndarray, side: np.ndarray | None = None) -> np.ndarray:
        return self.project(p, side)[2]

    def _normal(self, u: np.ndarray, foot: np.ndarray) -> np.ndarray:
        """Outward unit normal; at polyline vertices the mean of both sides."""
        if self.kind == "spline":
            t = self.tangent(u)
        else:
            um = np.mod(u, 1.0)
            i = np.searchsorted(self._u, um)
            # within 1e-13 of a vertex (``np.isclose`` with no relative part, without its overhead)
            at_vertex = np.abs(self._u[_clip(i, 0, len(self._u) - 1)] - um) <= 1e-13
            at_vertex |= np.abs(self._u[_clip(i - 1, 0, len(self._u) - 1)] - um) <= 1e-13
            t, t_before = self.tangent(np.concatenate([u, u - 1e-9])).reshape(2, len(u), 2)
            mean = t + t_before
            norm = _length(mean)[:, None]
            t = np.where(at_vertex[:, None] & (norm > 1e-12), mean / np.maximum(norm, 1e-300), t)
        return np.stack([t[:, 1], -t[:, 0]], -1)

    def _spline_012(self, u: np.ndarray):
        """Spline point and first two derivatives at ``u`` in [0, 1] (one interval lookup: as fast as
        three calls of scipy's ``PPoly``)."""
        return self._spline.value_and_derivatives(u)

    def _newton_foot(self, p, u, lo, hi, iters: int = 8):
        """Newton on d/du |γ(u) - p|² = 0, clamped to each point's arc: ``u, γ(u), γ'(u)``.

        Quadratic convergence: after a step below 1e-6 h the foot is within ~1e-12 h, where the distance
        is stationary in u, so the point and tangent come from the last evaluation moved by that step
        (its square is below round-off).
        """
        h = self._h
        for _ in range(iters):
            g, d1, d2 = self._spline_012(np.mod(u, 1.0))
            r = g - p
            f = dot2(d1, r)
            fp = dot2(d2, r) + dot2(d1, d1)
            step = -f / np.where(fp > 0, fp, np.inf)  # no step where the curve turns away
            un = np.minimum(np.maximum(u + np.minimum(np.maximum(step, -2.0 * h), 2.0 * h), lo), hi)
            du, u = (un - u)[:, None], un
            if np.abs(step).max(initial=0.0) <= 1e-6 * h:
                return u, g + d1 * du, d1 + d2 * du
        g, d1, _ = self._spline_012(np.mod(u, 1.0))
        return u, g, d1

    def _polyline_foot(self, p, u, lo, hi):
        """``(u, foot)``: the nearest of the feet on the seed's segment and its two neighbours, each tried in
        the arc's period and the ones either side, clamped to ``[lo, hi]`` (the first of near-equals).

        The nine candidates are evaluated in one batch (one ``point`` call, not nine: the per-call cost
        was most of a 16x16 design's projections); the arithmetic per candidate is the same.
        """
        K = len(self.points)
        um = np.mod(u, 1.0)
        i0 = self._segment(um)
        base = u - um  # keep the period offset of the arc range
        i = (i0 + _OFFSETS[:, None]) % K  # (3, N): the seed's segment and its neighbours
        a, b = self.points[i], self.points[(i + 1) % K]
        ab = b - a
        w = _clip(dot2(p - a, ab) / dot2(ab, ab), 0.0, 1.0)
        uu = self._u[i] + w * (self._u[i + 1] - self._u[i])
        # bring into the arc's period and clamp to it: (3 segments, 3 shifts, N) in the order tried
        cand = _clip((uu + base)[:, None, :] + _OFFSETS[None, :, None], lo, hi).reshape(9, -1)
        pts = self.point(cand.ravel()).reshape(9, len(p), 2)
        dd = _length(pts - p)
        best_d, best_k = np.full(len(p), np.inf), np.full(len(p), -1)
        for k in range(9):
            better = dd[k] < best_d - 1e-15
            best_d = np.where(better, dd[k], best_d)
            best_k[better] = k
        row, k = np.arange(len(p)), np.maximum(best_k, 0)
        found = best_k >= 0  # no candidate only for a point not finite: its seed kept
        return np.where(found, cand[k, row], u), pts[k, row]

    def default_corner_split(self) -> np.ndarray:
        return self._default_corners()

    def _default_corners(self) -> np.ndarray:
        """Split where rays from the bounding-box centre to its corners meet the curve.

        Where the rays meet a curve that is not star-shaped about that centre out of order (an E,
        a comb), split at the curve's farthest points along the four diagonals instead: those are
        vertices of its convex hull, met by a simple curve in the hull's own CCW order.
        """
        c = self._ray_corners()
        if (np.diff(np.mod(c - c[0], 1.0)) > 0).all():
            return c
        d = self._dense
        k = [int(np.argmax(d @ np.array(v))) for v in ((-1, -1), (1, -1), (1, 1), (-1, 1))]
        return self._dense_u[k]

    def _ray_corners(self) -> np.ndarray:
        d = self._dense
        lo, hi = d.min(0), d.max(0)
        c = 0.5 * (lo + hi)
        rel = d - c
        ang = np.arctan2(rel[:, 1], rel[:, 0])
        out = []
        for cx, cy in ((lo[0], lo[1]), (hi[0], lo[1]), (hi[0], hi[1]), (lo[0], hi[1])):
            target = math.atan2(cy - c[1], cx - c[0])
            diff = np.abs(np.angle(np.exp(1j * (ang - target))))
            # nearest in angle, farthest from the centre among near-ties (star-shaped or not)
            cand = np.flatnonzero(diff <= diff.min() + 1e-9)
            k = cand[np.argmax(np.linalg.norm(rel[cand], axis=1))]
            out.append(self._dense_u[k])
        return np.array(out)

    def to_dict(self) -> dict:
        return {
            "name": self.name,
            "kind": self.kind,
            "points": self.points.tolist(),
            "corners": self.corners.tolist(),
            "source": self.source,
            "size_mm": self.size,
            "area_mm2": self.area,
        }


def _check_simple(dense: np.ndarray, name: str) -> None:
    import shapely

    ring = shapely.LinearRing(dense)
    if not ring.is_simple:
        raise InputError(f"target {name!r}: the curve intersects itself")
