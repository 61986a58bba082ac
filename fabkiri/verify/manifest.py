"""The writer's declared allowances (manifest.json beside the cut files) as the verifier reads them."""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field, fields
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import VerifyError
from ..pattern.topology import STATES
from ..schemas import load_schema, schema_problem
from .hingeread import PLAIN, read_kinds, reading

# ------------------------------------------------------------------ manifest

MITRE_LIMIT = 10.0  # the mitre limit fabkiri's writer has always used (manifests that do not say)
SCHEMA = "cut-manifest.schema.json"


@dataclass
class CutManifest:
    """``manifest.json`` beside fabkiri's cut files: the one definition the writer
    fills (:mod:`fabkiri.fabricate.cut.manifest`) and the verifier reads.

    Fields are in the order written. The defaults are what a manifest that leaves a
    field out means (older fabkiri, a hand-made manifest, the printed tiles' top
    faces): no kerf offset, no shrink, scale 1, closed state 1, the hinge kind's
    usual layout (``layout`` None). Keys this version does not know are kept in
    ``extra`` and written after the known ones. The JSON Schema (``SCHEMA``, shipped
    beside this module) is checked on read.
    """

    format: str = "fabkiri.cut"
    version: int = 1
    units: str = "mm"
    generator: str | None = None
    pattern: str | None = None
    pattern_name: str | None = None
    hinge: str = "separate"
    state: int = 1
    layout: str | None = None
    scale: float = 1.0
    kerf_mm: float | None = None
    kerf_offset_mm: float = 0.0
    kerf_join: str = "mitre"
    mitre_limit: float = MITRE_LIMIT
    tile_shrink_mm: float = 0.0
    tolerance_mm: float | None = None
    parameters: dict[str, Any] = field(default_factory=dict)
    material: dict[str, Any] | None = None
    pattern_verification: dict[str, Any] | None = None
    reference_square: dict[str, Any] | list[dict[str, Any]] | None = None
    sheets: list[dict[str, Any]] = field(default_factory=list)
    tiles: list[dict[str, Any]] = field(default_factory=list)
    hinges: list[dict[str, Any]] = field(default_factory=list)
    hinge_features: list[dict[str, Any]] = field(default_factory=list)
    face_conflicts: int = 0
    ligament: dict[str, Any] | None = None
    warnings: list[str] = field(default_factory=list)
    files: list[str] = field(default_factory=list)
    verification: dict[str, Any] | None = None
    assembly: dict[str, Any] | None = None
    assembly_pieces: list[dict[str, Any]] = field(default_factory=list)
    extra: dict[str, Any] = field(default_factory=dict)

    def default_layout(self) -> str:
        """The layout a manifest without one means: the kind's reading says (tape and ligament sheets
        are cut in place)."""
        how = reading(self.hinge)
        return "in-place" if how is not None and how.in_place else "exploded"

    def to_dict(self) -> dict[str, Any]:
        """The manifest as written (shallow: the lists and dicts are the manifest's own)."""
        out = {f.name: getattr(self, f.name) for f in fields(self) if f.name != "extra"}
        out.update(self.extra)
        return out

    def to_json(self) -> str:
        """The manifest as written (:func:`dumps_manifest`)."""
        return dumps_manifest(self.to_dict())

    @classmethod
    def from_dict(cls, data: Any, where: str = "manifest") -> CutManifest:
        """A manifest read back, checked against the schema (:class:`VerifyError`,
        one line naming the first problem, if it does not conform)."""
        if not isinstance(data, dict):
            raise VerifyError(f"{where}: a manifest is a JSON object")
        _named_problems(data, where)
        problem = schema_problem(data, load_schema("fabkiri.verify", SCHEMA))
        if problem is not None:
            raise VerifyError(f"{where}: malformed manifest ({problem})")
        known = {f.name for f in fields(cls)} - {"extra"}
        return cls(
            **{k: v for k, v in data.items() if k in known},
            extra={k: v for k, v in data.items() if k not in known},
        )

    @classmethod
    def from_json(cls, text: str, where: str = "manifest") -> CutManifest:
        from ..limits import loads_json  # nesting depth and number bounds, as pattern.json

        return cls.from_dict(loads_json(text, f"{where} (manifest)", VerifyError), where)


def _named_problems(data: dict[str, Any], where: str) -> None:
    """The problems the verifier has always named in its own words, before the schema's:
    an unknown hinge kind, a state that is not 1 or 2, a scale that is not positive or
    a negative kerf offset or shrink."""
    hinge = str(data.get("hinge", "separate"))
    if reading(hinge) is None:
        *some, last = read_kinds()
        raise VerifyError(f"{where}: unknown hinge kind {hinge!r} ({', '.join(some)} or {last})")
    try:
        state = int(data.get("state", 1))
        scale, kerf, shrink = (
            float(data.get(k, d))
            for k, d in (("scale", 1.0), ("kerf_offset_mm", 0.0), ("tile_shrink_mm", 0.0))
        )
    except (TypeError, ValueError):
        return  # not numbers: the schema names the field
    if state not in STATES:
        raise VerifyError(f"{where}: state must be 1 or 2, not {state}")
    if (
        not (scale > 0 and math.isfinite(scale))
        or not (kerf >= 0 and math.isfinite(kerf))
        or not (shrink >= 0 and math.isfinite(shrink))
    ):
        raise VerifyError(
            f"{where}: scale must be positive and kerf_offset_mm, tile_shrink_mm non-negative"
        )


