"""Bounds on what fabkiri accepts, checked before any work starts.

Input that would exhaust the machine or overflow the numerics is refused with a
one-line :class:`~fabkiri.errors.InputError` that names the figure: tile
counts past the largest size measured (with the extrapolated memory and time),
files past a size bound, JSON nested too deep, integers past 2**53, numbers
that are not finite, coordinates past a kilometre, tiles with coinciding
corners. The figures in :data:`MEASURED` come from ``bench/limits.py``.
"""

from __future__ import annotations

import json
import math
import os
import re
from dataclasses import dataclass

import numpy as np

from .errors import CheckFailed, InputError, Param

MAX_PATTERN_BYTES = (
    256 * 2**20
)  # pattern.json / OBJ / target files (a 128x128 pattern is a few megabytes)
MAX_PRESET_BYTES = 2**20  # material and printer presets are a few hundred bytes
MAX_JSON_DEPTH = 64  # pattern.json nests 6 deep (design reports a few more)
MAX_INT = (
    2**53
)  # beyond it a JSON integer is no longer exact as a float (and overflows C long at 2**63)
MAX_COORD_MM = (
    1e6  # a kilometre: larger coordinates are a unit mistake, and their squares overflow sooner
)
MIN_EDGE_REL = (
    1e-9  # a tile edge shorter than this fraction of the pattern's extent is two coinciding corners
)
MAX_LENGTH_MM = 1e5  # a length parameter (tile size, target size): 100 m
MIN_LENGTH_MM = (
    1e-3  # ... and at least a micrometre: below it shapely's snapping and the tolerances break
)

# (tiles, CPU seconds, peak MB above the interpreter) per command, measured by bench/limits.py on this 2-core
# box at load 7-20 (CPU time: wall time was 3-15x more). The 64x64 full design is a lower bound: that run was
# stopped unfinished (LM still at rho=1e4, iteration 180).
MEASURED = {
    "new": [[65536, 3.9, 190.3], [262144, 19.8, 802.7]],
    "design full": [[256, 1.8, 56.3], [1024, 7.9, 72.8], [4096, 458.0, 270.0]],
    "design rigid": [[4096, 6.7, 116.9], [16384, 46.4, 750.4]],
    "design kagome": [
        [36, 12.5, 30.8],
        [64, 18.7, 31.7],
        [100, 29.2, 38.0],
        [252, 84.3, 34.0],  # the 12x21 heart at 240 mm (docs/kagome.md), load 9-13
    ],  # rows x cols, load 14-20
    "design tube": [[64, 3.7, 24.0], [144, 9.3, 25.7]],  # rows x cols around, at load 12-14
    # per byte of pattern.json (``new`` patterns, 474 bytes a tile): `info`, its JSON parse the peak
    # (21x the file); and per tile copy (tiles x --copies) of `export --format tube3d` (a 4x6 tube).
    # Both from /usr/bin/time at load 12-23, MB less what the command needs for a tiny input.
    "read pattern": [[7759585, 3.9, 168.0], [31172116, 15.2, 717.0], [126045395, 65.2, 2750.0]],
    "export tube3d": [[768, 5.7, 227.0], [3072, 20.6, 676.0]],
}
TESTED = {
    "new": 512 * 512,
    "design full": 32 * 32,
    "design rigid": 128 * 128,
    "design kagome": 12 * 21,  # the largest lattice docs/kagome.md designs
    "design tube": 12 * 12,
    "read pattern": 126045395,  # a 512x512 pattern, as `new` writes it
    "export tube3d": 24 * 128,
}  # largest run to the end
LOWER_BOUND = {"design full"}  # its largest row is a lower bound, so are its extrapolations


@dataclass(frozen=True)
class Estimate:
    tiles: int
    seconds: float
    megabytes: float
    tested_tiles: int
    lower_bound: bool = False

    def text(self) -> str:
        mb, s = self.megabytes, self.seconds
        mem = f"{mb / 1024:.3g} GB" if mb >= 1024 else f"{mb:.0f} MB"
        t = (
            f"{s / 3600:.3g} hours"
            if s >= 3600
            else (f"{s / 60:.3g} minutes" if s >= 60 else f"{s:.0f} s")
        )
        return f"{'at least' if self.lower_bound else 'about'} {mem} and {t}"


