"""``pattern.json``, fabkiri's own pattern file: read and written.

The file is validated against the JSON Schema shipped beside this module
(``pattern.schema.json``), then against the model's own consistency rules; the
writer gives deterministic bytes for the same pattern. Every reader raises
:class:`~fabkiri.errors.PatternError` with a one-line message naming the file
and the problem. Registered as the pattern format ``json``
(:mod:`.file_formats`).
"""

from __future__ import annotations

import json
import math
import os
from pathlib import Path
from typing import Any

import numpy as np

from .. import limits
from ..errors import PatternError
from ..fileio import atomic_write, read_input
from ..pattern.kinds.tessellation import DEFAULT_KIND, Tessellation, tessellation
from ..pattern.model import Pattern
from ..schemas import load_schema, schema_problem
from ..schemas import short as _short
from .file_formats import PatternFormat, register_format

FORMAT = "fabkiri.pattern"
VERSION = 1


# ---------------------------------------------------------------- pattern.json


def schema() -> dict[str, Any]:
    """The JSON Schema of pattern.json version 1."""
    return load_schema(__package__, "pattern.schema.json")


def _schema_error(data: Any) -> str | None:
    return schema_problem(data, schema())


_BULK = ("nodes", "tiles")


def _skeleton(data: dict) -> dict:
    """The document with its bulk arrays cut to a few rows.

    jsonschema walks every number (slow for a large pattern); the schema
    checks the structure on a few rows and :func:`_array_error` checks every
    row with a fast scan.
    """
    out = dict(data)
    for key in _BULK:
        if isinstance(out.get(key), list):
            out[key] = out[key][:4]
    if isinstance(out.get("contracted"), dict):
        out["contracted"] = {
            k: (v[:4] if isinstance(v, list) else v) for k, v in out["contracted"].items()
        }
    return out


def _is_num(v: Any) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool)


def _array_error(data: dict, tess: Tessellation) -> str | None:
    """Row-by-row shape and type check of the bulk arrays (what the schema says; the kind's tile arity)."""
    n = tess.arity
    for i, row in enumerate(data["nodes"]):
        if not (isinstance(row, list) and len(row) == 2 and _is_num(row[0]) and _is_num(row[1])):
            return f"nodes/{i}: {_short(row)} is not an [x, y] pair of numbers"
    for i, row in enumerate(data["tiles"]):
        if not (
            isinstance(row, list)
            and len(row) == n
            and all(isinstance(v, int) and not isinstance(v, bool) and v >= 0 for v in row)
        ):
            return f"tiles/{i}: {_short(row)} is not a {tess.tile_noun} of {n} node indices"
    for key, rows in data.get("contracted", {}).items():
        for i, tile in enumerate(rows):
            if not (
                isinstance(tile, list)
                and len(tile) == n
                and all(
                    isinstance(c, list) and len(c) == 2 and _is_num(c[0]) and _is_num(c[1])
                    for c in tile
                )
            ):
                return f"contracted/{key}/{i}: {_short(tile)} is not {n} corners [x, y]"
    return None


def pattern_from_dict(data: Any, source: str = "pattern") -> Pattern:
    """Build a :class:`Pattern` from parsed ``pattern.json`` content."""
    if not isinstance(data, dict):
        raise PatternError(f"{source}: expected a JSON object, got {type(data).__name__}")
    if data.get("format") != FORMAT:
        raise PatternError(
            f"{source}: not a fabkiri pattern (format is {_short(data.get('format'))}, "
            f"expected {FORMAT!r})"
        )
    if data.get("version") != VERSION:
        raise PatternError(
            f"{source}: unsupported pattern version {_short(data.get('version'))} "
            f"(this fabkiri reads version {VERSION})"
        )
    problem = _schema_error(_skeleton(data))
    if problem:
        raise PatternError(f"{source}: {problem}")
    try:
        tess = tessellation(str(data.get("kind", DEFAULT_KIND)))
    except PatternError as exc:
        raise PatternError(f"{source}: {exc}") from None
    problem = _array_error(data, tess)
    if problem:
        raise PatternError(f"{source}: {problem}")
    nodes = np.asarray(data["nodes"], dtype=float)
    tiles = np.asarray(data["tiles"], dtype=np.int64)
    contracted = {int(k): np.asarray(v, dtype=float) for k, v in data.get("contracted", {}).items()}
    if tiles.size and int(tiles.max()) >= len(nodes):
        t = int(np.flatnonzero((tiles >= len(nodes)).any(1))[0])
        raise PatternError(
            f"{source}: tile {t} references node {int(tiles[t].max())}, outside the "
            f"{len(nodes)} nodes"
        )
    problem = limits.coordinate_problem(nodes, tiles, contracted)
    if problem:
        raise PatternError(f"{source}: {problem}")
    try:
        return Pattern(
            nodes=nodes,
            tiles=tiles,
            contracted=contracted,
            parity=int(data.get("parity", 0)),
            name=str(data.get("name", "")),
            lattice=data.get("lattice"),
            design=data.get("design"),
            kind=tess.kind,
        )
    except PatternError as exc:
        raise PatternError(f"{source}: {exc}") from None


