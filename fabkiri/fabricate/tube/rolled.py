"""A tube's states in 3D: the sheet rolled onto its cylinder (or cone), as OBJ and as thin-plate STL.

Each tile of the tube (the seam copy column left out) is rolled isometrically
(:class:`fabkiri.mechanics.tube.TubeFrame`): its edges are subdivided so the bent tile follows the
surface. For the STL every tile becomes a closed plate: the rolled tile as its inner face, the same
tile on the surface ``thickness`` further out as its outer face, and side walls between them
(trimesh, one watertight body per tile). ``copies`` repeats the tube's columns around the
circumference ``k`` times: the multi-copy assembly of the paper's Fig. 5C, a tube ``k`` periods round.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import trimesh

from ...errors import InputError, Param
from ...mechanics.tube import TubeFrame, frame
from ...pattern.kinds.periodic.sheet import Seam, seam_map, seam_of, tube_tiles
from ...pattern.model import Pattern

SUBDIV = 6  # points per tile edge: a rolled 10 mm tile on a 12 mm radius bends visibly


def tube_seam(pattern: Pattern) -> Seam:
    """The tube's seam; a flat sheet (no seam) is bad input, said in one line."""
    seam = seam_of(pattern)
    if seam is None:
        raise InputError(
            "the pattern has no seam: it is a flat sheet, not a tube (make one with --tube)"
        )
    return seam


def state_frame(
    pattern: Pattern, state: str | int, copies: int = 1
) -> tuple[np.ndarray, TubeFrame]:
    """Per-tile corners of the tube's tiles (``copies`` periods side by side) and the frame to roll them."""
    if int(copies) != copies or copies < 1:
        raise InputError(Param("copies"), f" must be a whole number >= 1, got {copies}")
    seam = tube_seam(pattern)
    Y = pattern.corners(state)
    f = frame(Y, seam, state)
    tiles = Y[tube_tiles(pattern, seam)]
    if copies == 1:
        return tiles, f
    if f.apex is not None:
        raise InputError(
            "copies of a cone-shaped state are not a tube: use a state that is a cylinder"
        )
    t = seam_map(Y, seam).translation
    tiles = np.concatenate([tiles + j * t for j in range(copies)])
    return tiles, replace(f, period=f.period * copies)


def _tile_grid(quad: np.ndarray, n: int) -> np.ndarray:
    """``(n, n, 2)`` bilinear grid over a quad (corners BL, BR, TR, TL)."""
    s = np.linspace(0.0, 1.0, n)
    u, v = np.meshgrid(s, s, indexing="xy")
    a, b, c, d = quad
    return (
        ((1 - u) * (1 - v))[..., None] * a
        + (u * (1 - v))[..., None] * b
        + (u * v)[..., None] * c
        + ((1 - u) * v)[..., None] * d
    )


def _grid_faces(n: int, base: int = 0) -> np.ndarray:
    i, j = np.meshgrid(np.arange(n - 1), np.arange(n - 1), indexing="ij")
    a = base + i * n + j
    return np.concatenate(
        [
            np.stack([a, a + 1, a + n + 1], -1).reshape(-1, 3),
            np.stack([a, a + n + 1, a + n], -1).reshape(-1, 3),
        ]
    )


def surface_mesh(tiles: np.ndarray, f: TubeFrame, n: int = SUBDIV) -> trimesh.Trimesh:
    """The rolled tiles as one surface mesh (each tile an ``n x n`` grid), mm."""
    verts, faces = [], []
    for k, quad in enumerate(tiles):
        verts.append(f.roll(_tile_grid(quad, n).reshape(-1, 2)))
        faces.append(_grid_faces(n, k * n * n))
    return trimesh.Trimesh(np.concatenate(verts), np.concatenate(faces), process=False)