def estimate(kind: str, tiles: int) -> Estimate:
    """Memory and time for ``tiles`` tiles: the power law through the two largest measured sizes
    (time and memory each grow as tiles**p, p fitted on those two rows)."""
    (n0, s0, m0), (n1, s1, m1) = MEASURED[kind][-2:]
    r = max(tiles / n1, 1e-300)
    pt = math.log(s1 / s0) / math.log(n1 / n0)
    pm = math.log(m1 / m0) / math.log(n1 / n0)
    return Estimate(
        tiles, s1 * r**pt, m1 * r**pm, TESTED[kind], kind in LOWER_BOUND and tiles >= n1
    )


def available_mb() -> float:
    """Memory this machine can still give (``MemAvailable``), in MB; infinite if unknown."""
    try:
        with open("/proc/meminfo", encoding="ascii") as fh:
            for line in fh:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) / 1024.0
    except (OSError, ValueError, IndexError):
        pass
    return math.inf


def check_tiles(rows: int, cols: int, kind: str, i_know: bool = False) -> None:
    """Refuse a lattice past the largest measured size (unless ``i_know``) or past the free memory."""
    if os.environ.get("FABKIRI_NO_LIMITS"):  # bench/limits.py measures past the limits
        return
    tiles = rows * cols
    est = estimate(kind, tiles)
    side = int(math.isqrt(est.tested_tiles))
    if est.megabytes > available_mb():
        raise InputError(
            f"{rows}x{cols} tiles need {est.text()}; this machine has "
            f"{available_mb() / 1024:.3g} GB free ({side}x{side} is the largest tested)"
        )
    if tiles > est.tested_tiles and not i_know:
        raise InputError(
            f"{side}x{side} is the largest tested; {rows}x{cols} needs {est.text()} — pass ",
            Param("i_know", True),
            " to try",
        )


def check_read_cost(path, what: str = "pattern file", error=InputError) -> None:
    """Refuse, before it is parsed, a pattern file larger than the largest measured (or than the free
    memory its parse would take), with the figures extrapolated from its size."""
    if os.environ.get("FABKIRI_NO_LIMITS"):
        return
    try:
        size = os.stat(path).st_size
    except OSError:
        return  # the reader names the problem
    est = estimate("read pattern", size)
    if size > est.tested_tiles or est.megabytes > available_mb():
        raise error(
            f"{path}: a {size / 2**20:.0f} MB {what} needs {est.text()} to read "
            f"({est.tested_tiles / 2**20:.0f} MB, a 512x512 pattern, is the largest tested)"
        )


def check_copies(tiles: int, copies: int, name: str = "--copies") -> None:
    """Refuse ``copies`` of ``tiles`` tiles past the largest measured (tube3d), before any is made."""
    if os.environ.get("FABKIRI_NO_LIMITS"):
        return
    est = estimate("export tube3d", tiles * copies)
    if tiles * copies > est.tested_tiles or est.megabytes > available_mb():
        raise InputError(
            f"{name} {copies}: {tiles} tiles x {copies} copies need {est.text()} "
            f"({est.tested_tiles} tile copies is the largest tested)"
        )


def check_file_size(path, limit: int | None = None) -> None:
    """Refuse a file larger than ``limit`` bytes (default :data:`MAX_PATTERN_BYTES`) before it is read."""
    limit = MAX_PATTERN_BYTES if limit is None else limit
    try:
        size = os.stat(path).st_size
    except FileNotFoundError:
        raise InputError(f"{path}: no such file") from None
    except OSError as exc:  # a symlink loop, a path through a file, no permission
        raise InputError(f"{path}: cannot be read ({exc.strerror})") from None
    if size > limit:
        raise InputError(
            f"{path}: {size / 2**20:.1f} MB is larger than the {limit / 2**20:.0f} MB an input may have"
        )