def loads(text: str, source: str = "pattern") -> Pattern:
    if not text.strip():
        raise PatternError(f"{source}: the file is empty")
    data = limits.loads_json(text, source, PatternError)
    return pattern_from_dict(data, source)


def read_pattern(path: str | os.PathLike) -> Pattern:
    """Read ``pattern.json`` (validated); raises :class:`PatternError`."""
    text = _read_text(path)
    return loads(text, str(path))


def jsonable(value: Any) -> Any:
    """``value`` with numpy arrays, scalars and tuples made plain JSON values (non-finite floats None)."""
    # most values are floats (coordinates): the float branch's answer, asked first
    if type(value) is float:
        return value if math.isfinite(value) else None
    if isinstance(value, dict):
        return {str(k): jsonable(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [jsonable(v) for v in value]
    if isinstance(value, np.ndarray):
        return jsonable(value.tolist())
    if isinstance(value, (np.integer,)):
        return int(value)
    if isinstance(value, (np.floating, float)):
        v = float(value)
        return v if math.isfinite(v) else None  # JSON has no NaN; None says "not measured"
    if isinstance(value, np.bool_):
        return bool(value)
    return value


# one encoder for every row: json.dumps with non-default separators builds a new one per call (a third
# of writing a 128x128 design); the same class and options, so the same text
_ROW = json.JSONEncoder(separators=(", ", ": "))


def _rows(arr: np.ndarray, indent: str) -> str:
    """A JSON array with one compact row per line (diff-friendly, deterministic)."""
    if not len(arr):
        return "[]"
    sep = f",\n{indent}  "
    if arr.ndim >= 2 and arr.size:
        # one encode of the whole array, split between its rows (where ``k - 1`` brackets close and open: a
        # row itself nests less deep): the same text as one encode per row, at half its cost
        k = arr.ndim - 1
        inner = _ROW.encode(arr.tolist())[1:-1].replace(
            "]" * k + ", " + "[" * k, "]" * k + sep + "[" * k
        )
    else:
        inner = sep.join(_ROW.encode(r) for r in arr.tolist())
    return f"[\n{indent}  {inner}\n{indent}]"


def dumps(pattern: Pattern) -> str:
    """``pattern.json`` text: deterministic bytes for the same pattern."""
    head: dict[str, Any] = {"format": FORMAT, "version": VERSION, "units": "mm"}
    if pattern.name:
        head["name"] = pattern.name
    if pattern.kind != DEFAULT_KIND:  # absent means quad: files from before kinds read the same
        head["kind"] = pattern.kind
    head["parity"] = pattern.parity
    parts = [f'  "{k}": {json.dumps(v)}' for k, v in head.items()]
    if pattern.lattice:
        parts.append(f'  "lattice": {json.dumps(jsonable(pattern.lattice), sort_keys=True)}')
    parts.append(f'  "nodes": {_rows(pattern.nodes, "  ")}')
    parts.append(f'  "tiles": {_rows(pattern.tiles, "  ")}')
    if pattern.contracted:
        states = [
            f'    "{s}": {_rows(np.asarray(pattern.contracted[s]), "    ")}'
            for s in sorted(pattern.contracted)
        ]
        parts.append('  "contracted": {\n' + ",\n".join(states) + "\n  }")
    if pattern.design:
        design = json.dumps(jsonable(pattern.design), indent=2, sort_keys=True).replace(
            "\n", "\n  "
        )
        parts.append(f'  "design": {design}')
    return "{\n" + ",\n".join(parts) + "\n}\n"


def write_pattern(pattern: Pattern, path: str | os.PathLike) -> Path:
    return atomic_write(path, dumps(pattern))


def _read_text(path: str | os.PathLike) -> str:
    """A pattern file's text (any text format: JSON, OBJ, PyKirigami), size- and cost-checked."""
    limits.check_read_cost(path, error=PatternError)  # its parse alone takes ~21x the file
    return read_input(
        path, max_bytes=limits.MAX_PATTERN_BYTES, what="pattern file", error=PatternError
    )


def _read_json(path: Path, scale: float) -> Pattern:
    if scale != 1.0:
        raise PatternError(
            f"{path}: pattern.json is in mm already; --scale is for OBJ, FOLD and PyKirigami files"
        )
    return read_pattern(path)


register_format(PatternFormat("json", (".json",), read=_read_json, adopt_labels=False))
