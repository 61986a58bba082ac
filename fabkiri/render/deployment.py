"""E(t) plot and deployment GIF of a :class:`~fabkiri.mechanics.deploy.DeploymentPath`.

Both are deterministic bytes (no timestamps in the metadata). The GIF reuses
one figure and updates its collections frame by frame, so a 32×32 pattern
renders in a few seconds.
"""

from __future__ import annotations

import io
from types import ModuleType
from typing import TYPE_CHECKING, cast

import numpy as np

from ..mechanics.deploy import MARKS, DeploymentPath

if TYPE_CHECKING:  # matplotlib is imported where a picture is drawn
    from matplotlib.axes import Axes
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.collections import PolyCollection
    from matplotlib.colors import Colormap, Normalize
    from matplotlib.figure import Figure
    from PIL import Image

ZERO_ENERGY = 1e-12  # below this the path is reported as zero-energy


def _pyplot():
    import matplotlib

    matplotlib.use("Agg", force=True)
    import matplotlib.pyplot as plt

    return plt


def _energy_axes(
    ax: Axes, path: DeploymentPath, lo: float, hi: float, marks: bool = True, anchor: float = 0.0
) -> None:
    """E(t) on [lo, hi], plotted against ``t - anchor`` (a zoom next to t = 1 reads "t - 1", not "1e-9+1")."""
    sel = (path.t >= lo - 1e-12) & (path.t <= hi + 1e-12)
    t, e, emax = path.t[sel] - anchor, path.energy[sel], path.max_tile_energy[sel]
    ax.plot(t, e, "-o", ms=2.5, lw=1.5, color="C0", label="total energy E")
    ax.plot(t, emax, "-", lw=1.0, color="C3", label="largest tile energy")
    top = float(max(e.max(initial=0.0), emax.max(initial=0.0)))
    if top <= ZERO_ENERGY:
        ax.set_ylim(-0.05 * ZERO_ENERGY, ZERO_ENERGY)
    else:
        ax.set_ylim(-0.03 * top, 1.12 * top)
    for a, b in path.elastic_segments:
        ax.axvspan(a - anchor, b - anchor, color="C1", alpha=0.12, lw=0)
    if marks:
        for tm in MARKS.values():
            if lo - 1e-12 <= tm <= hi + 1e-12:
                ax.axvline(tm - anchor, color="0.4", lw=0.8, ls="--")
    pad = 0.02 * (hi - lo)
    ax.set_xlim(lo - anchor - pad, hi - anchor + pad)
    ax.ticklabel_format(axis="y", style="sci", scilimits=(-2, 3), useOffset=False)
    ax.ticklabel_format(axis="x", style="sci", scilimits=(-3, 3), useOffset=False)
    ax.xaxis.set_major_locator(_ticker().MaxNLocator(4))


def _ticker():
    import matplotlib.ticker as ticker

    return ticker


def energy_plot_png(path: DeploymentPath, title: str = "", dpi: int = 110) -> bytes:
    """PNG of E(t) and the largest tile energy, closed and deployed states marked.

    An elastic path whose barriers sit in narrow end segments (shaded: where
    the tiles leave the design's zero-energy mechanism to close up) gets two
    zoomed panels on those segments under the full path.
    """
    plt = _pyplot()
    segs = path.elastic_segments
    zoom = bool(segs) and max(b - a for a, b in segs) < 0.15
    if zoom:
        fig = plt.figure(figsize=(6.4, 5.6), dpi=dpi)
        gs = fig.add_gridspec(2, len(segs), height_ratios=[1.35, 1])
        ax = fig.add_subplot(gs[0, :])
    else:
        fig, ax = plt.subplots(figsize=(6.4, 3.8), dpi=dpi)
    _energy_axes(ax, path, 0.0, 1.0)
    top = float(max(path.energy.max(), path.max_tile_energy.max()))
    if top <= ZERO_ENERGY:
        ax.text(
            0.25,
            0.72,
            f"zero-energy path: max E = {top:.1e}",
            transform=ax.transAxes,
            ha="center",
            fontsize=10,
            color="C2",
            bbox=dict(facecolor="white", edgecolor="none"),
        )
    for name, tm in MARKS.items():
        right = tm > 0.75  # keep the last label inside the axes
        ax.text(
            tm - 0.008 if right else tm + 0.008,
            0.5,
            name,
            transform=ax.get_xaxis_transform(),
            ha="right" if right else "left",
            va="center",
            rotation=90,
            fontsize=8,
            color="0.3",
        )
    ax.set_xlabel("path parameter t")
    ax.set_ylabel("spring energy  Σ((l - l₀)/l₀)²")
    kind = "rigid path" if path.kind == "rigid" else f"elastic path, driver: {path.driver}"
    ax.set_title((f"{title} — " if title else "") + kind, fontsize=10)
    ax.legend(fontsize=8, loc="upper center", frameon=False)
    if zoom:
        for k, (a, b) in enumerate(segs):
            sub = fig.add_subplot(gs[1, k])
            first = a <= 0.0
            _energy_axes(sub, path, a, b, anchor=0.0 if first else 1.0)
            near = "closed state 1" if first else "closed state 2"
            sub.set_title(f"barrier next to {near}", fontsize=8)
            sub.set_xlabel("t" if first else "t - 1", fontsize=8)
            sub.tick_params(labelsize=7)
            sub.yaxis.get_offset_text().set_fontsize(7)
    fig.tight_layout()
    buf = io.BytesIO()
    fig.savefig(buf, format="png", metadata={"Software": None})
    plt.close(fig)
    return buf.getvalue()


