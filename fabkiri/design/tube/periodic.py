"""Periodicity constraints and targets of a tube's sheet (docs/tubes.md).

Families over the deployed nodes ``x`` (normalised units, the initial tile edge is 1), in the
:mod:`fabkiri.design.quad.constraints` convention (residuals, analytic sparse Jacobian):

* :func:`deployed_seam`: the seam copy column is the first column moved by a fixed rigid map
  ``x_copy = R x_first + c`` (a translation by the target circumference for a cylinder, a rotation
  about the apex for a cone): linear, one row per coordinate of every identified node pair;
* :func:`closed_seam`: in closed state ``s`` the copy's rotation relative to the first column, the
  sum of the hinge turns along a row plus their deployed relative rotation, is zero; with every hole
  closed this makes the closed seam a pure translation (one row per state);
* :func:`tube_fit`: the bottom and top boundary tips on the target's two ends (lines for a cylinder,
  circles about the apex for a cone).
"""

from __future__ import annotations

import re
from dataclasses import dataclass

import numpy as np
from scipy import sparse

from ...errors import InputError
from ...pattern.geometry import signed_angle, wrap_angle
from ...pattern.kinds.periodic.sheet import Seam
from ..core.stencils import Family, Stencils

TWO_PI = 2.0 * np.pi


@dataclass(frozen=True)
class TubeTarget:
    """The unrolled deployed tube, in mm: a cylinder (circumference x length) or a cone frustum.

    A cone frustum has radius ``r_bottom`` at the bottom row and ``r_top`` at the top row, ``length``
    apart along its axis; it unrolls onto an annular sector (a developable patch).
    """

    kind: str
    r_bottom: float
    r_top: float
    length: float

    @property
    def mean_circumference(self) -> float:
        return np.pi * (self.r_bottom + self.r_top)

    @property
    def slant(self) -> float:
        return float(np.hypot(self.length, self.r_bottom - self.r_top))

    def sector(self) -> tuple[float, float, float]:
        """Cone: distances of the bottom and top ends from the apex (mm) and the sector angle (rad)."""
        rho_top = self.r_top * self.slant / (self.r_bottom - self.r_top)
        rho_bottom = rho_top + self.slant
        return rho_bottom, rho_top, TWO_PI * self.r_bottom / rho_bottom

    def to_dict(self) -> dict:
        return {
            "kind": self.kind,
            "r_bottom_mm": self.r_bottom,
            "r_top_mm": self.r_top,
            "length_mm": self.length,
        }


def parse_tube_target(spec: str) -> TubeTarget:
    """``cylinder:CIRCUMFERENCE,LENGTH`` or ``cone:R_BOTTOM,R_TOP,LENGTH`` (mm) -> a target."""
    m = re.fullmatch(r"\s*(cylinder|cone)\s*:\s*([^,]+(?:,[^,]+)*)\s*", spec or "")
    if not m:
        raise InputError(
            f"--tube expects cylinder:CIRC,LENGTH or cone:R_BOTTOM,R_TOP,LENGTH (mm), got {spec!r}"
        )
    kind = m.group(1)
    try:
        vals = [float(v) for v in m.group(2).split(",")]
    except ValueError:
        raise InputError(
            f"--tube {kind}: the sizes must be numbers in mm, got {m.group(2)!r}"
        ) from None
    need = 2 if kind == "cylinder" else 3
    if len(vals) != need or not all(np.isfinite(v) and v > 0 for v in vals):
        raise InputError(f"--tube {kind} needs {need} positive sizes in mm, got {m.group(2)!r}")
    if kind == "cylinder":
        r = vals[0] / TWO_PI
        return TubeTarget("cylinder", r, r, vals[1])
    if vals[0] <= vals[1]:
        raise InputError(f"--tube cone: R_BOTTOM must exceed R_TOP, got {vals[0]:g} <= {vals[1]:g}")
    return TubeTarget("cone", vals[0], vals[1], vals[2])


@dataclass(frozen=True)
class UnitGeometry:
    """The target in normalised units (``scale`` mm per unit): the fixed deployed seam map and the ends.

    Cylinder: ends are the lines ``y = bottom`` and ``y = top``. Cone: circles of radius ``bottom`` and
    ``top`` about ``apex``; the seam map turns by ``alpha`` about the apex.
    """

    kind: str
    scale: float
    R: np.ndarray
    c: np.ndarray
    bottom: float
    top: float
    apex: np.ndarray | None = None
    alpha: float = 0.0


def unit_geometry(target: TubeTarget, period_units: float) -> UnitGeometry:
    """Normalise ``target`` so its mean deployed circumference is ``period_units`` (tile edges)."""
    scale = target.mean_circumference / period_units
    if target.kind == "cylinder":
        h = 0.5 * target.length / scale
        return UnitGeometry("cylinder", scale, np.eye(2), np.array([period_units, 0.0]), -h, h)
    rho_b, rho_t, alpha = target.sector()
    rho_b, rho_t = rho_b / scale, rho_t / scale
    apex = np.array(
        [0.0, 0.5 * (rho_b + rho_t)]
    )  # the sheet's middle row on the x axis, apex above
    R = np.array([[np.cos(alpha), -np.sin(alpha)], [np.sin(alpha), np.cos(alpha)]])
    return UnitGeometry("cone", scale, R, apex - R @ apex, rho_b, rho_t, apex, alpha)


