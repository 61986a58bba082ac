"""Fabrication inequalities: a design that can be cut or printed at the size it was asked for.

Plain numbers in millimetres (:class:`FabricationLimits`; the CLI resolves a material or printer
preset into them, this layer never sees a preset). At the design's size every tile must be

* at least ``min_width_mm`` wide at its thinnest once shrunk by ``shrink_mm`` (the smallest
  altitude of :mod:`fabkiri.pattern.thinness`, the definition ``cut`` checks): one row per
  tile edge, ``max_j dist(q_j, line e) - w >= 0`` over the two far corners, the max taken smoothly
  (:func:`smooth_max`, never above it, so a design that meets the rows meets ``cut``'s check);
* with ``shrink_mm``, every shrunk edge at least ``min_edge_mm`` long;
* ``hinge_spacing_mm`` between any two of its hinge corners (tape, ligament or strip allowance), and
  every edge that ends at a hinge ``hinge_edge_mm`` long (a printed strip runs along it);
* at every hinge corner, an angle whose sine is at least ``sin(min_hinge_angle_deg)`` (a printed
  strip's pad on an acute corner is too small at any scale);
* and every deployed hole at least ``min_hole_mm`` wide (opt-in);
* printed strips: two strips on one face of a tile at least ``strip_clearance_mm`` apart, each taken as
  the box it fills in the tile (along its seam from the hinge corner, ``strip_width`` plus the mitre
  start; across, ``strip_reach`` plus the shrink), separated along one of the four box axes
  (:func:`strip_rows`, the closed form of ``fabkiri.pattern.thinness.strip_clearance_scales``).

Rows are plain functions of a tile's (or hole's) four corners; their gradients are exact, carried
forward through every operation (:class:`Dual`, forward-mode differentiation over the 8 coordinates of
the four corners) and checked against finite differences in ``tests/design/test_fabrication.py``.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, fields, replace

import numpy as np

from ...pattern import thinness as fab
from ..core.dual import Dual, dual_corner, inward_normal, is_values_only, vec_dot, vec_sub
from . import print_rows, row_values
from .constraints import Family, Stencils
from .row_family import ineq_family, pick

NOT_LIMITS = ("source", "margin", "print_state")  # fields that are no requirement in mm
# fields in mm²: a continuation step scales them by the fraction squared, so a step's pad keeps the same share
# of its strip's band (0.25 w min(reach, w)) as the full limits' (linearly, a quarter step asked 1 mm² of a
# 1 x 1.05 mm band: every pad row of the 16x16 heart active and the step unconverged)
AREAS = ("strip_pad_mm2",)


@dataclass(frozen=True)
class FabricationLimits:
    """What the design must respect at its size, in mm (0: no such row)."""

    min_width_mm: float = 0.0
    shrink_mm: float = 0.0
    min_edge_mm: float = 0.0
    hinge_spacing_mm: float = 0.0
    hinge_edge_mm: float = (
        0.0  # every edge with a hinge at an end at least this long (a strip's seam)
    )
    min_hinge_angle_deg: float = 0.0
    min_hole_mm: float = 0.0
    # printed strips (fabkiri.fabricate.print.geometry): two strips on one face of a tile keep this clearance
    strip_clearance_mm: float = 0.0
    strip_width_mm: float = 0.0
    strip_reach_mm: float = 0.0
    strip_pad_mm2: float = 0.0  # every strip's pad on each tile at least this large (print_rows.py)
    source: str = ""  # what the numbers came from (material/printer names), for the report
    # penalty margin of the rows in tile edges (0: the solver's own, 0.005). A continuation step asks 0.02:
    # with 0.005 the penalty stages left width rows at exactly zero and the projection stalled against them
    # (16x16 heart at 200 mm, acrylic-3 at 3/4 of its limits: equality 1e-5, unconverged; 0.02: converged)
    margin: float = 0.0
    # the closed state ``print`` makes (the strip rows follow its folds): the one that fits the printer's bed
    print_state: int = 1

    @property
    def active(self) -> bool:
        return any(v > 0 for k, v in asdict(self).items() if k not in NOT_LIMITS)

    def scaled(self, fraction: float, margin: float = 0.0) -> FabricationLimits:
        """Every requirement times ``fraction``."""
        return replace(
            self,
            margin=margin,
            **{
                f.name: getattr(self, f.name) * fraction
                for f in fields(self)
                if f.name not in NOT_LIMITS
            },
        )

    def step(self, fraction: float, margin: float = 0.0) -> FabricationLimits:
        """A step of the continuation in the limits: every length times ``fraction`` and every area
        (``AREAS``) times its square, the limits of the same process shrunk alike."""
        out = self.scaled(fraction, margin)
        return replace(out, **{k: getattr(self, k) * fraction**2 for k in AREAS})

    def required_width_mm(self) -> float:
        """Unshrunk width every tile needs at least (erosion by d takes at least 2d off a width)."""
        return self.min_width_mm + 2.0 * self.shrink_mm if self.min_width_mm > 0 else 0.0

    def to_dict(self) -> dict:
        return asdict(self)


def _mitre(x, quads, rows, j, n: int | None = None):
    """Mitre vector at corner j: the corner moves by d times it when the quad shrinks by d.
    ``n``: the polygon's arity when ``quads`` holds more nodes after it (default all of them)."""
    n = quads.shape[1] if n is None else n
    prev, here, nxt = (dual_corner(x, quads, rows, (j + s) % n) for s in (-1, 0, 1))
    na, nb = inward_normal(prev, here), inward_normal(here, nxt)
    s = 1.0 + vec_dot(na, nb)
    return (na[0] + nb[0]) / s, (na[1] + nb[1]) / s


