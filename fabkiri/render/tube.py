"""Pictures of a tube in 3D: one PNG per state and a GIF of the deployment with the sheet rolled.

A frame of a deployment path whose seam is not a pure translation (an elastic path between the
states) is rolled with the mean seam translation and says how far its seam is from closing.
"""

from __future__ import annotations

import io
from typing import TYPE_CHECKING

import numpy as np

from ..fabricate.tube.rolled import state_frame, surface_mesh, tube_seam
from ..mechanics.deploy import DeploymentPath
from ..mechanics.tube import TubeFrame, frame
from ..pattern.kinds.periodic.sheet import seam_map, tube_tiles
from ..pattern.model import Pattern
from .deployment import _gif_bytes, _pyplot

if TYPE_CHECKING:  # matplotlib is imported where a picture is drawn
    from mpl_toolkits.mplot3d import Axes3D


def _draw(
    ax: Axes3D, tiles: np.ndarray, f: TubeFrame, lim: float, title: str, even: np.ndarray
) -> None:
    from mpl_toolkits.mplot3d.art3d import Poly3DCollection

    mesh = surface_mesh(tiles, f, n=4)
    tri = mesh.vertices[mesh.faces]
    shade = 0.55 + 0.4 * np.abs(mesh.face_normals @ np.array([0.3, -0.6, 0.75]))
    colours = np.repeat(even, len(mesh.faces) // len(tiles))
    base = np.where(colours[:, None], [[0.25, 0.45, 0.75]], [[0.85, 0.55, 0.25]])
    ax.add_collection3d(Poly3DCollection(tri, facecolors=base * shade[:, None], edgecolors="none"))
    centre = mesh.vertices.mean(0)
    for i, c in enumerate(centre):
        getattr(ax, f"set_{'xyz'[i]}lim")(c - lim, c + lim)
    ax.set_box_aspect((1, 1, 1))
    ax.view_init(elev=18, azim=-60)
    ax.set_axis_off()
    ax.set_title(title, fontsize=9)


def _half_extent(meshes: list) -> float:
    return max(0.5 * float(np.ptp(m.vertices, axis=0).max()) for m in meshes) * 0.8


def _even(pattern: Pattern) -> np.ndarray:
    """Tile colour (fold parity) of the tube's tiles, in tube order."""
    return pattern.topology.even_tiles()[tube_tiles(pattern, tube_seam(pattern))]


def states_png(pattern: Pattern, copies: int = 1, dpi: int = 100) -> bytes:
    """Deployed and both closed states side by side, rolled onto their tubes, one scale."""
    plt = _pyplot()
    states: list[str | int] = ["deployed", *sorted(pattern.contracted)]
    rolled = [state_frame(pattern, s, copies) for s in states]
    lim = _half_extent([surface_mesh(t, f, n=2) for t, f in rolled])
    fig = plt.figure(figsize=(4.0 * len(states), 4.6), dpi=dpi)
    for i, (s, (tiles, f)) in enumerate(zip(states, rolled, strict=True)):
        ax = fig.add_subplot(1, len(states), i + 1, projection="3d")
        r = f.period / (2 * np.pi) if f.apex is None else None
        label = "deployed" if s == "deployed" else f"closed state {s}"
        _draw(
            ax,
            tiles,
            f,
            lim,
            f"{label}" + (f", radius {r:.3g} mm" if r else ", cone"),
            np.tile(_even(pattern), copies),
        )
    fig.suptitle(pattern.name or "tube", fontsize=10)
    buf = io.BytesIO()
    fig.savefig(buf, format="png", metadata={"Software": None})
    plt.close(fig)
    return buf.getvalue()


def _frame_of(corners: np.ndarray, pattern: Pattern) -> tuple[np.ndarray, TubeFrame, float]:
    seam = tube_seam(pattern)  # a flat sheet: one-line bad input, not an AttributeError on None
    m = seam_map(corners, seam)
    if (
        seam.closed == "cone"
    ):  # a rigid cone tube: every frame's seam turns alike, each frame is a cone
        return corners[tube_tiles(pattern, seam)], frame(corners, seam, 1), m.rigid_dev
    t = corners[seam.copy].reshape(-1, 2).mean(0) - corners[seam.first].reshape(-1, 2).mean(0)
    u = t / np.linalg.norm(t)
    f = TubeFrame(
        origin=corners[seam.first][:, 0].mean(0),
        u=u,
        v=np.array([-u[1], u[0]]),
        period=float(np.linalg.norm(t)),
    )
    return corners[tube_tiles(pattern, seam)], f, m.translation_dev


def _radius_text(tiles: np.ndarray, f: TubeFrame) -> str:
    """A cylinder's radius, or a cone's radius at its narrow and wide end (over the tile corners)."""
    if f.apex is None:
        return f"{f.period / (2 * np.pi):.3g}"
    rad = np.hypot(*f.roll(tiles.reshape(-1, 2))[:, :2].T)
    return f"{rad.min():.3g}..{rad.max():.3g}"


def deployment_gif_3d(
    pattern: Pattern, path: DeploymentPath, max_frames: int = 24, frame_ms: int = 120, dpi: int = 80
) -> bytes:
    """The deployment path, every frame rolled onto its tube (closed 1 -> deployed -> closed 2)."""
    from PIL import Image

    plt = _pyplot()
    idx = np.unique(
        np.linspace(0, path.n_frames - 1, min(max_frames, path.n_frames)).round().astype(int)
    )
    frames = [_frame_of(path.corners[k], pattern) for k in idx]
    lim = _half_extent([surface_mesh(t, f, n=2) for t, f, _ in frames])
    images = []
    for k, (tiles, f, dev) in zip(idx, frames, strict=True):
        fig = plt.figure(figsize=(4.2, 4.4), dpi=dpi)
        ax = fig.add_subplot(projection="3d")
        note = "" if dev <= 1e-6 * path.tile_size else f", seam open {dev:.2g} mm"
        _draw(
            ax,
            tiles,
            f,
            lim,
            f"t = {path.t[k]:+.2f}, radius {_radius_text(tiles, f)} mm{note}",
            _even(pattern),
        )
        buf = io.BytesIO()
        fig.savefig(buf, format="png", metadata={"Software": None})
        plt.close(fig)
        images.append(Image.open(io.BytesIO(buf.getvalue())).convert("RGB"))
    return _gif_bytes(images, frame_ms)
