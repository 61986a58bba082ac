"""Preview PNG of a print bed: the bed outline, every part in its material's
colour, seen from the top and from below, with millimetre axes (matplotlib).

Each view paints the sections of the solids at the middle of every slab
between the bodies' prism heights, lowest first for the top view (what lies
higher hides what lies lower) and highest first for the bottom view, which is
mirrored left-right as seen from under the bed.
"""

from __future__ import annotations

import io

import numpy as np

from .printers import MATERIALS


def _heights(body) -> list[float]:
    zs = sorted({z for _, pr in body.ops for z in (pr.z0, pr.z1)})
    return [0.5 * (a + b) for a, b in zip(zs, zs[1:])]


def _layers(bed, manifolds) -> list[tuple[float, str, list[np.ndarray]]]:
    out = []
    for body, m in zip(bed, manifolds):
        lo, hi = m.bounding_box()[2], m.bounding_box()[5]
        for z in _heights(body):
            if lo < z < hi:
                rings = [np.asarray(r) for r in m.slice(z).to_polygons() if len(r) >= 3]
                out.append((z, body.material, rings))
    return sorted(out, key=lambda t: t[0])


def preview_png(bed, manifolds, printer, title: str) -> bytes:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.collections import PolyCollection
    from matplotlib.patches import Patch, Rectangle

    bx, by, _ = printer.bed_mm
    layers = _layers(bed, manifolds)
    fig, axes = plt.subplots(1, 2, figsize=(12, 6.2), dpi=110)
    for ax, view in zip(axes, ("top", "bottom")):
        ax.add_patch(Rectangle((0, 0), bx, by, facecolor="#f4f4f4", edgecolor="black", linewidth=1.0))
        order = layers if view == "top" else layers[::-1]
        for _, mat, rings in order:
            colour = MATERIALS[mat].colour if mat in MATERIALS else "#808080"
            # only outer rings (counter-clockwise) are filled; holes are left to the layers below
            outer = [r for r in rings if _signed_area(r) > 0]
            if view == "bottom":
                outer = [np.column_stack([bx - r[:, 0], r[:, 1]]) for r in outer]
            ax.add_collection(PolyCollection(outer, facecolors=colour, edgecolors="#333333", linewidths=0.2))
        ax.set_xlim(-0.02 * bx, 1.02 * bx)
        ax.set_ylim(-0.02 * by, 1.02 * by)
        ax.set_aspect("equal")
        ax.set_xlabel("x (mm)" + (", mirrored" if view == "bottom" else ""))
        ax.set_ylabel("y (mm)")
        ax.set_title(f"{view} view")
        ax.grid(True, linewidth=0.3, alpha=0.5)
    mats = sorted({b.material for b in bed})
    handles = [Patch(facecolor=MATERIALS[m].colour if m in MATERIALS else "#808080",
                     label=f"{m} (extruder {printer.extruder_of(m)})") for m in mats]
    fig.legend(handles=handles, loc="lower center", ncol=len(handles))
    fig.suptitle(f"{title}: printer {printer.name}, bed {bx:g} x {by:g} mm")
    out = io.BytesIO()
    fig.savefig(out, format="png", metadata={"Software": None})
    plt.close(fig)
    return out.getvalue()


def _signed_area(r: np.ndarray) -> float:
    x, y = r[:, 0], r[:, 1]
    return 0.5 * float(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1)))