def _edges(x: np.ndarray, quads: np.ndarray, sel: np.ndarray | None = None):
    """Every quad's edge e (quad-major; rows ``sel`` of them only, if given): row quads, e, and the edge's two
    ends."""
    rows, e = row_values.edge_index(quads, sel)
    n = quads.shape[1]
    return rows, e, dual_corner(x, quads, rows, e), dual_corner(x, quads, rows, (e + 1) % n)


def width_rows(
    x: np.ndarray, quads: np.ndarray, width: float, shrink: float, sel: np.ndarray | None = None
) -> Dual:
    """``max_j dist(q_j, line e) - width`` for every quad and edge e (rows ordered quad-major; ``sel``: those
    rows only); any arity: a triangle has one far corner (the row is its altitude, exact), more are folded by
    smooth maxima."""
    if is_values_only(x):  # a residual-only call: the same bits on plain arrays
        return Dual(row_values.width_values(x, quads, width, shrink, sel, SMOOTH), None)
    rows, e, a, b = _edges(x, quads, sel)
    n = inward_normal(a, b)
    far = []
    for off in range(2, quads.shape[1]):
        j = (e + off) % quads.shape[1]
        g = vec_dot(n, vec_sub(dual_corner(x, quads, rows, j), a))
        if shrink:
            g = g + shrink * (vec_dot(n, _mitre(x, quads, rows, j)) - 1.0)
        far.append(g)
    top = far[0]
    for g in far[1:]:
        top = smooth_max(top, g)
    return top - width


SMOOTH = (
    0.02  # normalised (tile edges): the smooth max is at most this much below the max, never above
)


def smooth_max(a: Dual, b: Dual, eps: float = SMOOTH) -> Dual:
    """``(a+b)/2 + sqrt(((a-b)/2)² + ε²) - ε``: smooth, in [max - ε, max], equal to it where a = b.

    The far corners of a near-parallelogram tile (most tiles of a rotating-squares pattern) are nearly
    equidistant from an edge, and the plain max switched gradients there from step to step."""
    h = (a - b) * 0.5
    return (a + b) * 0.5 + (h * h + eps * eps).sqrt() - eps


