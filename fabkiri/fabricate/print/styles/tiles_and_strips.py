"""The ``tiles-and-strips`` print style: rigid tiles joined by flexible strips, two materials."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
import shapely

from ....errors import FabricationError
from ....pattern.model import Pattern
from .. import geometry as printgeom
from ..build import PrintJob, Realised, StyleChecks, centre_shift, fits
from ..printers import Printer
from ..solid import SECTION_NOISE_MM, Body, Prism, manifold_of, section_polys, translate_body

if TYPE_CHECKING:
    from ..checks import MeshReport

LAYOUTS = ("recessed", "stacked")


def layer_top_above(z: float, printer: Printer) -> float:
    """Print height (top) of the first slicer layer lying above ``z``."""
    first, h = printer.first_layer_mm, printer.layer_mm
    if z < first - 1e-9:
        return first
    return first + (np.floor((z - first) / h + 1e-6) + 1) * h


def build(pattern: Pattern, state: int, printer: Printer, layout: str | None = None) -> PrintJob:
    """Rigid tiles joined by flexible strips, in one of two layouts:

    * ``recessed`` (two extruders): strips flush in pockets of the top and bottom
      faces, so both materials share the bottom and top ``strip_thickness`` layers;
    * ``stacked`` (one extruder, the default there): a flexible base sheet
      (every tile plus the bottom-face strips) ``strip_thickness`` thick, the
      rigid tiles on it, the top-face strips lying on the tiles. Each layer holds
      one material, so two colour changes (M600 at the first rigid layer and at
      the first top-strip layer) swap the filament.
    """
    layout = layout or ("recessed" if printer.extruders >= 2 else "stacked")
    if layout not in LAYOUTS:
        raise FabricationError(
            f"unknown tiles-and-strips layout {layout!r}; choose one of {', '.join(LAYOUTS)}"
        )
    plan = printgeom.closed_plan(pattern, state, printer)
    strips = printgeom.strip_outlines(plan, printer)
    T, ts = printer.tile_thickness_mm, printer.strip_thickness_mm
    fits(plan.bounds, printer, "the closed pattern")
    top = tuple(strips.outline[strips.top])
    bot = tuple(strips.outline[~strips.top])
    changes: list[tuple[float, str, str]] = []
    if layout == "recessed":
        tiles = Body(
            f"tiles_{printer.tile_material}",
            "tiles",
            (
                ("add", Prism(tuple(plan.tiles), 0.0, T)),
                (
                    "sub",
                    Prism(tuple(strips.pocket[strips.top]), T - ts, T + 1.0),
                ),  # +1: a clean cut through the face
                ("sub", Prism(tuple(strips.pocket[~strips.top]), -1.0, ts)),
            ),
            printer.tile_material,
        )
        hinges = Body(
            f"hinges_{printer.strip_material}",
            "hinges",
            (
                ("add", Prism(top, T - ts, T)),
                ("add", Prism(bot, 0.0, ts)),
            ),
            printer.strip_material,
        )
    else:
        base = shapely.simplify(shapely.union_all(list(plan.tiles) + list(bot)), printgeom.NOISE_MM)
        tiles = Body(
            f"tiles_{printer.tile_material}",
            "tiles",
            (("add", Prism(tuple(plan.tiles), ts, T)),),
            printer.tile_material,
        )
        hinges = Body(
            f"hinges_{printer.strip_material}",
            "hinges",
            (
                ("add", Prism(tuple(shapely.get_parts(base)), 0.0, ts)),
                ("add", Prism(top, T, T + ts)),
            ),
            printer.strip_material,
        )
        changes = [
            (float(layer_top_above(ts, printer)), "colour-change", printer.tile_material),
            (float(layer_top_above(T, printer)), "colour-change", printer.strip_material),
        ]
    dx, dy = centre_shift(plan.bounds, printer)
    beds = [[translate_body(tiles, dx, dy), translate_body(hinges, dx, dy)]]
    return PrintJob(
        "tiles-and-strips",
        state,
        printer,
        plan,
        beds,
        (dx, dy),
        strips=strips,
        layout=layout,
        layer_changes=changes,
    )


def clearances(r: Realised, rep: MeshReport) -> None:
    """Tiles-and-strips style: clearances measured on sections of the mesh."""
    job, pr = r.job, r.job.printer
    assert job.strips is not None  # a tiles-and-strips job always carries its strips
    # measured on the mesh: sections of both bodies at the bottom pocket, the
    # bare middle and the top pocket. Each section piece is attributed to
    # the tile or strip it belongs to; pieces of different tiles keep the
    # gap, a strip touches only the two tiles it joins and keeps the radial
    # clearance from everything else.
    tiles_m, hinges_m = r.manifolds[0]
    req = pr.radial_clearance_mm
    rep.required_clearance_mm = req
    shift = np.asarray(job.shift)
    design_t = shapely.transform(job.plan.tiles, lambda c: c + shift)
    design_s = shapely.transform(job.strips.outline, lambda c: c + shift)
    A, B = job.plan.hinge_tiles.T
    worst = np.inf
    lv = job.z_levels()
    zs: tuple[float, ...] = (lv["bottom"], lv["tiles"], lv["top"])
    if (
        job.layout == "stacked"
    ):  # the base sheet joins tiles by design: it must be the planned sheet
        zs = zs[1:]
        planned = shapely.union_all(list(design_t) + list(design_s[~job.strips.top]))
        got = shapely.union_all(section_polys(hinges_m, lv["bottom"]))
        diff = shapely.symmetric_difference(planned, got)
        # slivers thinner than the mesh's vertex noise are no deviation (a bound on their area failed
        # large sheets, whose outlines are long: docs/bad-input.md, hard56)
        if shapely.area(shapely.buffer(diff, -SECTION_NOISE_MM)) > 0:
            rep.problems.append(
                f"the base sheet deviates from its plan by {shapely.area(diff):.3g} mm²"
            )
    for z in zs:
        parts = section_polys(tiles_m, z)
        sparts = section_polys(hinges_m, z)
        allp = np.array(parts + sparts, dtype=object)
        kind = np.array([0] * len(parts) + [1] * len(sparts))
        owner = np.full(len(allp), -1)
        pts = shapely.point_on_surface(allp)
        for k, design in ((0, design_t), (1, design_s)):
            sel = np.flatnonzero(kind == k)
            qi, di = shapely.STRtree(design).query(pts[sel], predicate="dwithin", distance=1e-3)
            owner[sel[qi]] = di
        if (owner < 0).any():
            rep.problems.append(
                f"a section piece at z = {z:g} mm belongs to no planned tile or strip"
            )
        i, j = shapely.STRtree(allp).query(allp, predicate="dwithin", distance=2 * pr.gap_mm)
        sel = (i < j) & ~((kind[i] == kind[j]) & (owner[i] == owner[j]))  # same body: no clearance
        i, j = i[sel], j[sel]
        d = shapely.distance(allp[i], allp[j])
        mixed = kind[i] != kind[j]
        st_, tl = np.where(kind[i] == 1, i, j)[mixed], np.where(kind[i] == 1, j, i)[mixed]
        joined = np.zeros(len(i), dtype=bool)
        joined[mixed] = (owner[tl] == A[owner[st_]]) | (owner[tl] == B[owner[st_]])
        free = d[~joined]
        if len(free):
            worst = min(worst, float(free.min()))
    rep.min_clearance_mm = None if worst == np.inf else worst
    if rep.min_clearance_mm is not None and rep.min_clearance_mm < req - 1e-6:
        rep.problems.append(
            f"clearance {rep.min_clearance_mm:.3f} mm below the radial clearance {req:g} mm"
        )


def tiles(r: Realised, mesh=None):
    """The tile body (or ``mesh``, e.g. re-read from the STL), sectioned at its bare
    middle; nothing masked."""
    solid = manifold_of(mesh) if mesh is not None else r.manifolds[0][0]
    return solid, r.job.z_levels()["tiles"], None


def layout_checks(pattern: Pattern, r: Realised, rep: MeshReport) -> StyleChecks:
    """The layout verifier on the printed top faces; its reassembly into the other closed state is
    moot (listed as not applicable, and said once) for a pattern that closes one way only."""
    from ..topfaces import verify_printed_tiles  # lazy: the verifier's readers

    verifier = verify_printed_tiles(pattern, r)
    out = StyleChecks(verifier=verifier)
    moot = (
        []
        if r.job.plan.other_state_closes
        else [c.name for c in verifier.failed() if _reassembly(c.id)]
    )
    if moot:
        verifier.meta["not_applicable"] = moot
        out.notes.append(
            f"note: closed state {3 - r.job.state} does not close; the verifier's reassembly checks "
            "are moot"
        )
    out.problems += [
        f"verifier: {c.name} measured {c.value:.3g} {c.unit} (tolerance {c.tol:g})"
        for c in verifier.failed()
        if c.name not in moot
    ]
    return out


def _reassembly(check_id: str) -> bool:
    """Whether a layout-verifier check is one of (c), the cut tiles reassembled into a closed state
    (ids ``GROUP.reassembled.stateS.WHAT``)."""
    return ".reassembled.state" in check_id
