"""FOLD 1.2 (https://github.com/edemaine/fold, doc/spec.md) export and import.

A kirigami pattern is a FOLD mesh whose faces (tiles) share vertices (hinges)
but no edges: every tile edge borders a cut or the outside, so every edge is a
border edge ``"B"``. The key frame (frame 0) is the deployed state; frames 1
and 2 (``file_frames[0]`` and ``[1]``) are closed states 1 and 2, inheriting the
mesh and overriding ``vertices_coords`` only. In a closed state several
vertices lie at one point; each keeps its own index. Coordinates in mm
(``frame_unit``).
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np

from .. import __version__, limits
from ..errors import PatternError
from ..pattern import geometry
from ..pattern.kinds.tessellation import kind_of_arity
from ..pattern.model import Pattern
from .file_formats import PatternFormat, register_format

FILE_SPEC = 1.2
STATE_KEY = "fabkiri:state"  # custom frame property (a colon marks it as ours, per the spec)


def _edges(tiles: np.ndarray) -> np.ndarray:
    """``(nT, 2)`` tile edges in tile order, each CCW along its tile."""
    return np.stack([tiles, np.roll(tiles, -1, axis=1)], -1).reshape(-1, 2)


def fold_dict(pattern: Pattern) -> dict[str, Any]:
    """The FOLD object of a pattern with its stored closed states as frames."""
    tiles = pattern.tiles
    edges = _edges(tiles)
    out: dict[str, Any] = {
        "file_spec": FILE_SPEC,
        "file_creator": f"fabkiri {__version__}",
        "file_title": pattern.name or "fabkiri pattern",
        "file_classes": ["singleModel"],
        "frame_title": "deployed",
        "frame_classes": ["creasePattern"],
        "frame_attributes": ["2D", "noCuts"],
        "frame_unit": "mm",
        STATE_KEY: "deployed",
        "vertices_coords": pattern.nodes.tolist(),
        "edges_vertices": edges.tolist(),
        "edges_assignment": ["B"] * len(edges),
        "edges_faces": [[int(f)] for f in np.repeat(np.arange(len(tiles)), tiles.shape[1])],
        "faces_vertices": tiles.tolist(),
    }
    frames = []
    for s in sorted(pattern.contracted):
        frames.append(
            {
                "frame_title": f"closed state {s}",
                "frame_classes": ["fabkiri:contracted"],
                "frame_attributes": ["2D", "selfTouching"],
                "frame_unit": "mm",
                "frame_parent": 0,
                "frame_inherit": True,
                STATE_KEY: s,
                "vertices_coords": pattern.node_positions(s).tolist(),
            }
        )
    if frames:
        out["file_frames"] = frames
    return out


def _value(v: Any, indent: str) -> str:
    """JSON of one property: a list of rows one row per line, anything else compact."""
    if isinstance(v, list) and v and isinstance(v[0], list):
        return "[\n" + ",\n".join(f"{indent}  {json.dumps(r)}" for r in v) + f"\n{indent}]"
    if isinstance(v, list) and v and isinstance(v[0], dict):
        return (
            "[\n" + ",\n".join(f"{indent}  {_object(r, indent + '  ')}" for r in v) + f"\n{indent}]"
        )
    return json.dumps(v)


def _object(d: dict, indent: str = "") -> str:
    body = ",\n".join(f"{indent} {json.dumps(k)}: {_value(v, indent + ' ')}" for k, v in d.items())
    return "{\n" + body + f"\n{indent}}}"


def fold_text(pattern: Pattern) -> str:
    """FOLD JSON text, one row of each long array per line (deterministic bytes)."""
    return _object(fold_dict(pattern)) + "\n"


# mm per FOLD ``frame_unit`` (the spec's list); "unit" or none: unitless, ``--scale`` gives the mm
UNITS_MM = {
    "unit": None,
    "mm": 1.0,
    "cm": 10.0,
    "m": 1000.0,
    "in": 25.4,
    "pt": 25.4 / 72,
    "um": 1e-3,
    "nm": 1e-6,
}


def _array(data: dict, key: str, source: str, width: int | None = None) -> np.ndarray:
    if key not in data:
        raise PatternError(f"{source}: no {key} (a fabkiri pattern needs vertices and faces)")
    try:
        a = np.asarray(data[key])
    except (TypeError, ValueError):
        a = np.asarray(None)
    rows = data[key] if isinstance(data[key], list) else []
    flags = any(isinstance(v, bool) for r in rows if isinstance(r, list) for v in r)
    if a.dtype.kind not in "iuf" or flags:  # strings, true/false, nulls, ragged rows: not numbers
        raise PatternError(f"{source}: {key} is not a rectangular array of numbers")
    if a.ndim != 2 or (width is not None and a.shape[1] != width):
        raise PatternError(
            f"{source}: {key} must have {width} entries per row, got shape {a.shape}"
        )
    return a.astype(float)


def pattern_from_fold(data: Any, source: str = "fold") -> Pattern:
    """A pattern from a FOLD object: key frame deployed, frames tagged with a closed state stored.

    Frames without our state tag are read as closed states 1, 2 in order when
    they are 2D and inherit the mesh (a folded 3D form of another tool is no closed state). The faces'
    arity names the kind (quads, kagome triangles); z must be 0. Faces listed clockwise overall are
    reversed, as OBJ import does.
    """
    if not isinstance(data, dict):
        raise PatternError(f"{source}: expected a FOLD JSON object")
    _refuse_folded_key_frame(data, source)
    coords = _array(data, "vertices_coords", source)
    if coords.shape[1] == 3:
        if np.abs(coords[:, 2]).max(initial=0.0) > 0:
            raise PatternError(f"{source}: vertices have z != 0; patterns are planar")
        coords = coords[:, :2]
    elif coords.shape[1] != 2:
        raise PatternError(f"{source}: vertices_coords must be [x, y] or [x, y, z]")
    faces = _array(data, "faces_vertices", source)
    kind = kind_of_arity(faces.shape[1])
    if kind is None:
        raise PatternError(
            f"{source}: faces_vertices must have 4 entries per row (quads) or 3 "
            f"(kagome triangles), got shape {faces.shape}"
        )
    tiles = faces.astype(np.int64)
    if (
        not np.array_equal(tiles, faces)
        or tiles.min(initial=0) < 0
        or tiles.max(initial=0) >= len(coords)
    ):
        raise PatternError(f"{source}: faces_vertices must be vertex indices 0..{len(coords) - 1}")
    if geometry.signed_areas(coords[tiles]).sum() < 0:
        tiles = tiles[:, ::-1]
    return Pattern(
        nodes=coords,
        tiles=tiles,
        contracted=_closed_frames(data, tiles, len(coords), source),
        kind=kind,
        name=str(data.get("file_title", "")) or source,
        design={"source": {"fold": source, "file_creator": data.get("file_creator")}},
    )


def _refuse_folded_key_frame(data: dict, source: str) -> None:
    """A key frame classed ``foldedForm`` (and not ``creasePattern``) is a folded state, not the flat
    cut pattern read as the deployed state: refused, naming a frame classed as the flat pattern."""
    classes = _classes(data)
    if "foldedForm" not in classes or "creasePattern" in classes:
        return
    frames = data.get("file_frames") or []
    flat = [
        k
        for k, f in enumerate(frames if isinstance(frames, list) else [], 1)
        if "creasePattern" in _classes(f)
    ]
    hint = f"; its frame {flat[0]} is a creasePattern: make that the key frame" if flat else ""
    raise PatternError(
        f"{source}: the key frame is a foldedForm (a folded state), not the flat pattern fabkiri "
        f"reads as the deployed state{hint}"
    )


def _classes(frame: Any) -> list:
    """A frame's ``frame_classes`` (nothing for a malformed one)."""
    got = frame.get("frame_classes") if isinstance(frame, dict) else None
    return got if isinstance(got, list) else []


