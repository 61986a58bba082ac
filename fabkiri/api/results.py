"""What the top-level doors (:mod:`fabkiri.api.front`) return: one result type per task.

Every result has typed fields, ``ok``, ``summary()`` (one line of text), ``write(folder)`` (the
files the matching command writes, named after the pattern or design, all-or-nothing through
:mod:`fabkiri.fileio`, never over an input) and a picture for a notebook (``_repr_png_``: the
design over its target, the closed states, the cut sheet, the print bed, the deployment). Their
``repr`` is the summary, never an array dump. The outcome of the front door each one wraps stays
reachable as ``.outcome`` for everything else it holds.
"""

from __future__ import annotations

import os
import weakref
from dataclasses import dataclass, field
from functools import cached_property
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import CheckFailed
from ..exchange.pattern_json import dumps
from ..fileio import atomic_write_many, inputs_scope, note_inputs
from ..mechanics.info import PatternInfo
from ..mechanics.path import DeployReport
from ..pattern.model import Pattern
from ..pattern.picture import pattern_png, tiles_png
from ..verify.report import Report
from .advice import Alternative
from .cut import CutOutcome
from .deploy import DeployOutcome
from .display import result_html
from .print import PrintOutcome

Folder = str | os.PathLike

# the file each loaded pattern came from (fabkiri.load): names the results' files and is never written over
_SOURCES: dict[int, tuple[weakref.ref, Path]] = {}


def remember_source(pattern: Pattern, path: Path) -> None:
    """Record that ``pattern`` was read from ``path`` (forgotten with the pattern)."""
    key = id(pattern)
    _SOURCES[key] = (weakref.ref(pattern, lambda _: _SOURCES.pop(key, None)), path)


def source_of(pattern: Pattern) -> Path | None:
    """The file ``pattern`` was loaded from by :func:`fabkiri.load`, if any."""
    entry = _SOURCES.get(id(pattern))
    return entry[1] if entry is not None and entry[0]() is pattern else None


def stem_of(pattern: Pattern) -> str:
    """The files' stem: the loaded file's (as the commands name theirs), else the pattern's name as a
    file name (``circle 8x8 rigid`` -> ``circle-8x8-rigid``), else ``pattern``."""
    src = source_of(pattern)
    if src is not None:
        return src.stem
    safe = "".join(c if c.isalnum() or c in "._-" else "-" for c in pattern.name).strip("-.")
    return "-".join(filter(None, safe.split("-"))) or "pattern"


class _Result:
    """What every result shares: the repr, the picture hook and the all-or-nothing write."""

    inputs: tuple[Path, ...]

    @property
    def ok(self) -> bool:
        raise NotImplementedError

    def summary(self) -> str:
        raise NotImplementedError

    def _written(self) -> dict[str, bytes | str]:
        """The files :meth:`write` writes (``files``), by name relative to the folder."""
        raise NotImplementedError

    def write(self, folder: Folder) -> list[Path]:
        """Write ``files`` into ``folder`` (created if missing) all-or-nothing; refuses to replace
        the file the pattern was loaded from. Returns the paths written."""
        Path(folder).parent.mkdir(
            parents=True, exist_ok=True
        )  # the folder itself comes with its files
        with inputs_scope():
            note_inputs(*self.inputs)
            return atomic_write_many(folder, self._written())

    def __repr__(self) -> str:
        return f"<{type(self).__name__}: {self.summary()}>"

    def _repr_png_(self) -> bytes | None:
        return None

    def _repr_html_(self) -> str:
        return result_html(type(self).__name__, self.summary(), self._repr_png_())


def inputs_of(pattern: Pattern) -> tuple[Path, ...]:
    """The files a result made from ``pattern`` must not write over: the one it was loaded from."""
    src = source_of(pattern)
    return () if src is None else (src,)


@dataclass(repr=False, eq=False)
class DesignResult(_Result):
    """A design (``fabkiri.design``): the ``pattern`` with both closed states, its ``report``, whether
    it is ``valid`` (converged, closes, no overlaps) and meets the shape, and the retry ``messages``."""

    pattern: Pattern
    report: dict[str, Any]
    valid: bool
    stem: str
    messages: list[str] = field(default_factory=list)
    outcome: Any = None  # the kind's design outcome (api/design.py DesignOutcome, api/kagome.py)
    inputs: tuple[Path, ...] = ()

    @property
    def ok(self) -> bool:
        return self.outcome.exit_code == 0

    @property
    def status(self) -> str:
        return str(self.report.get("status", "ok" if self.ok else "failed"))

    def summary(self) -> str:
        name = f"{self.stem}.json"
        first = self.outcome.summary(name)[0].removeprefix(f"wrote {name}: ")
        return f"design {self.stem}: {'ok' if self.ok else 'FAILED'}; {first}"

    @cached_property
    def files(self) -> dict[str, bytes | str]:
        """``STEM.json`` and its preview ``STEM.png``, as ``fabkiri design -o STEM.json`` writes them."""
        made = self.outcome.files(self.stem + ".json") if hasattr(self.outcome, "files") else {}
        return {str(k): v for k, v in made.items()} or {f"{self.stem}.json": dumps(self.pattern)}

    def _written(self) -> dict[str, bytes | str]:
        return self.files

    def _repr_png_(self) -> bytes:
        png = self.files.get(f"{self.stem}.png")
        return png if isinstance(png, bytes) else pattern_png(self.pattern)


