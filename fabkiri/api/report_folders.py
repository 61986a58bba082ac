"""The folders ``report`` reads (cut, print, deploy, tolerance), checked before the page is built.

Each must be of the kind its flag names (the file that kind writes, the format it declares) and
made from the report's pattern: the manifest's ``pattern_fingerprint`` (its hash), or, in folders
written before fabkiri recorded one, the geometry the manifest keeps (tile and hinge counts, the
frames' tiles, the tile size). Anything else is refused in one line naming the folder and the
problem (:class:`~fabkiri.errors.InputError`): a report whose sections describe another pattern
is worse than none.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from .. import limits
from ..errors import CheckFailed, InputError, VerifyError
from ..pattern.fingerprint import KEY, pattern_sha256
from ..pattern.model import Pattern


@dataclass(frozen=True)
class FolderKind:
    name: str  # cut, print, deploy, tolerance
    file: str  # the file that kind always writes
    format: str | None  # the format it declares (deploy.json declares none)


KINDS = {
    "--cut": FolderKind("cut", "manifest.json", "fabkiri.cut"),
    "--print": FolderKind("print", "manifest.json", "fabkiri.print"),
    "--deploy": FolderKind("deploy", "deploy.json", None),
    "--tolerance": FolderKind("tolerance", "tolerance.json", "fabkiri.tolerance"),
}


def check_report_folders(pattern: Pattern, folders: dict[str, str | None]) -> None:
    """Refuse (one line) a folder given under ``flag`` (a :data:`KINDS` key) that does not exist,
    is of another kind, holds an unreadable manifest or was made from another pattern."""
    for flag, folder in folders.items():
        if folder:
            _check(pattern, flag, Path(folder))


def _check(pattern: Pattern, flag: str, d: Path) -> None:
    want = KINDS[flag]
    if not d.is_dir():
        raise InputError(f"{flag} {d}: no such folder")
    got = _kind_of(d, flag)
    if got is None:
        empty = "an empty folder" if not any(d.iterdir()) else "no fabkiri output folder"
        raise InputError(f"{flag} {d}: {empty}, not a {want.name} folder (no {want.file})")
    data = _read(d / got.file, flag)
    if got.name != want.name:
        raise InputError(f"{flag} {d}: a {got.name} folder ({got.file}), not a {want.name} folder")
    _check_schema(want.name, data, f"{flag} {d}/{want.file}")
    problem = _other_pattern(pattern, want.name, data, d, flag)
    if problem:
        raise InputError(f"{flag} {d}: made from another pattern ({problem})")


def _kind_of(d: Path, flag: str) -> FolderKind | None:
    """The kind the folder's files say it is (the flag's own kind first)."""
    order = [KINDS[flag], *(k for f, k in KINDS.items() if f != flag)]
    for kind in order:
        p = d / kind.file
        if not p.is_file():
            continue
        if kind.format is None:
            return kind
        declared = _read(p, flag).get("format")
        if declared == kind.format:
            return kind
        if declared not in {k.format for k in KINDS.values()}:
            raise InputError(f"{flag} {p}: not a fabkiri manifest (format {declared!r})")
    return None


def _read(path: Path, flag: str) -> dict[str, Any]:
    """A folder's JSON file, size- and depth-bounded; a JSON object or a one-line refusal."""
    try:
        size = path.stat().st_size
        if size > limits.MAX_PATTERN_BYTES:
            raise InputError(
                f"{flag} {path}: {size / 2**20:.0f} MB is larger than a manifest may be"
            )
        text = path.read_text("utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        raise InputError(f"{flag} {path}: cannot be read ({exc})") from None
    try:
        data = limits.loads_json(text, f"{flag} {path}")
    except InputError as exc:
        raise InputError(str(exc)) from None
    if not isinstance(data, dict):
        raise InputError(f"{flag} {path}: a manifest is a JSON object")
    return data


def _check_schema(kind: str, data: dict[str, Any], where: str) -> None:
    from ..verify.manifest import CutManifest
    from ..verify.printmanifest import PrintManifest

    readers: dict[str, Callable[..., object]] = {
        "cut": CutManifest.from_dict,
        "print": PrintManifest.from_dict,
    }
    if kind in readers:
        try:
            readers[kind](data, where)
        except VerifyError as exc:
            raise InputError(str(exc)) from None


def _other_pattern(pattern: Pattern, kind: str, data: dict, d: Path, flag: str) -> str | None:
    """What shows the folder was made from another pattern; None if nothing does."""
    mark = data.get(KEY)
    if isinstance(mark, dict) and isinstance(mark.get("sha256"), str):
        if mark["sha256"] == pattern_sha256(pattern):
            return None
        if mark.get("kind") != pattern.kind:
            return f"a {mark.get('kind')} {kind} for a {pattern.kind} pattern"
        return (
            f"its {mark.get('tiles')} tiles and {mark.get('nodes')} nodes hash to "
            f"{mark['sha256'][:12]}, this pattern's {len(pattern.tiles)} and "
            f"{len(pattern.nodes)} to {pattern_sha256(pattern)[:12]}"
        )
    return GEOMETRY[kind](pattern, data, d, flag)  # written before fabkiri recorded a fingerprint


# ------------------------------------------------------- folders without a fingerprint


def _pairs(rows: Any) -> set[tuple[int, int]] | None:
    try:
        return {tuple(sorted(int(t) for t in r["tiles"])) for r in rows}  # type: ignore[misc]
    except (TypeError, KeyError, ValueError):
        return None


def _hinges_and_tiles(
    label: str, pattern: Pattern, tiles: Any, hinges: Any, also: Pattern | None = None
) -> str | None:
    """The folder's tile count and hinge tile pairs against the pattern's (or ``also``'s)."""
    for p in (pattern, also) if also is not None else (pattern,):
        want = {tuple(int(t) for t in h) for h in p.topology.hinge_tiles}
        if tiles == len(p.tiles) and _pairs(hinges) == want:
            return None
    return f"the {label} has {tiles} tiles and {len(hinges or [])} hinges, the pattern {len(pattern.tiles)} and {pattern.topology.n_hinges}"


def _cut_geometry(pattern: Pattern, data: dict, d: Path, flag: str) -> str | None:
    from ..fabricate.tube.sheet import tube_cut_inputs

    try:  # a tube is cut as its flat sheet
        flat = tube_cut_inputs(pattern, int(data.get("state", 1)))[0]
    except (CheckFailed, ValueError):
        flat = pattern
    return _hinges_and_tiles("cut", pattern, len(data.get("tiles") or []), data.get("hinges"), flat)


def _print_geometry(pattern: Pattern, data: dict, d: Path, flag: str) -> str | None:
    bom = data.get("bill_of_materials") or {}
    return _hinges_and_tiles("print", pattern, bom.get("tiles"), data.get("hinges"))


def _deploy_geometry(pattern: Pattern, data: dict, d: Path, flag: str) -> str | None:
    frame = d / "frames" / "frame-0000.json"
    if frame.is_file():
        tiles = _read(frame, flag).get("tiles")
        if np.asarray(tiles, dtype=object).tolist() != np.asarray(pattern.tiles).tolist():
            return "its frames' tiles are not the pattern's"
        return None
    return _tile_size("deploy.json", data.get("tile_size_mm"), pattern)


def _tolerance_geometry(pattern: Pattern, data: dict, d: Path, flag: str) -> str | None:
    model = data.get("model") or {}
    if data.get("pattern") not in (None, pattern.name):
        return f"tolerance.json names pattern {data.get('pattern')!r}, this one is {pattern.name!r}"
    size = model.get("tile_size_mm")
    scale = model.get("scale") or 1.0
    return _tile_size(
        "tolerance.json", size / scale if isinstance(size, (int, float)) else None, pattern
    )


def _tile_size(label: str, size: Any, pattern: Pattern) -> str | None:
    if not isinstance(size, (int, float)):
        return None
    if abs(size - pattern.tile_size) > 1e-6 * pattern.tile_size:
        return f"{label} has tiles of {size:.6g} mm, the pattern {pattern.tile_size:.6g} mm"
    return None


GEOMETRY: dict[str, Callable[[Pattern, dict, Path, str], str | None]] = {
    "cut": _cut_geometry,
    "print": _print_geometry,
    "deploy": _deploy_geometry,
    "tolerance": _tolerance_geometry,
}