def _state_label(t: float, marks: dict[str, int], ts: np.ndarray, f: int) -> str:
    """ "closed state 1" / "deployed" / "closed state 2" on their frames, else where the motion goes."""
    for name, k in marks.items():
        if k == f:
            return name
    return "closed state 1 → deployed" if t < ts[marks["deployed"]] else "deployed → closed state 2"


def _scale_bar(ax: Axes, lo: np.ndarray, hi: np.ndarray, pad: float) -> None:
    """A round length in mm under the lower left of the drawing."""
    span = float(hi[0] - lo[0])
    L = next((v for v in (1, 2, 5, 10, 20, 50, 100, 200, 500, 1000) if v >= span / 5), 1000)
    x0, y0 = lo[0], lo[1] - 0.6 * pad
    ax.plot([x0, x0 + L], [y0, y0], color="k", lw=3, solid_capstyle="butt", clip_on=False)
    ax.text(x0 + L + 0.01 * span, y0, f"{L:g} mm", va="center", fontsize=11, clip_on=False)


def _frame_indices(n: int, max_frames: int) -> np.ndarray:
    if n <= max_frames:
        return np.arange(n)
    return np.unique(np.round(np.linspace(0, n - 1, max_frames)).astype(int))


def _colouring(
    path: DeploymentPath, color: str, plt: ModuleType
) -> tuple[np.ndarray, Normalize, Colormap, str, bool]:
    """The per-frame tile values and how they are coloured, for ``color``
    (``"energy"``, ``"rotation"`` or ``"auto"``): ``(values, norm, cmap,
    label, flat)``; ``flat`` when the energy is noise everywhere."""
    from matplotlib import colors as mcolors

    if color == "auto":
        color = "rotation" if path.kind == "rigid" else "energy"
    if color not in ("energy", "rotation"):
        raise ValueError(f"color must be energy, rotation or auto, not {color!r}")
    flat = (
        color == "energy" and float(path.tile_energy.max()) <= ZERO_ENERGY
    )  # noise: colours would mean nothing
    if flat:
        values = np.zeros_like(path.tile_energy)
        norm = mcolors.Normalize(vmin=-1.0, vmax=1.0)
        cmap = plt.get_cmap("Greys")
        label = ""
    elif color == "energy":
        values = path.tile_energy
        vmax = max(float(values.max()), ZERO_ENERGY * 10)
        norm = mcolors.LogNorm(vmin=max(vmax * 1e-6, ZERO_ENERGY), vmax=vmax, clip=True)
        cmap = plt.get_cmap("viridis")
        label = "tile energy e"
    else:
        values = path.rotation
        norm = mcolors.Normalize(vmin=-np.pi / 2, vmax=np.pi / 2)
        cmap = plt.get_cmap("coolwarm")
        label = "rotation θ from state 1 (rad)"
    return values, norm, cmap, label, flat


