"""What ``make`` returns: each step's outcome and the one summary the command prints at the end.

A :class:`MakeResult` holds the steps in the order they ran (design, cut or print, deploy,
report), the files each made (names relative to the output folder) and, when a step failed, which
one, its exit code and figures, and the alternatives a refusal names (the ``advice`` front door's,
once it is there). ``summary()`` is the text: what was made, at what size, what to do next, files.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, TypedDict

from ..fileio import atomic_write_many
from ..pattern.model import Pattern
from .display import result_html
from .maker_tiles import TilesChoice

MANIFEST = "make.json"  # the record of the run, written last (also when a step failed)
SCHEMA = "make.schema.json"  # beside this module: what ``make.json`` holds


class StepRecord(TypedDict):
    """One step as ``make.json`` records it (:meth:`Step.to_dict`)."""

    name: str
    ok: bool
    exit_code: int
    wall_s: float
    cpu_s: float
    figures: str
    details: list[str]
    files: list[str]


class MakeRecord(TypedDict):
    """``make.json`` (:meth:`MakeResult.to_dict`)."""

    format: str  # "fabkiri.make"
    version: int
    target: str
    size_mm: float
    process: str  # "cut" or "print"
    fabrication: str
    tiles: list[int]  # rows, cols
    tiles_reason: str
    ok: bool
    exit_code: int
    failed_step: str | None
    figures: dict[str, Any]
    alternatives: list[str]  # each a command line that makes it
    design_retries: list[str]
    steps: list[StepRecord]


@dataclass
class Step:
    """One step of ``make``: whether it passed, its exit code (0, 1 a failed check, 2 refused input),
    its wall and CPU time (s), one line of figures and the files it made (relative to the folder)."""

    name: str
    ok: bool
    exit_code: int
    wall_s: float
    cpu_s: float
    figures: str
    files: list[str] = field(default_factory=list)
    details: list[str] = field(
        default_factory=list
    )  # the step's own lines (a failed design's misses)

    def to_dict(self) -> StepRecord:
        return {
            "name": self.name,
            "ok": self.ok,
            "exit_code": self.exit_code,
            "wall_s": round(self.wall_s, 3),
            "cpu_s": round(self.cpu_s, 3),
            "figures": self.figures,
            "details": self.details,
            "files": self.files,
        }


@dataclass
class MakeResult:
    """The run: the target at ``size`` mm made by ``process`` (``cut`` or ``print``) with ``fabrication``
    (e.g. ``acrylic-3 tape``), on ``tiles``; the designed ``pattern`` (None if the design step did not
    finish), the ``steps`` in order and every file made (``files``, relative to ``output``)."""

    target: str
    size: float
    process: str
    fabrication: str
    tiles: TilesChoice
    stem: str
    output: Path | None = None
    pattern: Pattern | None = None
    steps: list[Step] = field(default_factory=list)
    files: dict[str, bytes | str] = field(default_factory=dict)
    alternatives: list[Any] = field(default_factory=list)  # a refusal's options, each with .command
    refused: bool = (
        False  # the failed step was a fabricability refusal (advice.Refused, maker_early)
    )
    figures: dict[str, Any] = field(default_factory=dict)  # design figures: Hausdorff, opening
    retried: list[str] = field(default_factory=list)  # after a shape miss: each count designed

    @classmethod
    def of_plan(cls, plan, output: Path | None = None, tiles=None, pattern=None) -> MakeResult:
        """A run of ``plan`` (at ``tiles``, else the plan's); without ``output`` nothing is written (an
        alternative's design and checks)."""
        return cls(
            target=plan.target,
            size=plan.size,
            process=plan.process,
            fabrication=plan.fabrication,
            tiles=plan.tiles if tiles is None else tiles,
            stem=plan.stem,
            output=output,
            pattern=pattern,
        )

    @property
    def ok(self) -> bool:
        return bool(self.steps) and all(s.ok for s in self.steps)

    def __repr__(self) -> str:  # the files are bytes: the summary's first line instead
        return f"<MakeResult: {self.summary()[0]}; {'ok' if self.ok else 'FAILED'}>"

    def _repr_png_(self) -> bytes | None:
        """The design preview (``STEM.png``) in a notebook, else the pattern's picture."""
        png = self.files.get(f"{self.stem}.png")
        if isinstance(png, bytes):
            return png
        return None if self.pattern is None else self.pattern._repr_png_()

    def _repr_html_(self) -> str:
        status = "ok" if self.ok else "FAILED"
        return result_html("MakeResult", f"{self.summary()[0]}; {status}", self._repr_png_())

    @property
    def failed(self) -> Step | None:
        return next((s for s in self.steps if not s.ok), None)

    @property
    def exit_code(self) -> int:
        step = self.failed
        return 0 if step is None else step.exit_code

    def step(self, name: str) -> Step | None:
        return next((s for s in self.steps if s.name == name), None)

    def to_dict(self) -> MakeRecord:
        """The record written as ``make.json``."""
        return {
            "format": "fabkiri.make",
            "version": 1,
            "target": self.target,
            "size_mm": self.size,
            "process": self.process,
            "fabrication": self.fabrication,
            "tiles": list(self.tiles.tiles),
            "tiles_reason": self.tiles.reason,
            "ok": self.ok,
            "exit_code": self.exit_code,
            "failed_step": None if self.failed is None else self.failed.name,
            "figures": self.figures,
            "alternatives": [getattr(a, "command", str(a)) for a in self.alternatives],
            "design_retries": self.retried,
            "steps": [s.to_dict() for s in self.steps],
        }

    def option_lines(self) -> list[str]:
        """A refusal's checked options as ``cut`` and ``print`` print them on stdout, and a missed design's
        (a tile count that was run through every step); none otherwise."""
        from .advice import option_lines

        return option_lines(self.alternatives) if self.refused or self.alternatives else []

    def manifest_text(self) -> str:
        return json.dumps(self.to_dict(), indent=2, sort_keys=True) + "\n"

    def write(self, folder) -> list[Path]:
        """Write every file made and ``make.json`` into ``folder`` all-or-nothing (``make(output=None)``)."""
        return atomic_write_many(folder, {**self.files, MANIFEST: self.manifest_text()})

    def summary(self, path=None) -> list[str]:
        """What was made, at what size and with how many tiles, each step's figures, what to do next
        (or which step failed, with its figures and any alternatives), and the files, in the folder ``path``
        (None: the run's output folder, if any)."""
        where = str(path if path is not None else self.output if self.output is not None else ".")
        t = self.tiles
        out = [
            f"make: {self.target} at {self.size:g} mm for {self.process} ({self.fabrication}), "
            f"{t.tiles[0]}x{t.tiles[1]} tiles: {t.reason}"
        ]
        for s in self.steps:
            out.append(
                f"  {s.name}: {'ok' if s.ok else f'FAILED (exit {s.exit_code})'}, {s.figures} "
                f"[{s.wall_s:.1f} s, CPU {s.cpu_s:.1f} s]"
            )
            out += [f"    {line}" for line in s.details]
        failed = self.failed
        if failed is None:
            out.append("next: " + self._next(where))
        elif (
            failed is not self.steps[-1]
        ):  # a step that lets the run go on (deploy): it still failed
            out.append(
                f"make: {failed.name} failed (exit {failed.exit_code}): {failed.figures}; "
                f"{where}/report.html documents the design; the run fails"
            )
        else:
            done = [s.name for s in self.steps if s.ok]
            out.append(
                f"make: stopped at {failed.name} (exit {failed.exit_code}); "
                + (f"kept what {', '.join(done)} made" if done else "nothing made")
            )
            out += [f"  try: {getattr(a, 'command', a)}" for a in self.alternatives]
        names = sorted({n.split("/")[0] + ("/" if "/" in n else "") for n in self.files})
        if self.output is not None:
            names.append(MANIFEST)
        out.append(f"files in {where}: {', '.join(names) if names else 'none'}")
        return out

    def _next(self, where: str) -> str:
        if self.process == "cut":
            return (
                f"cut {where}/cut/{self.stem}.dxf (or .svg) from {self.fabrication.split()[0]} at 100 % "
                f"(the 50 mm reference square checks it), join the tiles as {where}/cut/assembly.png "
                f"shows; {where}/report.html has everything"
            )
        three_mf = sorted(n for n in self.files if n.startswith("print/") and n.endswith(".3mf"))
        first = three_mf[0] if three_mf else "print/"
        return (
            f"open {where}/{first} in PrusaSlicer and print "
            f"({self.fabrication}); {where}/report.html has everything"
        )
