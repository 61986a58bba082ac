"""Fabrication inequalities of kagome designs: a kagome that can be cut or printed at its design size.

The limits are the quad designer's :class:`~.fabrication.FabricationLimits` (plain mm, resolved from the
material and printer presets in ``fabricate/design_limits.py``), and the rows are the same functions of a
tile's corners (:mod:`.fabrication`, any polygon arity), applied to the triangles:

* **width**: every triangle at least ``min_width_mm`` wide at its thinnest once shrunk by ``shrink_mm``.
  A triangle has one far corner per edge, so the row of edge e is exactly the altitude onto e of the
  shrunk triangle minus the width: the definition ``cut`` and ``print`` check
  (:func:`fabkiri.pattern.thinness.widths`), no smoothing;
* **shrunk edges** (with a shrink): every edge of the shrunk triangle at least ``min_edge_mm`` long;
* **hinge angles**: the sine of every hinge corner's angle at least ``sin(min_hinge_angle_deg)`` (a
  printed strip's pad in an acute corner is too small at any scale);
* **hinge spacing** and **hinge edges**: two hinge corners of a tile ``hinge_spacing_mm`` apart (on a
  triangle that is the edge between them), every edge ending at a hinge ``hinge_edge_mm`` long;
* **strip clearance**: the strip boxes of every two hinge corners of a tile ``strip_clearance_mm`` apart
  (:func:`.fabrication.strip_rows`, seams in closed state ``print_state``). Every pair, not only those on
  one face: ``print`` chooses the faces of kagome hinges by flips around odd cycles
  (``fabricate/print/geometry.py``), which the design cannot predict, and every pair is the safe superset;
* **strip pads**: every strip's pad on each of its triangles at least ``strip_pad_mm2`` (:mod:`.print_rows`,
  the area ``print`` clips);
* **holes** (``--min-hole``): every deployed hexagonal hole at least ``min_hole_mm`` wide.

The kagome fit's unknowns are normalised (1 = the standard tile edge, ``unit_mm`` millimetres), so every
mm limit is divided by ``unit_mm``. In the fit the rows are soft one-sided rows ``min(g - margin, 0)``
(the convention of :mod:`.kagome_rows`); the soft solve leaves a row violated by a little, so each asks
``MARGIN`` more than the limit, and :func:`measure` judges a design on the rows themselves in mm (no
margin): a design whose rows are all >= 0 meets the limits ``cut`` and ``print`` check.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from ...pattern import thinness as fab
from ...pattern.model import Pattern
from ..core.stencils import Family
from ..quad import fabrication as F
from ..quad import print_rows as PR

MARGIN = 0.01  # tile edges (about 0.1 mm at 11 mm tiles), or a sine: what the soft rows ask beyond a limit
# times the fit's inequality weight: at 1 the 12x21 heart's rows stayed 1.5 mm short at every Lawson step
# (the fit outweighs them), at 10 they are met to the margin
WEIGHT = 10.0
LAND = True  # the landing sees the rows
SLACK_MM = (
    fab.WEB_SLACK_MM
)  # a measured row this far below zero still meets (cut's own forgiveness)


@dataclass(frozen=True)
class Rows:
    """One kind of fabrication row: ``g(x)`` (a :class:`~.fabrication.Dual` per row, >= 0 when met), the tile
    each row belongs to, and whether it is a length (else a sine)."""

    name: str
    g: Callable[[np.ndarray], F.Dual]
    owner: np.ndarray
    length: bool = True
    polys: np.ndarray | None = None  # the nodes each row reads (None: its tile's, or hole's)


def rows(
    pattern: Pattern,
    limits: F.FabricationLimits | None,
    unit_mm: float,
    faces: np.ndarray | None = None,
) -> list[Rows]:
    """Every fabrication row of ``limits`` for ``pattern``'s triangles, in units of ``unit_mm`` (mm);
    ``faces``: the printed face of every hinge (None: the strip rows take every pair)."""
    if limits is None or not limits.active:
        return []
    top = pattern.topology
    tiles = top.tiles
    T, n = tiles.shape
    per_edge = np.repeat(np.arange(T), n)
    d = limits.shrink_mm / unit_mm
    out = []
    if limits.min_width_mm > 0:
        w = limits.min_width_mm / unit_mm
        out.append(Rows("fabrication_width", lambda x: F.width_rows(x, tiles, w, d), per_edge))
    if d > 0:
        e_min = max(limits.min_edge_mm, fab.EDGE_EPS_MM) / unit_mm
        out.append(
            Rows(
                "fabrication_shrunk_edges",
                lambda x: F.shrunk_edge_rows(x, tiles, d, e_min),
                per_edge,
            )
        )
    out += _hinge_rows(pattern, limits, unit_mm)
    if limits.strip_clearance_mm > 0:
        out += _strip_rows(pattern, limits, unit_mm, faces)
    if limits.strip_pad_mm2 > 0 and limits.strip_width_mm > 0 and top.n_hinges:
        ends = top.fold(limits.print_state).fold_corner_ends
        args = PR.pad_args(tiles, top.hinge_tiles, top.hinge_corner, ends)
        pad = PR.strip_pad(limits, unit_mm)
        owner = np.arange(len(args[0]))
        out.append(
            Rows(
                "fabrication_strip_pads",
                lambda x: PR.pad_rows(x, *args, *pad),
                owner,
                polys=args[0],
            )
        )
    if limits.min_hole_mm > 0 and len(top.hole_nodes):
        holes = F.ccw_polygons(top.hole_nodes, pattern.nodes)
        wh = limits.min_hole_mm / unit_mm
        owner = np.repeat(np.arange(len(holes)), holes.shape[1])
        out.append(Rows("fabrication_holes", lambda x: F.width_rows(x, holes, wh, 0.0), owner))
    return out


def _hinge_rows(pattern: Pattern, limits: F.FabricationLimits, unit_mm: float) -> list[Rows]:
    """Rows at the hinge corners: their angles, two of them on a tile apart, the edges that end at one."""
    top = pattern.topology
    tiles = top.tiles
    T, n = tiles.shape
    ht, hk = top.hinge_tiles.ravel(), top.hinge_corner.ravel()
    has = np.zeros((T, n), dtype=bool)
    has[ht, hk] = True
    out = []
    if limits.min_hinge_angle_deg > 0:
        s_min = float(np.sin(np.radians(limits.min_hinge_angle_deg)))
        out.append(
            Rows(
                "fabrication_hinge_angles",
                lambda x: F.hinge_angle_rows(x, tiles, ht, hk, s_min),
                ht,
                length=False,
            )
        )
    if limits.hinge_spacing_mm > 0:
        i, j = np.triu_indices(n, 1)
        t, p = np.nonzero(has[:, i] & has[:, j])
        s = limits.hinge_spacing_mm / unit_mm
        out.append(
            Rows(
                "fabrication_hinge_spacing",
                lambda x: F.spacing_rows(x, tiles, t, i[p], j[p], s),
                t,
            )
        )
    if limits.hinge_edge_mm > 0:
        k = np.arange(n)
        te, e = np.nonzero(has | has[:, (k + 1) % n])
        s_e = limits.hinge_edge_mm / unit_mm
        out.append(
            Rows(
                "fabrication_hinge_edges",
                lambda x: F.spacing_rows(x, tiles, te, e, (e + 1) % n, s_e),
                te,
            )
        )
    return out


def _strip_rows(
    pattern: Pattern, limits: F.FabricationLimits, unit_mm: float, faces: np.ndarray | None
) -> list[Rows]:
    """Strip clearance of every two hinge corners of a tile on one face (``faces`` None: every two)."""
    top = pattern.topology
    tiles = top.tiles
    face = np.zeros(len(top.hinge_tiles), np.int64) if faces is None else np.asarray(faces)
    t, h, sh, k, sk = fab.same_face_pairs(top.hinge_tiles, face, len(tiles))
    if not len(t):
        return []
    ends = top.fold(limits.print_state).fold_corner_ends
    hc = top.hinge_corner
    args = (t, hc[h, sh], ends[h, sh], hc[k, sk], ends[k, sk])
    box = F.strip_box(limits, unit_mm)
    return [Rows("fabrication_strip_clearance", lambda x: F.strip_rows(x, tiles, *args, box), t)]


def _polygons(pattern: Pattern, r: Rows) -> np.ndarray:
    """The node indices each row of ``r`` reads (its tile's, or its hole's)."""
    top = pattern.topology
    if r.polys is not None:
        return r.polys
    return top.hole_nodes if r.name == "fabrication_holes" else top.tiles


def families(
    pattern: Pattern,
    limits: F.FabricationLimits | None,
    unit_mm: float,
    margin: float = MARGIN,
    faces: np.ndarray | None = None,
    weight: float = WEIGHT,
    land: bool = LAND,
) -> list[Family]:
    """The rows of ``limits`` as soft one-sided families of the kagome fit: ``weight · min(g - margin, 0)``
    with the gradient where a row is active (normalised units, 1 = ``unit_mm``); ``land``: whether the
    landing on the family (``solve.land``) sees them too."""
    nv = pattern.topology.n_nodes
    out = []
    for r in rows(pattern, limits, unit_mm, faces):
        poly = _polygons(pattern, r)

        def fn(x, r=r, poly=poly):
            g = r.g(x)
            act = g.v < margin
            grads = weight * g.g.reshape(len(r.owner), poly.shape[1], 2) * act[:, None, None]
            return weight * np.where(act, g.v - margin, 0.0), (poly[r.owner], grads)

        def res(x, r=r):
            return weight * np.minimum(r.g(x).v - margin, 0.0)

        meta = {"land": land}
        out.append(Family(r.name, "ineq", fn, 1 if r.length else 0, meta=meta, nv=nv, res=res))
    return out


def measure(
    pattern: Pattern, limits: F.FabricationLimits | None, faces: np.ndarray | None = None
) -> dict:
    """Whether ``pattern`` (mm) meets ``limits``, on the rows themselves (no margin): per family its
    rows, how many are below zero and the smallest (mm, or a sine for the hinge angles), and the
    figures ``cut`` and ``print`` read: thinnest tile (unshrunk and shrunk) and smallest hinge angle."""
    x = pattern.nodes
    top = pattern.topology
    c = x[top.tiles]
    ht, hk = top.hinge_tiles.ravel(), top.hinge_corner.ravel()
    sines = F.hinge_angle_rows(x, top.tiles, ht, hk, 0.0).v
    v, a, b = (c[ht, (hk + s) % c.shape[1]] for s in (0, 1, -1))
    cosines = (
        ((a - v) * (b - v)).sum(1) / np.linalg.norm(a - v, axis=1) / np.linalg.norm(b - v, axis=1)
    )
    out: dict = {
        "thinnest_tile_mm": float(fab.widths(c).min()),
        "smallest_hinge_angle_deg": float(np.degrees(np.arccos(np.clip(cosines, -1, 1))).min()),
        "smallest_hinge_sine": float(sines.min()),
    }
    if limits is None or not limits.active:
        return out
    out["thinnest_shrunk_tile_mm"] = float(fab.widths(c, limits.shrink_mm).min())
    fams: dict = {}
    met = True
    for r in rows(pattern, limits, 1.0, faces):
        g = r.g(x).v
        slack = SLACK_MM if r.length else 0.0
        bad = int((g < -slack).sum())
        met &= bad == 0
        fams[r.name] = {"rows": int(len(g)), "violated": bad, "min": float(g.min())}
    out.update(limits=limits.to_dict(), families=fams, met=bool(met))
    return out