@dataclass(repr=False, eq=False)
class ContractResult(_Result):
    """The ``pattern`` with both closed states stored and its ``info``: ``ok`` when it closes in both."""

    pattern: Pattern
    info: PatternInfo
    stem: str
    inputs: tuple[Path, ...] = ()

    @property
    def ok(self) -> bool:
        return self.info.closes_both

    def summary(self) -> str:
        i = self.info
        verdict = "closes in both states" if self.ok else "; ".join(i.problems())
        return (
            f"contract {self.stem}: {i.tiles} tiles, {i.width_mm:.1f} x {i.height_mm:.1f} mm "
            f"deployed; {verdict}"
        )

    @property
    def files(self) -> dict[str, bytes | str]:
        return {f"{self.stem}.json": dumps(self.pattern)}

    def _written(self) -> dict[str, bytes | str]:
        return self.files

    def _repr_png_(self) -> bytes:
        return pattern_png(self.pattern)


@dataclass(repr=False, eq=False)
class VerifyResult(_Result):
    """The verifier's ``report`` on the pattern (and a cut layout, if one was given)."""

    pattern: Pattern
    report: Report
    stem: str
    inputs: tuple[Path, ...] = ()

    @property
    def ok(self) -> bool:
        return self.report.ok

    def summary(self) -> str:
        failed = [c.name for c in self.report.failed()]
        verdict = f"failed {', '.join(failed)}" if failed else "passed"
        return f"verify {self.stem}: {len(self.report.checks)} checks, {verdict}"

    def text(self) -> str:
        """The table ``fabkiri verify`` prints."""
        return self.report.to_text()

    @property
    def files(self) -> dict[str, bytes | str]:
        """The report as ``STEM.verify.json`` (``fabkiri verify --json`` prints it)."""
        return {f"{self.stem}.verify.json": self.report.to_json() + "\n"}

    def _written(self) -> dict[str, bytes | str]:
        return self.files

    def _repr_png_(self) -> bytes:
        return pattern_png(self.pattern)


class _Refusable(_Result):
    """A cut or print that a check may refuse (the command's exit 1): then ``error`` is the
    :class:`~fabkiri.errors.CheckFailed` that says why, ``alternatives`` the checked options that pass
    (:class:`~fabkiri.api.advice.Alternative`), and there are no files."""

    error: CheckFailed | None
    alternatives: list[Alternative]
    stem: str

    @property
    def problems(self) -> list[str]:
        """Why it was refused, in the library's words (empty when it was not)."""
        return [] if self.error is None else [str(self.error)]

    @property
    def advice(self) -> list[str]:
        """Each checked option that passes in a library caller's words: the call and the keywords it
        changes, e.g. ``cut with material='card-0.3', hinge='tape', scale=0.1`` (``scale='auto'``: at
        any size). Its ``command`` is the same option as a ``fabkiri`` command line."""
        return [_option_words(a) for a in self.alternatives]

    def _refusal(self, process: str) -> str:
        assert self.error is not None
        options = self.advice
        more = f" (+{len(options) - 3} more)" if len(options) > 3 else ""
        told = f"; options: {'; '.join(options[:3])}{more}" if options else "; no option passes"
        return f"{process} {self.stem}: REFUSED: {self.error}{told}"

    def write(self, folder: Folder) -> list[Path]:
        """Write ``files`` (see :meth:`_Result.write`); a refused one has none: raises its ``error``."""
        if self.error is not None:
            raise self.error
        return super().write(folder)


def _option_words(option: Alternative) -> str:
    call = {"design": "design again", "make": "make"}.get(option.what) or (
        "cut" if "material" in option.changes else "print_pattern"
    )
    return f"{call} with " + ", ".join(f"{k}={_value(k, v)}" for k, v in option.changes.items())


def _value(name: str, value: Any) -> str:
    """A keyword's value as a Python caller types it (numbers as ``%g``, numpy's too)."""
    if name == "scale" and value is None:
        return "'auto'"
    number = isinstance(value, (int, float)) and not isinstance(value, bool)
    return f"{float(value):g}" if number else repr(value)


