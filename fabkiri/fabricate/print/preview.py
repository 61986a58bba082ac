"""Preview PNG of a print bed: the bed outline, every part in its material's
colour, seen from the top and from below, with millimetre axes (matplotlib).

Each view paints, per body, the section at the middle of its slab nearest
the face seen (slabs lie between the body's prism heights), lowest first for
the top view (what lies higher hides what lies lower) and highest first for
the bottom view, which is mirrored left-right as seen from under the bed.
"""

from __future__ import annotations

import io

import numpy as np

from .printers import MATERIALS


def _heights(body) -> list[float]:
    zs = sorted({z for _, pr in body.ops for z in (pr.z0, pr.z1)})
    return [0.5 * (a + b) for a, b in zip(zs, zs[1:])]


def _layers(bed, manifolds, view: str) -> list[tuple[float, str, list]]:
    """Per body, the slab section nearest the face seen (the top one for the top
    view) as polygons with their holes, in painting order."""
    from .solid import section_polys

    out = []
    for body, m in zip(bed, manifolds):
        lo, hi = m.bounding_box()[2], m.bounding_box()[5]
        zs = [z for z in _heights(body) if lo < z < hi]
        for z in (zs[-1:] if view == "top" else zs[:1]) if zs else []:
            out.append((z, body.material, section_polys(m, z)))
    out.sort(key=lambda t: t[0])
    return out if view == "top" else out[::-1]


def _path(poly, mirror_x: float | None):
    from matplotlib.path import Path

    rings = [np.asarray(poly.exterior.coords)] + [np.asarray(r.coords) for r in poly.interiors]
    if mirror_x is not None:
        rings = [np.column_stack([mirror_x - r[:, 0], r[:, 1]]) for r in rings]
    return Path.make_compound_path(*[Path(r, closed=True) for r in rings])


def preview_png(bed, manifolds, printer, title: str) -> bytes:
    # a bare Figure on the Agg canvas: pyplot (its figure manager and backend set-up) is not needed
    from matplotlib.collections import PathCollection
    from matplotlib.figure import Figure
    from matplotlib.patches import Patch, Rectangle

    bx, by, _ = printer.bed_mm
    fig = Figure(figsize=(12, 6.2), dpi=110)
    axes = fig.subplots(1, 2)
    for ax, view in zip(axes, ("top", "bottom")):
        ax.add_patch(
            Rectangle((0, 0), bx, by, facecolor="#f4f4f4", edgecolor="black", linewidth=1.0)
        )
        for _, mat, polys in _layers(bed, manifolds, view):
            colour = MATERIALS[mat].colour if mat in MATERIALS else "#808080"
            paths = [_path(p, bx if view == "bottom" else None) for p in polys]  # holes stay open
            ax.add_collection(
                PathCollection(paths, facecolors=colour, edgecolors="#333333", linewidths=0.2)
            )
        ax.set_xlim(-0.02 * bx, 1.02 * bx)
        ax.set_ylim(-0.02 * by, 1.02 * by)
        ax.set_aspect("equal")
        ax.set_xlabel("x (mm)" + (", mirrored" if view == "bottom" else ""))
        ax.set_ylabel("y (mm)")
        ax.set_title(f"{view} view")
        ax.grid(True, linewidth=0.3, alpha=0.5)
    mats = sorted({b.material for b in bed})
    handles = [
        Patch(
            facecolor=MATERIALS[m].colour if m in MATERIALS else "#808080",
            label=f"{m} (extruder {printer.extruder_of(m)})",
        )
        for m in mats
    ]
    fig.legend(handles=handles, loc="lower center", ncol=len(handles))
    fig.suptitle(f"{title}: printer {printer.name}, bed {bx:g} x {by:g} mm")
    out = io.BytesIO()
    fig.savefig(out, format="png", metadata={"Software": None})
    return out.getvalue()
