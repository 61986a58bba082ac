"""Pattern file formats as strategy objects, chosen by name (``export --format``) or by suffix.

A :class:`PatternFormat` reads a file (or a model folder) into a :class:`~.model.Pattern` and/or
writes one; the built-in formats register themselves from their own modules (``pattern.json`` and
Wavefront OBJ in :mod:`.io`, FOLD 1.2 in :mod:`.fold`, PyKirigami model folders in
:mod:`.pykirigami`), loaded on first use as trimesh loads its file-format handlers. A new format is
one module that calls :func:`register_format`, plus one line in the built-in table :data:`_FORMATS`.
What happens around a read or a write (fold-parity labels, contraction of the closed states an
export needs, the fabrication gate) is the front door's, :mod:`fabkiri.api.patterns`.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

from ..errors import InputError
from ..registry import Registry

if TYPE_CHECKING:
    from ..pattern.model import Pattern


def _deployed_only(state: str) -> tuple[int, ...]:
    return ()


@dataclass(frozen=True)
class PatternFormat:
    """One pattern file format.

    ``read(path, scale)``: the pattern in a file (``scale``: mm per file unit), with the closed
    states it stores. ``write(pattern, state, unit)``: the file's text, or for a ``directory`` format
    ``{file name: text}``; ``closed_states(state)`` the closed states it needs stored first (with
    ``every_state``, the file holds both and the gate checks both); ``said(pattern, state, output,
    unit)`` the line ``export`` prints. ``suffixes`` (lower case, with the dot) choose it on reading;
    ``adopt_labels``: a file whose closed states are not labelled 1 and 2 by fabkiri's fold rule.
    """

    name: str
    suffixes: tuple[str, ...] = ()
    directory: bool = False
    read: Callable[[Path, float], Pattern] | None = None
    write: Callable[[Pattern, str, float | None], str | dict[str, str]] | None = None
    closed_states: Callable[[str], tuple[int, ...]] = _deployed_only
    every_state: bool = False
    adopt_labels: bool = True  # the closed states' labels are fixed from the fold parity on reading
    said: Callable[[Pattern, str, str, float | None], str] | None = None


# built-in formats, imported when first asked for (their modules call register_format())
_FORMATS: Registry[PatternFormat] = Registry(
    {
        "json": "fabkiri.exchange.patternfile",
        "obj": "fabkiri.exchange.patternfile",
        "fold": "fabkiri.exchange.fold",
        "pykirigami": "fabkiri.exchange.pykirigami",
    }
)


def register_format(fmt: PatternFormat) -> PatternFormat:
    """Add a format to the registry (a format's module calls this when it is imported)."""
    return _FORMATS.add(fmt.name, fmt)


def _all() -> list[PatternFormat]:
    return [f for f in map(_FORMATS.find, _FORMATS.names()) if f is not None]


def format_names(*, writable: bool = False) -> tuple[str, ...]:
    """The known formats (``writable``: those ``export`` can write), built-in first."""
    return tuple(f.name for f in _all() if f.write is not None or not writable)


def pattern_format(name: str, *, writable: bool = False) -> PatternFormat:
    """The format of this name, or :class:`InputError` naming the known ones."""
    found = _FORMATS.find(name)
    if found is None or (writable and found.write is None):
        raise InputError(
            f"unknown pattern format {name!r}; known: {', '.join(format_names(writable=writable))}"
        )
    return found


def format_of(path: str | Path, fallback: str) -> PatternFormat:
    """The readable format of ``path``: a folder's, else the one claiming its suffix, else ``fallback``."""
    p = Path(path)
    for f in _all():
        if f.read is not None and (p.suffix.lower() in f.suffixes or (f.directory and p.is_dir())):
            return f
    return pattern_format(fallback)