def shrunk_edge_rows(
    x: np.ndarray, quads: np.ndarray, shrink: float, min_edge: float, sel: np.ndarray | None = None
) -> Dual:
    """Signed length of every shrunk edge (rows ``sel`` only, if given) minus ``min_edge``."""
    if is_values_only(x):
        return Dual(row_values.shrunk_edge_values(x, quads, shrink, min_edge, sel), None)
    rows, e, a, b = _edges(x, quads, sel)
    E = vec_sub(b, a)
    ln = vec_dot(E, E).sqrt()
    u = E[0] / ln, E[1] / ln
    ma, mb = _mitre(x, quads, rows, e), _mitre(x, quads, rows, (e + 1) % quads.shape[1])
    return ln + shrink * vec_dot(u, vec_sub(mb, ma)) - min_edge


def hinge_angle_rows(
    x: np.ndarray, quads: np.ndarray, t: np.ndarray, k: np.ndarray, sin_min: float
) -> Dual:
    """sin of the corner angle at hinge corners ``(t, k)`` minus ``sin_min``."""
    v, a, b = (dual_corner(x, quads, t, (k + s) % quads.shape[1]) for s in (0, 1, -1))
    A, B = vec_sub(a, v), vec_sub(b, v)
    return (A[0] * B[1] - A[1] * B[0]) / (vec_dot(A, A) * vec_dot(B, B)).sqrt() - sin_min


def spacing_rows(
    x: np.ndarray, quads: np.ndarray, t: np.ndarray, i: np.ndarray, j: np.ndarray, spacing: float
) -> Dual:
    """Distance between corners ``i`` and ``j`` of quads ``t`` minus ``spacing``."""
    d = vec_sub(dual_corner(x, quads, t, i), dual_corner(x, quads, t, j))
    return vec_dot(d, d).sqrt() - spacing


SOFT = 0.002  # normalised: the soft min/max of the strip rows are at most this far on the safe side
STRIP_SMOOTH = 0.002  # ... and their smooth max over the eight axis gaps


def _strip_box(x, quads, t, c, end):
    """Hinge corner ``c`` of quads ``t``, the unit direction of its seam (to corner ``end``) and the inward
    normal of that edge (tiles counter-clockwise)."""
    p = dual_corner(x, quads, t, c)
    q = dual_corner(x, quads, t, end)
    ev = vec_sub(q, p)
    ln = vec_dot(ev, ev).sqrt()
    e = ev[0] / ln, ev[1] / ln
    sgn = np.where(end == (c + 1) % quads.shape[1], 1.0, -1.0)
    return p, e, (-e[1] * sgn, e[0] * sgn)


def strip_rows(
    x: np.ndarray,
    quads: np.ndarray,
    t: np.ndarray,
    ch: np.ndarray,
    eh: np.ndarray,
    ck: np.ndarray,
    ek: np.ndarray,
    box: tuple[float, float, float, float],
) -> Dual:
    """Separating-axis gap between the strip boxes of hinge corners ``ch`` and ``ck`` of quads ``t`` (seams
    towards corners ``eh``, ``ek``; ``box = (a0, along, across, clearance)``, :func:`strip_box`: the box
    ``[a0, a0 + along]`` along the seam, ``[0, across]`` into the tile) minus ``clearance``; soft min/max and
    the smooth max over the eight axis gaps are all on the safe side."""
    if is_values_only(x):
        v = row_values.strip_values(x, quads, (t, ch, eh, ck, ek), box, SOFT, STRIP_SMOOTH)
        return Dual(v, None)
    a0, along, across, clearance = box
    ph, e_h, n_h = _strip_box(x, quads, t, ch, eh)
    pk, e_k, n_k = _strip_box(x, quads, t, ck, ek)

    def extents(e, n, u):
        """The box's lower and upper extent along u: smooth bounds of min(., 0) and max(., 0) of its axes'
        components, at most ``SOFT`` to the safe side (the two bounds share their square root)."""
        eu, nu = vec_dot(e, u), vec_dot(n, u)
        re, rn = (eu * eu + SOFT * SOFT).sqrt(), (nu * nu + SOFT * SOFT).sqrt()
        base = eu * a0
        lower = base + (eu - re) * 0.5 * along + (nu - rn) * 0.5 * across
        return lower, base + (eu + re) * 0.5 * along + (nu + rn) * 0.5 * across

    gaps = []
    for u in (e_h, n_h, e_k, n_k):
        dp = vec_dot(vec_sub(pk, ph), u)
        (lo_h, hi_h), (lo_k, hi_k) = extents(e_h, n_h, u), extents(e_k, n_k, u)
        gaps.append(dp + lo_k - hi_h)
        gaps.append(-dp + lo_h - hi_k)
    while len(gaps) > 1:  # a balanced tree of smooth maxima: at most 3 · STRIP_SMOOTH below the max
        gaps = [smooth_max(a, b, STRIP_SMOOTH) for a, b in zip(gaps[::2], gaps[1::2])]
    return gaps[0] - clearance


