"""Material presets for laser cutting (docs/fabrication.md#materials).

Presets live as JSON files in ``templates/materials/`` (one per material);
:func:`load_material` reads one by name or path and :func:`Material.override`
applies command-line overrides. Every length is in millimetres. Values marked
[E] in the preset notes are estimates: calibrate them with a coupon.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, fields, replace
from pathlib import Path
from typing import Any

from ...errors import FabricationError, InputError, Param
from ...fileio import read_input
from ...limits import MAX_PRESET_BYTES, loads_json
from ...schemas import load_schema, schema_problem
from ...templates import nearest, template_dir

HINGE_KINDS = ("tape", "ligament", "separate")
DEFAULT_MATERIAL = (
    "acrylic-3"  # what a cut is made of when neither the caller nor the design names one
)
COLOR_PRESETS = ("default", "boxes", "ponoko")
MATERIALS_DIR = template_dir("materials")


@dataclass(frozen=True)
class Material:
    """A sheet material and the laser process settings that go with it.

    ``kerf_mm`` is the full kerf (Boxes.py's ``burn`` is half of it).
    ``min_web_mm`` is the narrowest material that survives cutting,
    ``min_hole_mm`` the smallest hole (diameter) worth cutting,
    ``strain_limit`` the allowed in-plane bending strain of a ligament,
    ``gap_mm`` the design gap between tiles of a ligament sheet and
    ``ligament_width_mm`` the widest ligament wanted (the strain rule may
    narrow it, never below ``min_web_mm``). ``tolerance_mm`` is what the
    verifier allows for this material.
    """

    name: str
    description: str = ""
    thickness_mm: float = 3.0
    kerf_mm: float = 0.15
    min_web_mm: float = 3.0
    min_hole_mm: float = 4.5
    strain_limit: float = 0.02
    hinge: str = "tape"
    colors: str = "default"
    gap_mm: float = 2.0
    ligament_width_mm: float = 1.0
    tolerance_mm: float = 0.05
    cut_speed_mm_s: float = 15.0
    engrave_speed_mm_s: float = 100.0
    label_height_mm: float = 4.0
    notes: str = ""

    def __post_init__(self) -> None:
        for f in fields(self):
            v = getattr(self, f.name)
            if f.type in ("float", float):
                if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
                    raise FabricationError(
                        f"material {self.name}: {f.name} must be a finite number, got {v!r}"
                    )
                object.__setattr__(self, f.name, float(v))
                if v <= 0:
                    raise FabricationError(
                        f"material {self.name}: {f.name} must be positive, got {v:g}"
                    )
        if self.hinge not in HINGE_KINDS:
            raise FabricationError(
                f"material {self.name}: hinge must be one of {', '.join(HINGE_KINDS)}, "
                f"got {self.hinge!r}"
            )
        if self.colors not in COLOR_PRESETS:
            raise FabricationError(
                f"material {self.name}: colors must be one of {', '.join(COLOR_PRESETS)}, "
                f"got {self.colors!r}"
            )
        if self.kerf_mm >= self.min_web_mm:
            raise FabricationError(
                f"material {self.name}: kerf {self.kerf_mm:g} mm is not smaller than the minimum web "
                f"{self.min_web_mm:g} mm; the laser would burn every web away"
            )
        if self.strain_limit >= 1:
            raise FabricationError(
                f"material {self.name}: strain_limit is a fraction (< 1), got {self.strain_limit:g}"
            )

    @property
    def kerf_offset_mm(self) -> float:
        """Half the kerf: how far a compensated toolpath sits outside the part."""
        return 0.5 * self.kerf_mm

    def override(self, **changes: Any) -> Material:
        """A copy with the given fields replaced (``None`` values are ignored)."""
        known = {f.name: f for f in fields(self)}
        clean = {}
        for key, value in changes.items():
            if value is None:
                continue
            if key not in known:
                raise InputError(
                    f"unknown material field {key!r} (known: {', '.join(sorted(known))})"
                )
            clean[key] = value
        return replace(self, **clean)

    def to_dict(self) -> dict[str, Any]:
        return asdict(self)


def available() -> list[str]:
    """Names of the presets shipped in ``templates/materials``."""
    return sorted(p.stem for p in MATERIALS_DIR.glob("*.json"))


def load_material(name_or_path: str) -> Material:
    """A preset by name (``acrylic-3``) or a material JSON file by path.

    A file by path is checked against the material schema; a shipped preset by name is not (the tests check
    every shipped preset against it): jsonschema's import alone is a real share of every ``design``, whose
    fabricability summary reads every preset."""
    path = Path(name_or_path)
    shipped = path.suffix.lower() != ".json"
    if shipped:
        path = MATERIALS_DIR / f"{name_or_path}.json"
        if not path.exists():
            raise InputError(
                f"unknown material {name_or_path!r}{nearest(name_or_path, available())}; "
                f"presets: {', '.join(available())}"
            )
    text = read_input(path, max_bytes=MAX_PRESET_BYTES, what="material preset")
    data = loads_json(text, f"material file {path}")
    if not isinstance(data, dict) or data.get("format") != "fabkiri.material":
        got = data.get("format") if isinstance(data, dict) else type(data).__name__
        raise InputError(
            f"material file {path} is not a fabkiri material preset (format {got!r}, "
            f"expected 'fabkiri.material')"
        )
    problem = (
        None if shipped else schema_problem(data, load_schema(__package__, "material.schema.json"))
    )
    if problem:
        raise InputError(f"material file {path}: {problem}")
    data = {k: v for k, v in data.items() if k not in ("format", "version")}
    data.setdefault("name", path.stem)
    return Material(**data)


SETTINGS = Param("settings", flag="--set")  # ``cut_material(settings=[...])``, the CLI's --set


def parse_setting(text: str) -> tuple[str, Any]:
    """``FIELD=VALUE`` from ``--set``: numbers become floats, the rest stays text."""
    if "=" not in text:
        raise InputError(SETTINGS, f" expects FIELD=VALUE, got {text!r}")
    key, value = (s.strip() for s in text.split("=", 1))
    key = key.replace("-", "_")
    known = {f.name: f for f in fields(Material)}
    if key not in known:
        raise InputError(
            SETTINGS, f": unknown material field {key!r} (known: {', '.join(sorted(known))})"
        )
    if known[key].type in ("float", float):
        try:
            return key, float(value)
        except ValueError:
            raise InputError(SETTINGS, f" {key}: expected a number, got {value!r}") from None
    return key, value