def _closed_frames(data: dict, tiles: np.ndarray, n: int, source: str) -> dict[int, np.ndarray]:
    """The closed states among ``file_frames``: tagged ones, then untagged 2D frames on the same mesh."""
    contracted: dict[int, np.ndarray] = {}
    untagged = 0
    for k, frame in enumerate(data.get("file_frames", []) or [], 1):
        if not isinstance(frame, dict) or "vertices_coords" not in frame:
            continue
        if STATE_KEY not in frame:
            own = frame.get("faces_vertices")
            if "3D" in (frame.get("frame_attributes") or []) or (
                own is not None and not np.array_equal(np.asarray(own), data["faces_vertices"])
            ):
                continue
            untagged += 1
        state = _state_tag(frame, untagged, f"{source} frame {k}")
        if state not in (1, 2) or state in contracted:
            continue
        xyz = _array(frame, "vertices_coords", f"{source} frame {k}")
        if len(xyz) != n:
            raise PatternError(f"{source} frame {k}: {len(xyz)} vertices, the key frame has {n}")
        if xyz.shape[1] > 2 and np.abs(xyz[:, 2:]).max(initial=0.0) > 0:
            if STATE_KEY in frame:
                raise PatternError(f"{source} frame {k}: closed state {state} has z != 0")
            untagged -= 1  # a folded form: no closed state
            continue
        contracted[int(state)] = xyz[:, :2][tiles]
    return contracted


