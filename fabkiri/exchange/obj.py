"""Wavefront OBJ pattern files: read (a design and its contracted states) and written (one state).

OBJ files are the design/contracted triples written by other kirigami tools:
``v x y z`` and ``f a// b// c// d//`` lines, 1-based, identical face lists
across a set. Every reader raises :class:`~fabkiri.errors.PatternError` with a
one-line message naming the file and the problem. Registered as the pattern
format ``obj`` (:mod:`.file_formats`).
"""

from __future__ import annotations

import math
import os
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from .. import limits
from ..errors import PatternError
from ..fileio import atomic_write
from ..pattern import geometry
from ..pattern.kinds.tessellation import DEFAULT_KIND, kind_of_arity
from ..pattern.model import Pattern
from .file_formats import PatternFormat, register_format
from .pattern_json import _read_text

# OBJ faces of the kinds other than quads, for the one-line error
_OTHER_TILES = " or kagome triangles"


def parse_obj(text: str, source: str = "obj") -> tuple[np.ndarray, np.ndarray]:
    """Vertices ``(n, 2)`` and 0-based faces ``(T, n)`` of an OBJ text: quads, or the tiles of
    another kind (kagome triangles), all faces of one kind."""
    verts, faces, _ = _parse(text, source)
    return verts, faces


def _parse(text: str, source: str) -> tuple[np.ndarray, np.ndarray, str]:
    """:func:`parse_obj`'s vertices and faces, and the file's up axis (``z``, or ``y``: see :func:`_plane`)."""
    verts: list[tuple[float, ...]] = []
    lines: list[int] = []
    faces: list[list[int]] = []
    for lineno, raw in enumerate(text.splitlines(), 1):
        line = raw.split("#", 1)[0].strip()
        if not line:
            continue
        tag, *rest = line.split()
        if tag == "v":
            verts.append(_obj_vertex(rest, f"{source}: line {lineno}"))
            lines.append(lineno)
        elif tag == "f":
            face = _obj_face(rest, f"{source}: line {lineno}", faces[0] if faces else None)
            # a negative index counts back from the last vertex so far (the OBJ spec)
            faces.append([i if i >= 0 else len(verts) + 1 + i for i in face])
        # other records (vn, vt, o, g, s, usemtl, ...) carry nothing a pattern needs
    if not verts:
        raise PatternError(f"{source}: no vertices (empty or not an OBJ file)")
    if not faces:
        raise PatternError(f"{source}: no faces")
    f = np.asarray(faces, dtype=np.int64)
    bad = (f < 1) | (f > len(verts))
    if bad.any():
        i = int(np.flatnonzero(bad.any(1))[0])
        raise PatternError(
            f"{source}: face {i} references vertex {int(f[i][bad[i]][0])}, "
            f"but the file has vertices 1..{len(verts)}"
        )
    xy, up = _plane(np.asarray(verts, dtype=float), lines, source)
    return xy, f - 1, up


def _plane(v: np.ndarray, lines: list[int], source: str) -> tuple[np.ndarray, str]:
    """The pattern plane of vertices ``v`` ``(n, 3)``: ``x, y`` when every z is 0; ``x, -z`` when every y
    is 0 (Blender's default OBJ export, Y up, turns its ground plane x, y into x, -z); else refused."""
    if not v[:, 2].any():
        return v[:, :2], "z"
    if not v[:, 1].any():
        return np.column_stack([v[:, 0], -v[:, 2]]), "y"
    i = int(np.flatnonzero(v[:, 2])[0])
    raise PatternError(
        f"{source}: line {lines[i]}: vertex has z = {v[i, 2]:g}; patterns are planar: every z = 0 "
        "(or every y = 0, a Y-up export)"
    )


def _obj_vertex(rest: list[str], where: str) -> tuple[float, ...]:
    """``x, y, z`` of an OBJ ``v`` record (z 0 when not given)."""
    try:
        vals = [float(t) for t in rest[:3]]
    except ValueError:
        raise PatternError(f"{where}: vertex coordinates are not numbers") from None
    if len(vals) < 2:
        raise PatternError(f"{where}: a vertex needs at least x and y")
    if not all(math.isfinite(v) for v in vals):
        raise PatternError(f"{where}: non-finite vertex coordinate")
    return (*vals, 0.0)[:3]


