"""Printer presets for 3D-printed kirigami (templates/printers/*.json).

A preset fixes what the slicer and the machine impose: nozzle and layer
height, the clearances that keep print-in-place parts apart (radial: in the
plane, axial: between stacked layers), the gap between tiles, and the sizes of
the printed parts. Every field can be overridden from the CLI. Values are
starting points (docs/fabrication.md#print-clearances); print a clearance coupon to calibrate.
"""

from __future__ import annotations

from dataclasses import MISSING, asdict, dataclass, field, fields, replace
from pathlib import Path
from typing import Any

from ...errors import FabricationError, InputError
from ...fileio import read_input
from ...limits import MAX_PRESET_BYTES, loads_json
from ...schemas import load_schema, schema_problem
from ...templates import nearest, template_dir

PRINTERS_DIR = template_dir("printers")
DEFAULT_PRINTER = "prusa-mk4"


@dataclass(frozen=True)
class PinSpec:
    """Print-in-place pin hinge sizes (``--style pinned``)."""

    ear_radius_mm: float = 3.0
    pin_radius_mm: float = 1.0
    tile_thickness_mm: float = 6.0


@dataclass(frozen=True)
class Printer:
    """One printer preset, all lengths in mm."""

    name: str
    bed_mm: tuple[float, float, float]
    nozzle_mm: float
    layer_mm: float
    radial_clearance_mm: float
    axial_clearance_mm: float
    gap_mm: float
    tile_thickness_mm: float
    strip_thickness_mm: float
    strip_width_mm: float
    strip_reach_mm: float
    part_spacing_mm: float = 3.0
    tile_material: str = "PLA"
    strip_material: str = "TPU"
    description: str = ""
    pin: PinSpec = field(default_factory=PinSpec)
    extruders: int = 1
    # what each extruder is loaded with (multi-material printers); a single
    # extruder is loaded with whatever the job prints
    materials: tuple[str, ...] = ()
    first_layer_mm: float = 0.2
    min_feature_mm: float = 0.8  # narrowest wall the slicer prints solid (two perimeters)

    def __post_init__(self) -> None:
        object.__setattr__(self, "bed_mm", self._bed())
        self._check_lengths()
        self._check_materials()
        self._check_layers()

    def _bed(self) -> tuple[float, ...]:
        """``bed_mm`` as three floats (one line naming the printer otherwise)."""
        try:
            bed = tuple(float(v) for v in self.bed_mm)
        except (TypeError, ValueError):
            raise FabricationError(
                f"printer {self.name}: bed_mm must be [x, y, z] in mm, got {self.bed_mm!r}"
            ) from None
        if len(bed) != 3:
            raise FabricationError(
                f"printer {self.name}: bed_mm must be [x, y, z], got {list(self.bed_mm)}"
            )
        return bed

    def _check_lengths(self) -> None:
        """Every ``*_mm`` field, the bed and the pin's sizes positive."""
        bed = self.bed_mm
        for f in fields(self):
            v = getattr(self, f.name)
            if (
                f.name.endswith("_mm")
                and f.name != "bed_mm"
                and not (isinstance(v, (int, float)) and v > 0)
            ):
                raise FabricationError(
                    f"printer {self.name}: {f.name} must be a positive length, got {v!r}"
                )
        if min(bed) <= 0:
            raise FabricationError(
                f"printer {self.name}: bed size must be positive, got {list(bed)}"
            )
        for f in fields(PinSpec):
            v = getattr(self.pin, f.name)
            if not (isinstance(v, (int, float)) and v > 0):
                raise FabricationError(
                    f"printer {self.name}: pin.{f.name} must be a positive length, got {v!r}"
                )

    def _check_materials(self) -> None:
        """The extruders, what each is loaded with, and the tile and strip materials among them."""
        if not (isinstance(self.extruders, int) and 1 <= self.extruders <= 16):
            raise FabricationError(
                f"printer {self.name}: extruders must be a whole number 1-16, got {self.extruders!r}"
            )
        mats = tuple(self.materials)
        object.__setattr__(self, "materials", mats)
        if mats and (
            len(mats) != self.extruders or not all(isinstance(m, str) and m for m in mats)
        ):
            raise FabricationError(
                f"printer {self.name}: materials must name one material per extruder "
                f"({self.extruders}), got {list(mats)}"
            )
        for m in {self.tile_material, self.strip_material}:
            if m not in MATERIALS:
                raise FabricationError(
                    f"printer {self.name}: unknown material {m!r}; known: {', '.join(MATERIALS)}"
                )
        if (
            self.extruders > 1
            and mats
            and not {self.tile_material, self.strip_material} <= set(mats)
        ):
            raise FabricationError(
                f"printer {self.name}: tile and strip materials must be among the extruders' "
                f"materials {list(mats)}"
            )

    def _check_layers(self) -> None:
        """The layers suit the nozzle; the gap, the strips and the tiles suit the layers and each other."""
        if self.first_layer_mm > 2 * self.layer_mm or self.layer_mm > 0.8 * self.nozzle_mm:
            raise FabricationError(
                f"printer {self.name}: layer {self.layer_mm} mm / first layer "
                f"{self.first_layer_mm} mm do not suit a {self.nozzle_mm} mm nozzle"
            )
        if self.gap_mm < self.radial_clearance_mm:
            raise FabricationError(
                f"printer {self.name}: the tile gap {self.gap_mm} mm is below the radial clearance "
                f"{self.radial_clearance_mm} mm; neighbouring tiles would fuse"
            )
        if self.strip_thickness_mm < self.layer_mm:
            raise FabricationError(
                f"printer {self.name}: strip thickness {self.strip_thickness_mm} mm is thinner than one "
                f"layer ({self.layer_mm} mm)"
            )
        if 2 * self.strip_thickness_mm >= self.tile_thickness_mm:
            raise FabricationError(
                f"printer {self.name}: two recessed strips ({self.strip_thickness_mm} mm each, top and "
                f"bottom) do not fit in a {self.tile_thickness_mm} mm tile"
            )

    def extruder_of(self, material: str) -> int:
        """1-based extruder printing ``material``: its place in ``materials`` on a
        multi-material printer, else 1 (a single extruder is loaded for the job)."""
        if self.extruders > 1:
            mats = self.materials or (self.tile_material, self.strip_material)
            if material in mats:
                return mats.index(material) + 1
            raise FabricationError(f"printer {self.name} has no extruder loaded with {material}")
        return 1

    @property
    def tolerance_mm(self) -> float:
        """How far a printed edge may sit from the design: half the tile gap
        (each tile is shrunk by it) plus half a nozzle width of print error."""
        return 0.5 * self.gap_mm + 0.5 * self.nozzle_mm

    def with_overrides(self, **kw: Any) -> Printer:
        """A copy with some fields replaced; ``None`` values are ignored."""
        kw = {k: v for k, v in kw.items() if v is not None}
        pin_kw = {k[4:]: kw.pop(k) for k in list(kw) if k.startswith("pin_")}
        out = replace(self, **kw)
        if pin_kw:
            out = replace(out, pin=replace(out.pin, **pin_kw))
        return out

    def to_dict(self) -> dict[str, Any]:
        d = asdict(self)
        d["bed_mm"] = list(self.bed_mm)
        d["materials"] = list(self.materials)
        return d


