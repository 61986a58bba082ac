"""Every file format fabkiri reads or writes, by name and by suffix: one table, three families.

* **pattern** formats read a file (or a model folder) into a :class:`~fabkiri.pattern.model.Pattern`
  and/or write one (:class:`PatternFormat`): ``json``, ``obj``, ``fold``, ``pykirigami``;
* **drawing** formats write a cut sheet (:class:`~.drawing.SheetDrawing`) and read back the
  linework of a layer of any such file (:class:`DrawingFormat`): ``dxf``, ``svg``;
* **solid** formats write what a print job builds and, where fabkiri checks its own files, read
  the meshes back (:class:`SolidFormat`): ``3mf``, ``stl``, ``step``.

Each format is one module that registers itself when imported (:func:`register_format`); the table
:data:`BUILTIN` names that module, which is imported only when the format is first asked for (as
trimesh loads its file-format handlers), so importing this registry costs nothing and never forms
an import cycle. The solid formats are written from print jobs (printers, bodies), so their modules
live in ``fabricate/print``: the table holds their paths as strings and ``exchange`` never imports
a layer above it. Adding a format is one module and one line here, e.g. a CSV of tile centres::

    # a new module, fabkiri.exchange.centres
    from .file_formats import PatternFormat, register_format

    register_format(PatternFormat("centres", (".ctr",), read=read_centres, write=centres_text))

    # in BUILTIN below
    "centres": ("pattern", "fabkiri.exchange.centres"),

What happens around a pattern read or write (fold-parity labels, contraction of the closed states
an export needs, the fabrication gate) is the front door's, :mod:`fabkiri.api.patterns`.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, ClassVar

from ..errors import InputError, VerifyError
from ..registry import Registry

if TYPE_CHECKING:
    import numpy as np

    from ..pattern.model import Pattern
    from .drawing import SheetDrawing
    from .linework import Linework

FAMILIES = ("pattern", "drawing", "solid")

# name: (family, the module that registers it), in the order the formats are listed
BUILTIN: dict[str, tuple[str, str]] = {
    "json": ("pattern", "fabkiri.exchange.pattern_json"),
    "obj": ("pattern", "fabkiri.exchange.obj"),
    "fold": ("pattern", "fabkiri.exchange.fold"),
    "pykirigami": ("pattern", "fabkiri.exchange.pykirigami"),
    "dxf": ("drawing", "fabkiri.exchange.dxf"),
    "svg": ("drawing", "fabkiri.exchange.svg"),
    # written from print jobs: registered by their modules in fabricate (imported on first use)
    "3mf": ("solid", "fabkiri.fabricate.print.threemf"),
    "stl": ("solid", "fabkiri.fabricate.print.stl"),
    "step": ("solid", "fabkiri.fabricate.print.step"),
}


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
    ``adopt_labels``: a file whose closed states are not labelled 1 and 2 by fabkiri's fold rule;
    ``takes_unit``: ``write`` scales by ``unit`` (others are in mm and refuse one).
    """

    family: ClassVar[str] = "pattern"
    name: str
    suffixes: tuple[str, ...] = ()
    directory: bool = False
    read: Callable[[Path, float], Pattern] | None = None
    write: Callable[[Pattern, str, float | None], str | dict[str, str]] | None = None
    closed_states: Callable[[str], tuple[int, ...]] = _deployed_only
    every_state: bool = False
    adopt_labels: bool = True  # the closed states' labels are fixed from the fold parity on reading
    said: Callable[[Pattern, str, str, float | None], str] | None = None
    takes_unit: bool = False  # whether ``write`` reads its ``unit`` (mm per file unit)


@dataclass(frozen=True)
class DrawingFormat:
    """One 2D drawing format of cut files: ``write(sheet, colors)`` the file's bytes (millimetres,
    one layer per purpose); ``read(path, layer)`` the linework of ``layer`` (``"CUT"``: what a laser
    cuts) of any file of the format, in mm with y up."""

    family: ClassVar[str] = "drawing"
    name: str
    suffixes: tuple[str, ...]
    write: Callable[[SheetDrawing, str], bytes]
    read: Callable[[Path, str], Linework] | None = None


Mesh = tuple[str, "np.ndarray", "np.ndarray"]  # (name, vertices (n, 3), triangles (t, 3))


