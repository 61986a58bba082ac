"""The writer's declared allowances (manifest.json beside the cut files) as the verifier reads them."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import VerifyError
from ..pattern.topology import STATES

# ------------------------------------------------------------------ manifest


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
    sheet_files: dict[int, str]
    cross_sheet: set[int] = field(default_factory=set)  # hinges the writer declares split across sheets
    ligament_width: float | None = None  # declared ligament width (mm), when the manifest has one
    tiles_placed: dict[int, tuple[float, np.ndarray]] = field(default_factory=dict)  # tile -> (rotation, shift)
    labels: bool = False  # the manifest says the layout is labelled (fabkiri's tape marks come with the labels)


def _allowances(manifest: dict[str, Any] | None, where: str) -> Allowances:
    if manifest is None:
        return Allowances("plain", "auto", 1, 1.0, 0.0, 0.0, {}, [], {}, {})
    try:
        hinge = str(manifest.get("hinge", "separate"))
        if hinge not in ("tape", "separate", "ligament"):
            raise VerifyError(f"{where}: unknown hinge kind {hinge!r} (tape, separate or ligament)")
        layout = str(manifest.get("layout", "in-place" if hinge in ("tape", "ligament") else "exploded"))
        state = int(manifest.get("state", 1))
        if state not in STATES:
            raise VerifyError(f"{where}: state must be 1 or 2, not {state}")
        scale = float(manifest.get("scale", 1.0))
        kerf = float(manifest.get("kerf_offset_mm", 0.0))
        shrink = float(manifest.get("tile_shrink_mm", 0.0))
        if not (scale > 0 and math.isfinite(scale)) or not (kerf >= 0 and math.isfinite(kerf)) \
                or not (shrink >= 0 and math.isfinite(shrink)):
            raise VerifyError(f"{where}: scale must be positive and kerf_offset_mm, tile_shrink_mm non-negative")
        ref: dict[int, np.ndarray] = {}
        rs = manifest.get("reference_square")
        for item in ([rs] if isinstance(rs, dict) else (rs or [])):
            ref[int(item.get("sheet", 1))] = np.asarray(item["corners"], dtype=float).reshape(-1, 2)
        feats = list(manifest.get("hinge_features") or [])
        tile_sheet = {int(t["tile"]): int(t.get("sheet", 1)) for t in manifest.get("tiles") or []}
        sheet_files = {}
        for sh in manifest.get("sheets") or []:
            for key in ("dxf", "svg"):
                if sh.get(key):
                    sheet_files.setdefault(int(sh["index"]), {})[key] = str(sh[key])
        cross = {int(h["hinge"]) for h in manifest.get("hinges") or [] if h.get("cross_sheet")}
        lig = manifest.get("ligament") if isinstance(manifest.get("ligament"), dict) else {}
        lig_w = float(lig["width_mm"]) if lig.get("width_mm") else None
        placed = {int(t["tile"]): (float(t["rotation_rad"]), np.asarray(t["shift_mm"], dtype=float))
                  for t in manifest.get("tiles") or [] if "rotation_rad" in t and "shift_mm" in t}
    except VerifyError:
        raise
    except (TypeError, ValueError, KeyError, AttributeError) as exc:
        raise VerifyError(f"{where}: malformed manifest ({type(exc).__name__}: {exc})") from None
    params = manifest.get("parameters") if isinstance(manifest.get("parameters"), dict) else {}
    return Allowances(hinge, layout, state, scale, kerf, shrink, ref, feats, tile_sheet, sheet_files, cross, lig_w,
                      placed, bool(params.get("labels", False)))