def _state_tag(frame: dict, untagged: int, where: str) -> int | str:
    """A frame's closed state: its tag (1, 2, also written "1", "2"; "deployed" is the key frame's) or,
    untagged, ``untagged``; any other tag is refused rather than the frame skipped."""
    tag = frame.get(STATE_KEY, untagged)
    if tag in ("1", "2"):
        return int(tag)
    if tag == "deployed" or (type(tag) is int and tag in (1, 2)) or STATE_KEY not in frame:
        return tag
    raise PatternError(
        f"{where}: {STATE_KEY} is {json.dumps(tag)}; expected 1 or 2 (a closed state)"
    )


def _unit_mm(data: Any, scale: float, source: str) -> float:
    """mm per file coordinate: the key frame's ``frame_unit``, or ``scale`` for a unitless file."""
    unit = data.get("frame_unit", "unit") if isinstance(data, dict) else "unit"
    if unit not in UNITS_MM:
        raise PatternError(
            f"{source}: unknown frame_unit {unit!r} (FOLD units: {', '.join(UNITS_MM)})"
        )
    mm = UNITS_MM[unit]
    if mm is None:
        return scale
    if scale != 1.0:
        raise PatternError(
            f"{source}: its frame_unit is {unit!r}; --scale is for files without a unit"
        )
    return mm


def loads_fold(text: str, source: str = "fold", scale: float = 1.0) -> Pattern:
    """A FOLD file's pattern in mm (its ``frame_unit``, or ``scale`` mm per unit when it has none)."""
    from ..limits import loads_json  # depth, integer and float bounds, as pattern.json

    data = loads_json(text, source, PatternError)
    mm = _unit_mm(data, scale, source)
    pat = pattern_from_fold(data, source)
    if mm != 1.0:
        pat = Pattern(
            nodes=pat.nodes * mm,
            tiles=pat.tiles,
            contracted={k: v * mm for k, v in pat.contracted.items()},
            kind=pat.kind,
            name=pat.name,
            design=pat.design,
        )
    return pat


def _read_fold(path: Path, scale: float) -> Pattern:
    """A ``.fold`` file in mm: its ``frame_unit``, or ``scale`` mm per file unit."""
    from .pattern_json import _read_text

    return limits.check_pattern(loads_fold(_read_text(path), str(path), scale), str(path))


def _fold_said(pattern: Pattern, state: str, output: str, unit: float | None) -> str:
    return (
        f"wrote {output}: FOLD 1.2, frames deployed / closed 1 / closed 2, {pattern.n_tiles} faces"
    )


register_format(
    PatternFormat(
        "fold",
        (".fold",),
        read=_read_fold,
        write=lambda pattern, state, unit: fold_text(pattern),
        closed_states=lambda state: (1, 2),
        every_state=True,
        said=_fold_said,
    )
)