ROW_LISTS = (
    "tiles",
    "hinges",
    "hinge_features",
    "assembly_pieces",
)  # lists written one row per line


def dumps_manifest(manifest: dict[str, Any]) -> str:
    """A manifest as JSON: indented, but each row of the long lists on one line.

    (One row per line reads well and lets json's C encoder write the thousands of
    rows of a large pattern; ``indent`` alone runs the pure-Python encoder.)
    """
    m = dict(manifest)
    rows = {}
    for k in ROW_LISTS:
        if isinstance(m.get(k), list) and m[k]:
            rows[k] = m[k]
            m[k] = f"\u0000rows {k}"
    text = json.dumps(m, indent=1, ensure_ascii=False)
    for k, v in rows.items():
        at = f'\n "{k}": ' + json.dumps(m[k], ensure_ascii=False)
        body = ",\n".join("  " + json.dumps(r, ensure_ascii=False) for r in v)
        if text.count(at) != 1:  # cannot happen: a top-level key is written once
            raise RuntimeError(f"manifest key {k!r} not found once")
        text = text.replace(at, f'\n "{k}": [\n{body}\n ]')
    return text + "\n"


def load_manifest(layout_path: Path) -> dict[str, Any] | None:
    m = layout_path.parent / "manifest.json"
    if not m.exists():
        return None
    from ..limits import loads_json  # nesting depth and number bounds, as pattern.json

    try:
        data = loads_json(m.read_text("utf-8"), f"{m} (manifest)", VerifyError)
    except (OSError, UnicodeDecodeError) as exc:
        raise VerifyError(f"{m}: not a readable manifest ({exc})") from None
    if not isinstance(data, dict):
        raise VerifyError(f"{m}: a manifest is a JSON object")
    return data


@dataclass
class Allowances:
    hinge: str  # tape | separate | ligament | plain
    layout: str  # in-place | exploded | nested | auto
    state: int
    scale: float
    kerf_offset: float
    tile_shrink: float
    reference: dict[int, np.ndarray]  # sheet -> 4 corners
    hinge_features: list[dict[str, Any]]
    tile_sheet: dict[int, int]
    sheet_files: dict[int, dict[str, str]]  # sheet -> {"dxf": file, "svg": file}
    cross_sheet: set[int] = field(
        default_factory=set
    )  # hinges the writer declares split across sheets
    ligament_width: float | None = None  # declared ligament width (mm), when the manifest has one
    tiles_placed: dict[int, tuple[float, np.ndarray]] = field(
        default_factory=dict
    )  # tile -> (rotation, shift)
    labels: bool = False  # the manifest says the layout is labelled (fabkiri's tape marks come with the labels)
    mitre_limit: float = (
        MITRE_LIMIT  # the writer's mitre limit for its kerf offsets and shrunk tiles
    )
    # a ligament sheet's ligaments are cut in its files; False: the file holds the tiles only and the
    # ligaments are the declared features (the printed tiles' top faces)
    ligaments_in_file: bool = True


def _allowances(manifest: CutManifest | dict[str, Any] | None, where: str) -> Allowances:
    if manifest is None:
        return Allowances(PLAIN, "auto", 1, 1.0, 0.0, 0.0, {}, [], {}, {})
    m = manifest if isinstance(manifest, CutManifest) else CutManifest.from_dict(manifest, where)
    ref: dict[int, np.ndarray] = {}
    rs = m.reference_square
    for item in [rs] if isinstance(rs, dict) else (rs or []):
        ref[int(item.get("sheet", 1))] = np.asarray(item["corners"], dtype=float).reshape(-1, 2)
    tile_sheet = {int(t["tile"]): int(t.get("sheet", 1)) for t in m.tiles}
    sheet_files: dict[int, dict[str, str]] = {}
    for sh in m.sheets:
        for key in ("dxf", "svg"):
            if sh.get(key):
                sheet_files.setdefault(int(sh["index"]), {})[key] = str(sh[key])
    cross = {int(h["hinge"]) for h in m.hinges if h.get("cross_sheet")}
    lig_w = float(m.ligament["width_mm"]) if m.ligament and m.ligament.get("width_mm") else None
    placed = {
        int(t["tile"]): (float(t["rotation_rad"]), np.asarray(t["shift_mm"], dtype=float))
        for t in m.tiles
        if "rotation_rad" in t and "shift_mm" in t
    }
    return Allowances(
        m.hinge,
        m.layout or m.default_layout(),
        m.state,
        float(m.scale),
        float(m.kerf_offset_mm),
        float(m.tile_shrink_mm),
        ref,
        list(m.hinge_features),
        tile_sheet,
        sheet_files,
        cross,
        lig_w,
        placed,
        bool(m.parameters.get("labels", False)),
        mitre_limit=float(m.mitre_limit),
        ligaments_in_file=bool(m.parameters.get("ligaments_in_file", True)),
    )