def _gif_bytes(images: list, frame_ms: int) -> bytes:
    """The frames as one looping GIF."""
    from PIL import Image

    # one shared palette keeps colours steady and the file small
    palette = images[len(images) // 2].quantize(colors=64, method=Image.Quantize.MEDIANCUT)
    frames = [im.quantize(palette=palette, dither=Image.Dither.NONE) for im in images]
    buf = io.BytesIO()
    frames[0].save(
        buf,
        format="GIF",
        save_all=True,
        append_images=frames[1:],
        duration=frame_ms,
        loop=0,
        optimize=False,
        disposal=1,
    )
    return buf.getvalue()


def deployment_gif(
    path: DeploymentPath,
    color: str = "auto",
    *,
    max_frames: int = 61,
    size_px: int = 840,
    frame_ms: int = 80,
    trajectories: bool = True,
    title: str = "",
) -> bytes:
    """Animated GIF of the motion.

    ``color``: ``"energy"`` (tile energy, log scale), ``"rotation"`` (signed
    rotation from state 1, common rotation removed) or ``"auto"`` (rotation for
    the rigid path, energy otherwise). Tile-centre trajectories are drawn up to
    the current frame, the current centre as a dot. At most ``max_frames``
    evenly spaced frames are drawn.
    """
    plt = _pyplot()
    from matplotlib.collections import LineCollection, PolyCollection

    values, norm, cmap, label, flat = _colouring(path, color, plt)
    idx = _frame_indices(path.n_frames, max_frames)
    corners, centres = path.corners, path.centres

    dpi = 100
    fig = plt.figure(figsize=(size_px / dpi, size_px / dpi * 1.08), dpi=dpi)
    ax = fig.add_axes([0.02, 0.16, 0.96, 0.76])
    cax = fig.add_axes([0.2, 0.09, 0.6, 0.022])
    lo = corners.reshape(-1, 2).min(0)
    hi = corners.reshape(-1, 2).max(0)
    pad = 0.03 * float((hi - lo).max())
    ax.set_xlim(lo[0] - pad, hi[0] + pad)
    ax.set_ylim(lo[1] - pad, hi[1] + pad)
    ax.set_aspect("equal")
    ax.axis("off")
    tiles = PolyCollection(corners[0], cmap=cmap, norm=norm, edgecolors="k", linewidths=0.3)
    tiles.set_array(np.asarray(values[0], dtype=float))
    ax.add_collection(tiles)
    _colour_legend(fig, cax, tiles, path, label, flat)
    _scale_bar(ax, lo, hi, pad)
    lines = dots = None
    if trajectories:
        lines = LineCollection([], colors="k", linewidths=0.5)
        ax.add_collection(lines)
        dots = ax.scatter(centres[0, :, 0], centres[0, :, 1], s=2, c="k", zorder=3)
    head = ax.set_title("", fontsize=12)
    state = ax.text(
        0.02, 0.98, "", transform=ax.transAxes, ha="left", va="top", fontsize=15, weight="bold"
    )
    marks = path.mark_frames()
    # what a frame changes is drawn over the rest, drawn once (the legend's and the scale's text was most of
    # a frame's drawing); in the full draw's order (by z-order, then as added), so the pixels are the same
    moving = [a for a in (tiles, lines, dots, state, head) if a is not None]
    for a in moving:
        a.set_animated(True)
    fig.canvas.draw()
    still = (cast("FigureCanvasAgg", fig.canvas).copy_from_bbox(fig.bbox), moving)

    images = [
        _draw_frame(fig, path, f, values, (tiles, lines, dots, head, state), marks, title, still)
        for f in idx
    ]
    plt.close(fig)
    return _gif_bytes(images, frame_ms)


def _colour_legend(
    fig: Figure, cax: Axes, tiles: PolyCollection, path: DeploymentPath, label: str, flat: bool
) -> None:
    """The colour bar under the animation, or a note when the tile energy is noise everywhere."""
    if flat:
        cax.axis("off")
        cax.text(
            0.5,
            0.5,
            f"tile energy below noise everywhere (max {path.tile_energy.max():.1e} <= "
            f"{ZERO_ENERGY:g}): no energy colours",
            ha="center",
            va="center",
            fontsize=10,
        )
    else:
        cb = fig.colorbar(tiles, cax=cax, orientation="horizontal")
        cb.set_label(label, fontsize=10)
        cb.ax.tick_params(labelsize=9)


def _draw_frame(
    fig: Figure,
    path: DeploymentPath,
    f: int,
    values: np.ndarray,
    artists: tuple,
    marks: dict[str, int],
    title: str,
    still: tuple[object, list],
) -> Image.Image:
    """Frame ``f`` drawn into the figure's artists ``(tiles, lines, dots, head, state)`` over ``still`` (the
    figure drawn without them, and those of them drawn, in draw order), as an image."""
    from PIL import Image

    tiles, lines, dots, head, state = artists
    tiles.set_verts(path.corners[f])
    tiles.set_array(np.asarray(values[f], dtype=float))
    if lines is not None and dots is not None:  # set exactly when trajectories are drawn
        lines.set_segments(list(np.swapaxes(path.centres[: f + 1], 0, 1)) if f > 0 else [])
        dots.set_offsets(path.centres[f])
    head.set_text(f"{title + '   ' if title else ''}t = {path.t[f]:.3f}   E = {path.energy[f]:.2e}")
    state.set_text(_state_label(path.t[f], marks, path.t, f))
    canvas = cast("FigureCanvasAgg", fig.canvas)
    backdrop, moving = still
    canvas.restore_region(backdrop)
    for a in moving:
        fig.draw_artist(a)
    rgb = np.asarray(canvas.buffer_rgba())[..., :3]  # _pyplot draws with Agg
    return Image.fromarray(np.ascontiguousarray(rgb))