@dataclass(repr=False, eq=False)
class CutResult(_Refusable):
    """A verified laser cut: the ``files`` (DXF, SVG, PNG, manifest) named after ``stem``, the
    ``material``, the ``manifest`` and any ``warnings``; ``readback_ok`` is false only for a
    forced cut whose verifier failed. A refused cut has ``ok`` false, no files, its ``error``
    (``problems``) and the ``alternatives`` (``advice``) that pass."""

    files: dict[str, bytes]
    manifest: dict[str, Any]
    material: str
    stem: str
    warnings: list[str] = field(default_factory=list)
    readback_ok: bool = True
    outcome: CutOutcome | None = None
    inputs: tuple[Path, ...] = ()
    error: CheckFailed | None = None
    alternatives: list[Alternative] = field(default_factory=list)

    @property
    def ok(self) -> bool:
        return self.error is None and self.readback_ok

    @property
    def n_sheets(self) -> int:
        return len(self.manifest.get("sheets", []))

    def summary(self) -> str:
        if self.error is not None:
            return self._refusal("cut")
        sheets = self.manifest.get("sheets", [])
        metres = sum(s.get("cut_length_mm", 0.0) for s in sheets) / 1000
        minutes = sum(s.get("cut_time_s", 0.0) for s in sheets) / 60
        return (
            f"cut {self.stem}: {len(sheets)} sheet(s), {self.manifest.get('hinge')} hinges, "
            f"{self.material}, scale {float(self.manifest.get('scale', 1.0)):g}, cut {metres:.2f} m "
            f"(~{minutes:.1f} min); read-back {'passed' if self.readback_ok else 'FAILED (forced)'}"
        )

    def _written(self) -> dict[str, bytes | str]:
        return dict(self.files)

    def _repr_png_(self) -> bytes | None:
        return self.files.get(f"{self.stem}.png")


@dataclass(repr=False, eq=False)
class PrintResult(_Refusable):
    """A verified print: the ``files`` (3MF, STL, PNG, manifest, ...) named after ``stem``, the
    ``scale``, the ``printer``'s name, the one-line ``description`` and the notes (``messages``).
    A refused print has ``ok`` false, no files, the ``scale`` asked for (nan: ``"auto"``), its
    ``error`` (``problems``) and the ``alternatives`` (``advice``) that pass."""

    files: dict[str, Any]
    scale: float
    printer: str
    description: str
    stem: str
    messages: list[str] = field(default_factory=list)
    outcome: PrintOutcome | None = None
    inputs: tuple[Path, ...] = ()
    error: CheckFailed | None = None
    alternatives: list[Alternative] = field(default_factory=list)

    @property
    def ok(self) -> bool:
        return self.error is None

    def summary(self) -> str:
        if self.error is not None:
            return self._refusal("print")
        return f"print {self.stem}: {self.description}"

    def _written(self) -> dict[str, bytes | str]:
        return dict(self.files)

    def _repr_png_(self) -> bytes | None:
        png = self.files.get(f"{self.stem}.png")
        return png if isinstance(png, bytes) else None


@dataclass(repr=False, eq=False)
class DeployResult(_Result):
    """The deployment path (``outcome.path``), its ``figures`` (``deploy.json``), the files and the
    ``problems`` that make ``fabkiri deploy`` exit 1 (none: ``ok``)."""

    figures: DeployReport
    problems: list[str]
    stem: str
    outcome: DeployOutcome
    inputs: tuple[Path, ...] = ()

    @property
    def ok(self) -> bool:
        return not self.problems

    def summary(self) -> str:
        p = self.outcome.path
        kind = "rigid path" if p.kind == "rigid" else f"elastic path ({p.driver})"
        verdict = "ok" if self.ok else "; ".join(self.problems)
        return (
            f"deploy {self.stem}: {kind}, {p.n_frames} frames, max energy {float(p.energy.max()):.3g}, "
            f"collisions {'none' if p.collisions.collision_free() else len(p.collisions.overlaps)}; "
            f"{verdict}"
        )

    @property
    def files(self) -> dict[str, bytes | str]:
        """``energy.csv``, ``deploy.json``, the frames and any plot or GIF, as ``fabkiri deploy``."""
        return self.outcome.files

    def _written(self) -> dict[str, bytes | str]:
        return dict(self.files)

    def _repr_png_(self) -> bytes:
        p = self.outcome.path
        marks = sorted(p.mark_frames().items(), key=lambda kv: kv[1])
        frames = [(name, f) for name, f in marks]
        for (_, a), (_, b) in zip(marks[:-1], marks[1:], strict=True):  # half-way between marks
            frames.append((f"t = {float(p.t[(a + b) // 2]):.2f}", (a + b) // 2))
        frames.sort(key=lambda nf: nf[1])
        return tiles_png([(name, np.asarray(p.corners[f])) for name, f in frames], self.stem)