def _outward(f: TubeFrame, pts3: np.ndarray) -> np.ndarray:
    """Unit surface normals pointing away from the axis."""
    if f.apex is None:
        nrm = pts3.copy()
        nrm[:, 2] = 0.0
    else:  # a cone's normal tilts towards the apex end by the half angle
        k = abs(f.alpha) / (2 * np.pi)
        r = np.hypot(pts3[:, 0], pts3[:, 1])
        nrm = np.stack(
            [
                pts3[:, 0] / r * np.sqrt(1 - k * k),
                pts3[:, 1] / r * np.sqrt(1 - k * k),
                -np.full(len(r), k),
            ],
            -1,
        )
    return nrm / np.linalg.norm(nrm, axis=1, keepdims=True)


def plate_meshes(
    tiles: np.ndarray, f: TubeFrame, thickness: float, n: int = SUBDIV
) -> list[trimesh.Trimesh]:
    """One watertight plate per tile: inner face on the surface, outer face ``thickness`` outwards."""
    if not np.isfinite(thickness) or thickness <= 0:
        raise InputError(f"plate thickness must be a positive length in mm, got {thickness}")
    grid_faces = _grid_faces(n)
    ring = np.concatenate(
        [
            np.arange(n - 1),
            np.arange(n - 1, n * n - 1, n),
            np.arange(n * n - 1, n * n - n, -1),
            np.arange(n * n - n, 0, -n),
        ]
    )
    # a wall quad is fanned about its centre: two neighbours sharing an edge then mesh their common wall
    # alike (a diagonal splits it one way for one tile and the other way for the other; on a cone, where
    # the quad is not planar, the plates would then interpenetrate by slivers of ~1e-5 of a plate)
    a, b = ring, np.roll(ring, -1)
    m = 2 * n * n + np.arange(len(ring))
    walls = np.concatenate(
        [
            np.stack([a, b, m], -1),
            np.stack([b, b + n * n, m], -1),
            np.stack([b + n * n, a + n * n, m], -1),
            np.stack([a + n * n, a, m], -1),
        ]
    )
    out = []
    for quad in tiles:
        inner = f.roll(_tile_grid(quad, n).reshape(-1, 2))
        outer = inner + thickness * _outward(f, inner)
        centre = 0.25 * (inner[a] + inner[b] + outer[a] + outer[b])
        faces = np.concatenate([grid_faces[:, ::-1], grid_faces + n * n, walls])
        mesh = trimesh.Trimesh(np.concatenate([inner, outer, centre]), faces, process=True)
        if mesh.volume < 0:
            mesh.invert()
        out.append(mesh)
    return out


def obj_bytes(mesh: trimesh.Trimesh) -> bytes:
    return trimesh.exchange.obj.export_obj(mesh, include_normals=False).encode()


def stl_bytes(plates: list[trimesh.Trimesh]) -> bytes:
    both = trimesh.util.concatenate(plates)  # a Trimesh; trimesh annotates it as a Geometry
    return both.export(file_type="stl")  # type: ignore[call-arg]  # Geometry's export needs a file


def plate_overlap(plates: list[trimesh.Trimesh]) -> tuple[float, tuple[int, int] | None]:
    """Largest intersection volume of two plates, as a share of the smaller plate, and the pair.

    Candidates are pairs whose bounding boxes meet; each intersection is a manifold3d boolean. Plates
    that only touch (neighbours in a closed state) intersect in round-off (~1e-15)."""
    import manifold3d as m3

    # double precision: float32 vertices turn the shared walls of a cone's neighbours into slivers (~1e-8)
    bodies = [
        m3.Manifold(
            m3.Mesh64(
                vert_properties=np.asarray(p.vertices, np.float64),
                tri_verts=np.asarray(p.faces, np.uint64),
            )
        )
        for p in plates
    ]
    lo = np.array([p.bounds[0] for p in plates])
    hi = np.array([p.bounds[1] for p in plates])
    vol = np.array([p.volume for p in plates])
    meet = np.all(lo[:, None] <= hi[None], -1) & np.all(lo[None] <= hi[:, None], -1)
    worst, pair = 0.0, None
    for i, j in zip(*np.nonzero(np.triu(meet, 1)), strict=True):
        share = (bodies[i] ^ bodies[j]).volume() / min(vol[i], vol[j])
        if share > worst:
            worst, pair = float(share), (int(i), int(j))
    return worst, pair
