"""Histograms of a tolerance run (:mod:`fabkiri.mechanics.tolerance`), PNG bytes."""

from __future__ import annotations

import io
from typing import TYPE_CHECKING

import numpy as np

from ..mechanics.tolerance import ToleranceResult
from .deployment import _pyplot

if TYPE_CHECKING:  # matplotlib is imported where a picture is drawn
    from matplotlib.axes import Axes


def _hist(ax: Axes, series: dict[str, np.ndarray], xlabel: str, title: str) -> None:
    for k, (name, v) in enumerate(series.items()):
        ax.hist(v, bins=40, histtype="step", lw=1.4, color=f"C{k}", label=name)
        ax.axvline(np.percentile(v, 95), color=f"C{k}", lw=0.8, ls="--")
    ax.set_xlabel(xlabel, fontsize=8)
    ax.set_ylabel("samples", fontsize=8)
    ax.set_title(title, fontsize=9)
    ax.tick_params(labelsize=7)
    ax.ticklabel_format(axis="both", style="plain", useOffset=False)
    ax.legend(fontsize=7, frameon=False)


def tolerance_png(res: ToleranceResult, title: str = "", dpi: int = 110) -> bytes:
    """Four panels: closure gap, seam gap, largest overlap, deployed outline error (dashed: 95th percentile)."""
    plt = _pyplot()
    fig, axes = plt.subplots(2, 2, figsize=(9, 6.4), dpi=dpi)
    _hist(
        axes[0, 0],
        res.gap,
        "largest hinge gap (mm)",
        "closure gap: pivot copies apart after assembly",
    )
    _hist(
        axes[0, 1], res.seam_gap, "widest seam opening (mm)", "seam gap: edges meant to lie flush"
    )
    _hist(
        axes[1, 0],
        res.overlap_max,
        "largest overlap along a seam (mm²)",
        "overlap in the closed states",
    )
    _hist(
        axes[1, 1],
        {"deployed": res.outline},
        "outline error (mm)",
        "deployed outline vs the design outline",
    )
    fig.suptitle(
        f"{title + ': ' if title else ''}{res.n} samples, kerf sd {res.kerf_sd_mm:g} mm, "
        f"hinge sd {res.hinge_sd_mm:g} mm, tile {res.tile_size_mm:.3g} mm (dashed: 95th percentile)",
        fontsize=10,
    )
    fig.tight_layout()
    buf = io.BytesIO()
    fig.savefig(buf, format="png", metadata={"Software": None})
    plt.close(fig)
    return buf.getvalue()