def check_length(value: float, name: str | Param) -> float:
    """A finite length in mm within [:data:`MIN_LENGTH_MM`, :data:`MAX_LENGTH_MM`]."""
    if not (math.isfinite(value) and MIN_LENGTH_MM <= value <= MAX_LENGTH_MM):
        raise _named(
            name, f" must be a length in [{MIN_LENGTH_MM:g}, {MAX_LENGTH_MM:g}] mm, got {value:g}"
        )
    return value


def check_scale(nodes: np.ndarray, tiles: np.ndarray, k: float, name: str | Param) -> float:
    """A scale factor that keeps the pattern within the coordinate bound and its tile edges a micrometre."""
    if not (math.isfinite(k) and k > 0):
        raise _named(name, f" must be a positive number, got {k:g}")
    q = np.asarray(nodes, dtype=float)[np.asarray(tiles)]
    extent = float(np.abs(q).max()) * k
    edge = float(np.linalg.norm(q - np.roll(q, -1, axis=1), axis=2).min()) * k
    if not (math.isfinite(extent) and extent <= MAX_COORD_MM):
        raise _named(
            name,
            f" {k:g} puts the pattern {extent:.3g} mm from the origin (at most {MAX_COORD_MM:g} mm)",
        )
    if not edge >= MIN_LENGTH_MM:
        raise _named(
            name,
            f" {k:g} makes the shortest tile edge {edge:.3g} mm (at least {MIN_LENGTH_MM:g} mm)",
        )
    return k


def _named(name: str | Param, text: str) -> InputError:
    """The error ``name`` + ``text``: a :class:`Param` worded for a library caller or the command line."""
    return InputError(name, text) if isinstance(name, Param) else InputError(f"{name}{text}")


# -------------------------------------------------------------------- JSON

_STRING = re.compile(r'"(?:[^"\\]|\\.)*"', re.S)


def json_depth(text: str) -> int:
    """Deepest nesting of arrays/objects in a JSON text (strings skipped), without parsing it."""
    if "[" not in text and "{" not in text:
        return 0
    bare = _STRING.sub('""', text) if '"' in text else text
    b = np.frombuffer(bare.encode("utf-8", "replace"), dtype=np.uint8)
    step = (b == ord("[")).astype(np.int32) + (b == ord("{"))
    step -= (b == ord("]")).astype(np.int32) + (b == ord("}"))
    return int(np.cumsum(step).max(initial=0))


def _int(text: str) -> int:
    v = int(text)
    if abs(v) > MAX_INT:
        raise ValueError(f"integer {text[:24]}{'...' if len(text) > 24 else ''} is beyond ±2**53")
    return v


def _float(text: str) -> float:
    v = float(text)
    if not math.isfinite(v):
        raise ValueError(f"number {text[:24]} is out of the double range")
    return v


def _constant(name: str) -> float:
    raise ValueError(f"non-finite number {name}")


def loads_json(text: str, source: str, error=InputError):
    """``json.loads`` with the bounds above; any problem is one ``error`` line naming ``source``."""
    depth = json_depth(text)
    if depth > MAX_JSON_DEPTH:
        raise error(f"{source}: JSON nested {depth} deep (at most {MAX_JSON_DEPTH})")
    try:
        return json.loads(text, parse_int=_int, parse_float=_float, parse_constant=_constant)
    except json.JSONDecodeError as exc:
        raise error(
            f"{source}: malformed JSON at line {exc.lineno} column {exc.colno}: {exc.msg}"
        ) from None
    except ValueError as exc:
        raise error(f"{source}: {exc}") from None
    except RecursionError:
        raise error(f"{source}: JSON nested too deep") from None


# ------------------------------------------------------------- coordinates


