"""``manifest.json`` beside fabkiri's print files, as one typed object: :class:`PrintManifest`.

Written by the print front door (:func:`fabkiri.fabricate.print.mesh.manifest`, then
:func:`fabkiri.fabricate.assembly.add_to_print` adds the bill of materials) and read back by the
report, with its JSON Schema (``print-manifest.schema.json`` beside this module) checked on read.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field, fields
from typing import Any

from ..errors import VerifyError
from ..schemas import load_schema, schema_problem

SCHEMA = "print-manifest.schema.json"
WHEN_GIVEN = (
    "placements",
    "assembly",
    "unlabelled_hinges",
    "pins",
)  # written only by the styles that have them
ADDED_LAST = ("assembly_pieces", "bill_of_materials", "pattern_fingerprint")  # None: not written


@dataclass
class PrintManifest:
    """A print's manifest; fields in the order written. ``checks`` holds the figures of the mesh,
    file, tile and verifier checks (``meshes``, ``files``, ``tiles``, ``verifier``: each a dict or
    None). ``placements``, ``assembly``, ``unlabelled_hinges`` (hand-glued strips) and ``pins``
    (pinned tiles) are written only when given; ``assembly_pieces`` and ``bill_of_materials`` are
    added last. Keys this version does not know are kept in ``extra``, written after the others."""

    format: str = "fabkiri.print"
    version: int = 1
    units: str = "mm"
    pattern: str | None = None
    style: str = ""
    state: int = 1
    printer: dict[str, Any] = field(default_factory=dict)
    shift_mm: list[float] = field(default_factory=lambda: [0.0, 0.0])
    layout: str | None = None
    layer_changes: list[dict[str, Any]] = field(default_factory=list)
    beds: list[list[str]] = field(default_factory=list)
    hinges: list[dict[str, Any]] = field(default_factory=list)
    files: list[str] = field(default_factory=list)
    checks: dict[str, Any] = field(default_factory=dict)
    placements: list[Any] | None = None
    assembly: str | None = None
    unlabelled_hinges: list[Any] | None = None
    pins: dict[str, Any] | None = None
    assembly_pieces: list[dict[str, Any]] | None = None
    bill_of_materials: dict[str, Any] | None = None
    pattern_fingerprint: dict[str, Any] | None = (
        None  # the pattern's hash and counts (report checks it)
    )
    extra: dict[str, Any] = field(default_factory=dict)

    def check(self, name: str) -> dict[str, Any] | None:
        """The figures of one check (``meshes``, ``files``, ``tiles`` or ``verifier``); None if not run."""
        return self.checks.get(name)

    @property
    def printer_name(self) -> str | None:
        return self.printer.get("name")

    def to_dict(self) -> dict[str, Any]:
        """The manifest as written: the optional keys only when given."""
        out: dict[str, Any] = {}
        for f in fields(self):
            v = getattr(self, f.name)
            if f.name == "extra" or (v is None and f.name in (*WHEN_GIVEN, *ADDED_LAST)):
                continue
            out[f.name] = v
        out.update(self.extra)
        return out

    def to_json(self) -> str:
        return json.dumps(self.to_dict(), indent=1, sort_keys=False) + "\n"

    @classmethod
    def from_dict(cls, data: Any, where: str = "print manifest") -> PrintManifest:
        """A manifest read back, checked against the schema (:class:`VerifyError`, one line naming
        the first problem, if it does not conform)."""
        if not isinstance(data, dict):
            raise VerifyError(f"{where}: a manifest is a JSON object")
        problem = schema_problem(data, load_schema("fabkiri.verify", SCHEMA))
        if problem is not None:
            raise VerifyError(f"{where}: malformed print manifest ({problem})")
        known = {f.name for f in fields(cls)} - {"extra"}
        return cls(
            **{k: v for k, v in data.items() if k in known},
            extra={k: v for k, v in data.items() if k not in known},
        )

    @classmethod
    def from_json(cls, text: str, where: str = "print manifest") -> PrintManifest:
        from ..limits import loads_json  # nesting depth and number bounds, as pattern.json

        return cls.from_dict(loads_json(text, where, VerifyError), where)