def deployed_seam(seam: Seam, st: Stencils, geo: UnitGeometry, nv: int) -> Family:
    """``x_copy - R x_first - c = 0`` for every identified node pair (2 rows a pair, linear)."""
    pairs = seam.node_pairs(st.tiles)
    first, copy = pairs[:, 0], pairs[:, 1]
    m = len(pairs)
    rows = np.repeat(np.arange(2 * m), 3)
    # row 2i+d: +1 at copy coordinate d, -R[d, 0] and -R[d, 1] at the first node's x and y
    cols = np.stack(
        [
            2 * copy[:, None] + np.arange(2),
            np.repeat(2 * first[:, None], 2, 1),
            np.repeat(2 * first[:, None] + 1, 2, 1),
        ],
        -1,
    ).reshape(-1)
    vals = np.tile(np.stack([np.ones(2), -geo.R[:, 0], -geo.R[:, 1]], -1), (m, 1)).reshape(-1)
    J = sparse.csr_matrix((vals, (rows, cols)), shape=(2 * m, 2 * nv))

    def fn(x):
        r = x[copy] - x[first] @ geo.R.T - geo.c
        return r.reshape(-1), J

    return Family("seam_deployed", "eq", fn, 1, meta={"pairs": pairs}, nv=nv)


def _angle_grad(v: np.ndarray) -> np.ndarray:
    """∂ atan2(v_y, v_x) / ∂v."""
    return np.stack([-v[..., 1], v[..., 0]], -1) / (v * v).sum(-1, keepdims=True)


def row_path_hinges(st: Stencils, path: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Hinge index and orientation (+1: the path goes from its tile A to B) between consecutive tiles."""
    T = len(st.tiles)
    key = {int(a) * T + int(b): i for i, (a, b) in enumerate(st.hinge_tiles)}
    hs, sign = [], []
    for p, q in zip(path[:-1], path[1:], strict=True):
        a, b = min(p, q), max(p, q)
        hs.append(key[int(a) * T + int(b)])
        sign.append(1.0 if p == a else -1.0)
    return np.array(hs), np.array(sign)


def closed_seam(seam: Seam, st: Stencils, state: int, nv: int, row: int = 0) -> Family:
    """Rotation of the copy relative to the first column in closed ``state`` (one row, radians).

    Along the tiles of ``row`` the closed placement turns tile B by δ_h relative to A at every hinge
    (:func:`fabkiri.mechanics.contract.hinge_turns`); the copy's closed rotation relative to the first
    column is Σ ±δ_h plus the deployed angle between one edge of each.
    """
    t0, tc = int(seam.first[row]), int(seam.copy[row])
    path = np.arange(t0, tc + 1)  # a lattice row: tiles r*cols + c, left to right
    hs, sign = row_path_hinges(st, path)
    fold = st.folds[state]
    h, a, b = st.hinge_node[hs], fold.fold_ends[hs, 0], fold.fold_ends[hs, 1]
    e0, ec = st.tiles[t0, :2], st.tiles[tc, :2]
    nodes = np.concatenate([a, h, b, e0, ec])[None, :]

    def fn(x):
        va, vb = x[a] - x[h], x[b] - x[h]
        u0, uc = x[e0[1]] - x[e0[0]], x[ec[1]] - x[ec[0]]
        r = wrap_angle(np.array([sign @ signed_angle(vb, va) + signed_angle(u0, uc)]))
        ga, gb = _angle_grad(va) * sign[:, None], _angle_grad(vb) * sign[:, None]
        g0, gc = _angle_grad(u0), _angle_grad(uc)
        grads = np.concatenate([ga, gb - ga, -gb, [g0, -g0], [-gc, gc]])[None]
        return r, (nodes, grads)

    return Family(f"seam_closed_{state}", "eq", fn, 0, nv=nv)


def tube_fit(st: Stencils, geo: UnitGeometry, nv: int) -> Family:
    """Signed distance of the bottom (side B) and top (side T) tips to the target's two ends."""
    sel = np.flatnonzero((st.tip_side == 0) | (st.tip_side == 2))
    nodes = st.tip_nodes[sel]
    goal = np.where(st.tip_side[sel] == 0, geo.bottom, geo.top)

    def fn(x):
        p = x[nodes]
        if geo.apex is None:
            g = np.tile([0.0, 1.0], (len(p), 1))
            return p[:, 1] - goal, (nodes[:, None], g[:, None, :])
        d = p - geo.apex
        rho = np.linalg.norm(d, axis=1)
        return rho - goal, (nodes[:, None], (d / rho[:, None])[:, None, :])

    return Family("tube_fit", "fit", fn, 1, meta={"nodes": nodes}, nv=nv)