def ccw_polygons(quads: np.ndarray, x: np.ndarray) -> np.ndarray:
    """Polygons (node indices) reordered counter-clockwise in ``x`` (holes come either way round)."""
    p = x[quads]
    area = 0.5 * (
        p[:, :, 0] * np.roll(p[:, :, 1], -1, 1) - np.roll(p[:, :, 0], -1, 1) * p[:, :, 1]
    ).sum(1)
    out = quads.copy()
    out[area < 0] = out[area < 0][:, ::-1]
    return out


def families(
    st: Stencils, nv: int, limits: FabricationLimits | None, unit_mm: float, base: np.ndarray
) -> list[Family]:
    """The fabrication rows of ``limits`` in normalised units (1 = ``unit_mm``); ``base`` orients holes."""
    if limits is None or not limits.active:
        return []
    out = _families(st, nv, limits, unit_mm, base)
    if limits.margin > 0:
        for f in out:
            f.meta["margin"] = limits.margin
    return out


def _families(
    st: Stencils, nv: int, limits: FabricationLimits, unit_mm: float, base: np.ndarray
) -> list[Family]:
    tiles = st.tiles
    T = len(tiles)
    out = []
    d = limits.shrink_mm / unit_mm
    per_edge = {"quad_of_row": np.repeat(np.arange(T), 4)}
    if limits.min_width_mm > 0:
        w = limits.min_width_mm / unit_mm
        out.append(
            ineq_family(
                "fabrication_width",
                tiles,
                lambda x, sel, w=w: width_rows(x, tiles, w, d, sel),
                nv,
                dict(per_edge),
            )
        )
    if d > 0:
        e_min = max(limits.min_edge_mm, fab.EDGE_EPS_MM) / unit_mm
        out.append(
            ineq_family(
                "fabrication_shrunk_edges",
                tiles,
                lambda x, sel: shrunk_edge_rows(x, tiles, d, e_min, sel),
                nv,
                dict(per_edge),
            )
        )
    out += _hinge_families(st, nv, limits, unit_mm, tiles)
    if limits.strip_clearance_mm > 0:
        out += _strip_family(st, nv, limits, unit_mm, tiles)
    out += print_rows.families(st, nv, limits, unit_mm)
    if limits.min_hole_mm > 0 and len(st.hole_nodes):
        holes = ccw_polygons(st.hole_nodes, base)
        wh = limits.min_hole_mm / unit_mm
        out.append(
            ineq_family(
                "fabrication_holes",
                holes,
                lambda x, sel: width_rows(x, holes, wh, 0.0, sel),
                nv,
                {"quad_of_row": np.repeat(np.arange(len(holes)), 4)},
            )
        )
    return out