def coordinate_problem(
    nodes: np.ndarray, tiles: np.ndarray | None = None, corners: dict | None = None
) -> str | None:
    """Why these coordinates cannot be a pattern (non-finite, absurd, coinciding corners), or None."""
    arrays = [("node", np.asarray(nodes, dtype=float))]
    arrays += [
        (f"contracted state {k} tile", np.asarray(v, dtype=float))
        for k, v in (corners or {}).items()
    ]
    for what, a in arrays:
        if a.size == 0:
            continue
        flat = a.reshape(-1, 2) if a.ndim >= 2 else a.reshape(-1, 1)
        bad = ~np.isfinite(flat).all(1)
        if bad.any():
            return f"{what} {_index(a, bad)} has a non-finite coordinate"
        far = np.abs(flat).max(1) > MAX_COORD_MM
        if far.any():
            i = int(np.flatnonzero(far)[0])
            return (
                f"{what} {_index(a, far)} lies {float(np.abs(flat[i]).max()):.3g} mm from the origin "
                f"(at most {MAX_COORD_MM:g} mm)"
            )
    if tiles is not None and len(tiles) and len(nodes):
        q = np.asarray(nodes, dtype=float)[np.asarray(tiles)]  # (T, 4, 2)
        extent = float(np.ptp(q.reshape(-1, 2), axis=0).max())
        if extent == 0.0:
            return "all nodes lie at one point"
        edge = np.linalg.norm(q - np.roll(q, -1, axis=1), axis=2)
        short = edge.min(1) <= MIN_EDGE_REL * extent
        if short.any():
            t = int(np.flatnonzero(short)[0])
            return f"tile {t} has two coinciding corners (an edge of {edge[t].min():.3g} mm)"
        tiny = edge.min(1) < MIN_LENGTH_MM
        if tiny.any():  # as check_scale: below a micrometre the geometry checks break
            t = int(np.flatnonzero(tiny)[0])
            return f"tile {t} has an edge of {edge[t].min():.3g} mm (at least {MIN_LENGTH_MM:g} mm)"
    return None


def check_pattern(pattern, source: str):
    """``pattern`` unchanged, or :class:`InputError` naming ``source`` and its coordinate problem."""
    problem = coordinate_problem(pattern.nodes, pattern.tiles, pattern.contracted)
    if problem:
        raise InputError(f"{source}: {problem}")
    return pattern


# a design whose typical tile edge is this many times the least length, yet has one under it, squeezed a tile
# (the drop's point at 96x96 tiles: 0.87 um among ~1 mm edges), where its size was not too small
SLIVER_RATIO = 100.0


def sliver(nodes: np.ndarray, tiles: np.ndarray, corners: dict | None = None) -> str | None:
    """The coordinate problem (:func:`coordinate_problem`: a sliver, or any coordinate no file reader takes) of a
    designed pattern whose typical tile edge is ``SLIVER_RATIO`` times the least length: one tile squeezed among
    tiles of a sane size, a failed design (the design search judges it invalid, as an overlap), not a target too
    small for its tiles (:func:`check_designed` says so); else None."""
    problem = coordinate_problem(nodes, tiles, corners)
    return (
        problem if problem and _typical_edge(nodes, tiles) >= SLIVER_RATIO * MIN_LENGTH_MM else None
    )


def check_designed(pattern) -> None:
    """Refuse a designed ``pattern`` with coordinates every reader refuses (:func:`coordinate_problem`), rather
    than write it: :class:`InputError` for a target too small for its tile count; :class:`CheckFailed` (the
    design failed, the input was fine) where one tile was squeezed to a sliver among tiles of a sane size."""
    problem = coordinate_problem(pattern.nodes, pattern.tiles, pattern.contracted)
    if not problem:
        return
    if sliver(pattern.nodes, pattern.tiles, pattern.contracted):
        raise CheckFailed(
            f"design failed: {problem}, a sliver among edges of "
            f"{_typical_edge(pattern.nodes, pattern.tiles):.3g} mm, which no file reader takes: not written "
            "(fewer tiles, or a larger --size)"
        )
    raise InputError(f"the design's {problem}: give a larger ", Param("size"), " or fewer tiles")


def _typical_edge(nodes: np.ndarray, tiles: np.ndarray) -> float:
    """The median tile edge, mm."""
    q = np.asarray(nodes, dtype=float)[np.asarray(tiles)]
    return float(np.median(np.linalg.norm(q - np.roll(q, -1, axis=1), axis=2)))


def _index(a: np.ndarray, bad: np.ndarray) -> int:
    i = int(np.flatnonzero(bad)[0])
    return i // a.shape[1] if a.ndim == 3 else i  # a per-tile corner array: the tile