@dataclass(frozen=True)
class MaterialSettings:
    """What the slicer project needs per filament (PrusaSlicer names)."""

    slicer_type: str  # filament_type
    colour: str
    nozzle_c: int
    bed_c: int


MATERIALS: dict[str, MaterialSettings] = {
    "PLA": MaterialSettings("PLA", "#3C78D8", 215, 60),
    "PETG": MaterialSettings("PETG", "#6AA84F", 240, 85),
    "TPU": MaterialSettings("FLEX", "#F1C232", 230, 50),
}


def min_pad_mm2(printer: Printer) -> float:
    """The least area of a strip's pad on each of its tiles (print's plan; ``design --printer`` keeps
    it too)."""
    return 0.25 * printer.strip_width_mm * min(printer.strip_reach_mm, printer.strip_width_mm)


def available_printers() -> list[str]:
    return sorted(p.stem for p in PRINTERS_DIR.glob("*.json"))


def printer_from_dict(data: dict[str, Any], source: str = "preset", schema: bool = True) -> Printer:
    """A printer from preset JSON; ``schema=False`` skips the JSON Schema check (shipped presets, which the tests
    check against it: jsonschema's import alone is a real share of every ``design``)."""
    if not isinstance(data, dict) or data.get("format") != "fabkiri.printer":
        got = data.get("format") if isinstance(data, dict) else type(data).__name__
        raise InputError(
            f"{source} is not a fabkiri printer preset (format {got!r}, expected 'fabkiri.printer')"
        )
    known = {f.name for f in fields(Printer)}
    body = {k: v for k, v in data.items() if k not in ("format", "version")}
    unknown = sorted(set(body) - known)
    if unknown:
        raise InputError(f"{source}: unknown printer field(s) {', '.join(unknown)}")
    pin = body.pop("pin", {}) or {}
    pin_known = {f.name for f in fields(PinSpec)}
    if not isinstance(pin, dict) or set(pin) - pin_known:
        raise InputError(f"{source}: pin must be an object with {', '.join(sorted(pin_known))}")
    required = [
        f.name for f in fields(Printer) if f.default is MISSING and f.default_factory is MISSING
    ]
    missing = [k for k in required if k not in body]
    if missing:
        raise InputError(f"{source}: missing printer field(s) {', '.join(missing)}")
    problem = (
        schema_problem(data, load_schema(__package__, "printer.schema.json")) if schema else None
    )
    if problem:
        raise InputError(f"{source}: {problem}")
    try:
        return Printer(**body, pin=PinSpec(**pin))
    except (TypeError, ValueError) as exc:
        raise InputError(f"{source}: malformed printer preset ({exc})") from None


def load_printer(name_or_path: str | None = None) -> Printer:
    """A preset by name (``templates/printers/NAME.json``) or by path to a JSON file."""
    name = name_or_path or DEFAULT_PRINTER
    path = Path(name)
    shipped = path.suffix.lower() != ".json"  # a missing FILE.json is no such file, not a preset
    if shipped:
        path = PRINTERS_DIR / f"{name}.json"
        if not path.is_file():
            raise InputError(
                f"unknown printer {name!r}{nearest(name, available_printers())}; "
                f"presets: {', '.join(available_printers())}"
            )
    text = read_input(path, max_bytes=MAX_PRESET_BYTES, what="printer preset")
    return printer_from_dict(
        loads_json(text, f"printer preset {path}"), str(path), schema=not shipped
    )