def _obj_face(rest: list[str], where: str, first: list[int] | None) -> list[int]:
    """The 1-based vertex indices of an OBJ ``f`` record, of the same arity as the ``first`` face."""
    idx = []
    for tok in rest:
        try:
            idx.append(int(tok.split("/", 1)[0]))
        except ValueError:
            raise PatternError(f"{where}: face index {tok!r} is not an integer") from None
    if kind_of_arity(len(idx)) is None or (first is not None and len(idx) != len(first)):
        raise PatternError(
            f"{where}: face has {len(idx)} vertices; tiles must be quads"
            f"{_OTHER_TILES} and all of one kind"
        )
    if any(abs(i) > limits.MAX_INT for i in idx):
        raise PatternError(f"{where}: face index beyond ±2**53")
    return idx


def read_obj(path: str | os.PathLike) -> tuple[np.ndarray, np.ndarray]:
    verts, faces, _ = _read(path)
    return verts, faces


def _read(path: str | os.PathLike) -> tuple[np.ndarray, np.ndarray, str]:
    return _parse(_read_text(path), str(path))


def import_obj(
    design: str | os.PathLike,
    contracted: Sequence[str | os.PathLike] = (),
    *,
    scale: float = 1.0,
    name: str | None = None,
) -> Pattern:
    """A pattern from an OBJ design file and optionally its contracted files.

    ``scale`` is millimetres per OBJ unit. Tiles listed clockwise overall are
    reversed. The contracted files are stored as states 1 and 2 in the given
    order; :func:`fabkiri.mechanics.contract.adopt_state_labels` then picks the
    fold parity that makes the computed states agree with those labels.
    """
    if not math.isfinite(scale) or scale <= 0:
        raise PatternError(f"scale must be a positive number of mm per OBJ unit, got {scale}")
    if len(contracted) > 2:
        raise PatternError(f"at most two contracted files (states 1 and 2), got {len(contracted)}")
    verts, faces, up = _read(design)
    flip = geometry.signed_areas(verts[faces]).sum() < 0
    if flip:
        faces = faces[:, ::-1]
    states: dict[int, np.ndarray] = {}
    for i, path in enumerate(contracted, 1):
        cv, cf, _ = _read(path)
        if flip:
            cf = cf[:, ::-1]
        if cf.shape != faces.shape or not np.array_equal(cf, faces):
            raise PatternError(f"{path}: its face list differs from the design's ({design})")
        if len(cv) != len(verts):
            raise PatternError(f"{path}: has {len(cv)} vertices, the design has {len(verts)}")
        states[i] = cv[faces] * scale
    problem = limits.coordinate_problem(verts * scale, faces, states)
    if problem:
        raise PatternError(f"{design}: {problem}")
    return Pattern(
        nodes=verts * scale,
        tiles=faces,
        kind=kind_of_arity(faces.shape[1]) or DEFAULT_KIND,
        contracted=states,
        name=name if name is not None else Path(design).stem,
        design={
            "source": {
                "design": Path(design).name,
                "contracted": [Path(p).name for p in contracted],
                "scale_mm_per_unit": scale,
                "reversed_tiles": bool(flip),
                **({"up_axis": "y (read x, -z as x, y)"} if up == "y" else {}),
            }
        },
    )


def obj_text(pattern: Pattern, state: str | int = "deployed", scale: float = 1.0) -> str:
    """OBJ of one state with the pattern's node indexing and face list.

    Closed states repeat coordinates for nodes that coincide there. ``scale``
    divides the mm coordinates (1 writes millimetres).
    """
    xy = pattern.node_positions(state) / scale
    lines = [f"# {len(xy)} vertices, {pattern.n_tiles} faces"]
    lines += [f"v {x!r} {y!r} 0.0" for x, y in xy.tolist()]
    lines += ["f " + " ".join(f"{i + 1}//" for i in tile) for tile in pattern.tiles.tolist()]
    return "\n".join(lines) + "\n"


def write_obj(pattern: Pattern, path: str | os.PathLike, state: str | int = "deployed") -> Path:
    return atomic_write(path, obj_text(pattern, state))


def _obj_states(state: str) -> tuple[int, ...]:
    return () if state == "deployed" else (int(state),)


def _obj_said(pattern: Pattern, state: str, output: str, unit: float | None) -> str:
    return f"wrote {output}: state {state}, {pattern.n_tiles} faces"


register_format(
    PatternFormat(
        "obj",
        (".obj",),
        read=lambda path, scale: import_obj(path, scale=scale),
        write=lambda pattern, state, unit: obj_text(pattern, state),
        closed_states=_obj_states,
        said=_obj_said,
    )
)
