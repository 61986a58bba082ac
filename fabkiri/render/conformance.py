"""Design preview: the tiles over their targets, the Hausdorff distance drawn where it is worst.

One panel for the deployed state over ``--target`` and one per closed state with an outline target
(the closed tiles placed on the target as :mod:`fabkiri.design.conformance` measured them). Deterministic
PNG bytes (no timestamps in the metadata).
"""

from __future__ import annotations

import io

import numpy as np

from ..design.conformance import target_polygon
from ..design.targets import target_from_dict
from ..pattern.model import Pattern
from .deployment import _pyplot


def _panels(pattern: Pattern, conformance: dict):
    """``(key, title, tiles (T, 4, 2), target polygon)`` per measured outline."""
    d = pattern.design or {}
    out = []
    if "deployed" in conformance and isinstance(d.get("target"), dict):
        out.append(("deployed", "deployed", pattern.corners(), target_polygon(target_from_dict(d["target"]))))
    for key, c in conformance.items():
        if not key.startswith("state_"):
            continue
        s = int(key.split("_")[1])
        tgt = (d.get("contracted_targets") or {}).get(str(s))
        if tgt is None or s not in pattern.contracted:
            continue
        pl = c.get("placement") or {}
        th = float(pl.get("rotation_rad", 0.0))
        R = np.array([[np.cos(th), -np.sin(th)], [np.sin(th), np.cos(th)]])
        tiles = pattern.contracted[s] @ R.T + np.asarray(pl.get("shift_mm", [0.0, 0.0]))
        out.append((key, f"closed state {s}", tiles, target_polygon(target_from_dict(tgt))))
    return out


def conformance_png(pattern: Pattern, conformance: dict, shape: dict | None = None, dpi: int = 110) -> bytes:
    """PNG of every measured outline: tiles (grey), target (blue), worst Hausdorff gap (red)."""
    from matplotlib.collections import PolyCollection

    plt = _pyplot()
    shape = shape or {}
    panels = _panels(pattern, conformance)
    n = max(1, len(panels))
    fig, axes = plt.subplots(1, n, figsize=(5.2 * n, 5.6), squeeze=False)
    for ax, (key, title, tiles, poly) in zip(axes[0], panels):
        c = conformance[key]
        ax.add_collection(PolyCollection(tiles, facecolors="0.82", edgecolors="0.35", linewidths=0.3))
        ring = np.vstack([poly, poly[:1]])
        ax.plot(ring[:, 0], ring[:, 1], "-", color="C0", lw=1.4, label="target")
        if key == "deployed":
            order = _tip_order(pattern)
            tips = pattern.nodes[order]
            loop = np.vstack([tips, tips[:1]])
            ax.plot(loop[:, 0], loop[:, 1], "-", color="C1", lw=0.9, label="tip polygon")
            ax.plot(tips[:, 0], tips[:, 1], ".", color="C1", ms=3)
        w = c["worst"]
        a, b = np.asarray(w["at"]), np.asarray(w["nearest"])
        ax.plot([a[0], b[0]], [a[1], b[1]], "-", color="C3", lw=2.2)
        ax.plot(*a, "o", mfc="none", mec="C3", ms=14, mew=1.6, label=f"worst: {c['hausdorff_mm']:.3g} mm")
        j = shape.get(key) or {}
        verdict = f", {j['status']} (tol {j['tol_mm']:.3g} mm)" if j else ""
        ax.set_title(f"{title}: Hausdorff {c['hausdorff_mm']:.3g} mm ({100 * c['hausdorff_rel']:.2f} %)"
                     f"{verdict}\n1-IoU {c['one_minus_iou']:.3g}, spacing min/mean "
                     f"{c['spacing_min_mm']:.3g}/{c['spacing_mean_mm']:.3g} mm", fontsize=9)
        pts = np.vstack([tiles.reshape(-1, 2), poly])
        lo, hi = pts.min(0), pts.max(0)
        pad = 0.04 * float((hi - lo).max())
        ax.set_xlim(lo[0] - pad, hi[0] + pad)
        ax.set_ylim(lo[1] - pad, hi[1] + pad)
        ax.set_aspect("equal")
        ax.legend(loc="best", fontsize=7, framealpha=0.8)
        ax.tick_params(labelsize=7)
        ax.set_xlabel("mm", fontsize=7)
    if not panels:
        axes[0, 0].set_axis_off()
        axes[0, 0].text(0.5, 0.5, "no target curve", ha="center", va="center")
    fig.suptitle(pattern.name or "design", fontsize=10)
    fig.tight_layout()
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=dpi, metadata={"Software": None})
    plt.close(fig)
    return buf.getvalue()


def _tip_order(pattern: Pattern) -> np.ndarray:
    from ..pattern.conformance import boundary_tip_order

    top = pattern.topology
    return boundary_tip_order(top.tiles, top.hole_nodes, top.hole_tiles, top.free_nodes)