@dataclass(frozen=True)
class SolidFormat:
    """One 3D format of print files: ``write`` the bytes of what a print job builds (named meshes
    ``{name: (vertices, triangles)}``, or for STEP the bodies); ``read(data)`` the meshes of a file
    as fabkiri writes it, where fabkiri reads its own files back."""

    family: ClassVar[str] = "solid"
    name: str
    suffixes: tuple[str, ...]
    write: Callable[..., bytes]
    read: Callable[[bytes], list[Mesh]] | None = None


AnyFormat = PatternFormat | DrawingFormat | SolidFormat

_REGISTRIES: dict[str, Registry] = {family: Registry({}) for family in FAMILIES}


def _registry(family: str) -> Registry:
    """The family's registry, its built-in members as :data:`BUILTIN` lists them now."""
    reg = _REGISTRIES[family]
    reg.builtin = {n: m for n, (f, m) in BUILTIN.items() if f == family}
    return reg


def register_format(fmt: AnyFormat) -> AnyFormat:
    """Add a format to its family (a format's module calls this when it is imported)."""
    return _REGISTRIES[fmt.family].add(fmt.name, fmt)


def _all(family: str) -> list:
    reg = _registry(family)
    return [f for f in map(reg.find, reg.names()) if f is not None]


def known_formats() -> dict[str, str]:
    """Every format's name and family (nothing imported): family by family, built-in ones first."""
    return {n: family for family in FAMILIES for n in _registry(family).names()}


def file_format(name: str) -> AnyFormat:
    """The format of this name in any family, or :class:`InputError` naming the known ones."""
    family = known_formats().get(name)
    found = _registry(family).find(name) if family else None
    if found is None:
        raise InputError(f"unknown file format {name!r}; known: {', '.join(known_formats())}")
    return found


# ---------------------------------------------------------------- pattern formats


def format_names(*, writable: bool = False) -> tuple[str, ...]:
    """The known pattern formats (``writable``: those ``export`` can write), built-in first."""
    return tuple(f.name for f in _all("pattern") if f.write is not None or not writable)


def pattern_format(name: str, *, writable: bool = False) -> PatternFormat:
    """The pattern format of this name, or :class:`InputError` naming the known ones."""
    found = _registry("pattern").find(name)
    if found is None or (writable and found.write is None):
        raise InputError(
            f"unknown pattern format {name!r}; known: {', '.join(format_names(writable=writable))}"
        )
    return found


def format_of(path: str | Path, fallback: str) -> PatternFormat:
    """The readable pattern format of ``path``: a folder's, else the one claiming its suffix, else
    ``fallback``."""
    p = Path(path)
    for f in _all("pattern"):
        if f.read is not None and (p.suffix.lower() in f.suffixes or (f.directory and p.is_dir())):
            return f
    return pattern_format(fallback)


# ---------------------------------------------------------------- drawings and solids


def _member(family: str, name: str):
    """The ``family`` format of this name, or :class:`InputError` naming the known ones."""
    found = _registry(family).find(name)
    if found is None:
        known = ", ".join(_registry(family).names())
        raise InputError(f"unknown {family} format {name!r}; known: {known}")
    return found


def drawing_format(name: str) -> DrawingFormat:
    """The drawing format of this name, or :class:`InputError` naming the known ones."""
    return _member("drawing", name)


def solid_format(name: str) -> SolidFormat:
    """The solid format of this name, or :class:`InputError` naming the known ones."""
    return _member("solid", name)


def read_cut_file(path: str | Path, layer: str = "CUT") -> Linework:
    """The CUT linework of a drawing (DXF or SVG, chosen by suffix), in mm with y up (``layer``:
    another named layer, e.g. ENGRAVE; a file without it gives an empty linework with
    ``layer_found`` False). Any file a laser tool writes is read, not only fabkiri's own."""
    p = Path(path)
    if not p.exists():
        raise VerifyError(f"{p}: no such layout file")
    readable = [f for f in _all("drawing") if f.read is not None]
    for f in readable:
        if p.suffix.lower() in f.suffixes:
            return f.read(p, layer)
    kinds = " or ".join(s for f in readable for s in f.suffixes)
    raise VerifyError(f"{p}: a layout must be a {kinds} file")