def _hinge_families(
    st: Stencils, nv: int, limits: FabricationLimits, unit_mm: float, tiles
) -> list[Family]:
    """Rows at the hinges: the angle of each hinge corner, two hinge corners of a tile apart, and a hinge
    corner clear of the far end of its edges."""
    T = len(tiles)
    out: list[Family] = []
    ht, hk = st.hinge_tiles.ravel(), st.hinge_corner.ravel()
    if limits.min_hinge_angle_deg > 0:
        s_min = float(np.sin(np.radians(limits.min_hinge_angle_deg)))
        out.append(
            ineq_family(
                "fabrication_hinge_angles",
                tiles,
                lambda x, sel: hinge_angle_rows(x, tiles, *pick((ht, hk), sel), s_min),
                nv,
                {"quad_of_row": ht},
            )
        )
    if limits.hinge_spacing_mm > 0:
        has = np.zeros((T, 4), dtype=bool)
        has[ht, hk] = True
        i, j = np.triu_indices(4, 1)
        t, p = np.nonzero(has[:, i] & has[:, j])
        s = limits.hinge_spacing_mm / unit_mm
        out.append(
            ineq_family(
                "fabrication_hinge_spacing",
                tiles,
                lambda x, sel: spacing_rows(x, tiles, *pick((t, i[p], j[p]), sel), s),
                nv,
                {"quad_of_row": t},
            )
        )
    if limits.hinge_edge_mm > 0:
        has = np.zeros((T, 4), dtype=bool)
        has[ht, hk] = True
        k = np.arange(4)
        te, e = np.nonzero(has | has[:, (k + 1) % 4])
        s_e = limits.hinge_edge_mm / unit_mm
        out.append(
            ineq_family(
                "fabrication_hinge_edges",
                tiles,
                lambda x, sel: spacing_rows(x, tiles, *pick((te, e, (e + 1) % 4), sel), s_e),
                nv,
                {"quad_of_row": te},
            )
        )
    return out


def _strip_family(
    st: Stencils, nv: int, limits: FabricationLimits, unit_mm: float, tiles
) -> list[Family]:
    """Strip clearance rows for every two hinge corners of a tile whose strips share a face (in closed state
    ``limits.print_state``, the one ``print`` makes; faces from the fold rules, as ``print`` assigns them)."""
    T = len(tiles)
    pairs = np.concatenate(
        [
            fab.coincident_hinges(st.hinge_tiles, st.hinge_corner, st.folds[s].fold_corner_ends, T)
            for s in (1, 2)
        ]
    )
    face = fab.strip_faces(np.unique(pairs, axis=0), len(st.hinge_tiles))
    t, h, sh, k, sk = fab.same_face_pairs(st.hinge_tiles, face, T)
    if not len(t):
        return []
    ends = st.folds[limits.print_state].fold_corner_ends
    a0, along, across, cl = strip_box(limits, unit_mm)
    args = (t, st.hinge_corner[h, sh], ends[h, sh], st.hinge_corner[k, sk], ends[k, sk])
    return [
        ineq_family(
            "fabrication_strip_clearance",
            tiles,
            lambda x, sel: strip_rows(x, tiles, *pick(args, sel), (a0, along, across, cl)),
            nv,
            {"quad_of_row": t},
        )
    ]


def strip_box(limits: FabricationLimits, unit_mm: float) -> tuple[float, float, float, float]:
    """``(a0, along, across, clearance)`` of :func:`strip_rows` for ``limits`` in units of ``unit_mm``."""
    d = limits.shrink_mm
    sin_min = (
        float(np.sin(np.radians(limits.min_hinge_angle_deg)))
        if limits.min_hinge_angle_deg > 0
        else 1.0
    )
    a0 = d / unit_mm  # the strip starts t0 = d / sin(sharper corner) along the seam: at least d, at
    along = (d / sin_min - d + limits.strip_width_mm) / unit_mm  # most d / sin(min hinge angle)
    across = (limits.strip_reach_mm + d) / unit_mm
    return a0, along, across, limits.strip_clearance_mm / unit_mm


def smallest_size(
    size_mm: float, area_mm2: float, n_tiles: int, limits: FabricationLimits
) -> float | None:
    """The smallest target size (same shape) at which the tiles could be wide enough, or None when
    ``size_mm`` already could: ``n_tiles`` tiles each ``w`` wide cover at least ``n · w²/√3`` (Pál),
    and they lie inside the deployed outline, so its area must be at least that."""
    w = limits.required_width_mm()
    need = fab.pal_bound(n_tiles, w)
    if w <= 0 or area_mm2 >= need:
        return None
    return float(size_mm * np.sqrt(need / area_mm2))
