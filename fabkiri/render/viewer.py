"""The interactive deployment viewer: the pattern as SVG moving along its computed deployment path.

One self-contained piece of HTML (no network, no library): ``viewer.js`` (shipped beside this module)
and the path's frames as JSON in a ``<script type="application/json">``. A slider runs from closed
state 1 (t = 0) through the deployed state (t = ½) to closed state 2 (t = 1) and snaps to the computed
frames (nothing is interpolated), with play/pause, tiles coloured by spring energy or turn angle, the
target outline and the worst-fit point over the deployed state, a true-scale view of the closed state
the sheet is cut in, and for a tube the frames rolled into 3D (drag to turn).

Every drawn tile is a ``<polygon data-tile="i">`` whose ``points`` are the frame's corners in mm, and
``window.fabkiriViewer`` answers ``frame()``, ``t()`` and ``positions()``: a test reads back exactly
what is drawn.
"""

from __future__ import annotations

import html
import json
from pathlib import Path
from typing import Any

import numpy as np

from ..mechanics.deploy import DeploymentPath
from ..pattern.geometry import signed_areas
from ..pattern.model import Pattern
from ..pattern.thinness import widths
from .htmlparts import data_uri, screen_svg

SCRIPT = Path(__file__).with_name("viewer.js")
DIGITS_MM = 4  # corners to 0.1 µm: far inside the 0.01 mm a reader can see


def viewer_data(
    pattern: Pattern,
    path: DeploymentPath,
    *,
    pieces: list[dict] | None = None,
    problems: list[str] | None = None,
    sheets: list[dict] | None = None,
) -> dict[str, Any]:
    """What the viewer draws: every frame's tile corners, per-tile energy and turn, and the overlays.

    ``pieces``: a cut or print manifest's ``assembly_pieces`` (each names its ``tiles`` and ``hinge``),
    shown on hover; ``sheets``: a cut's sheets (:func:`cut_sheets`), drawn at true scale.
    """
    top = pattern.topology
    corners = np.round(path.corners, DIGITS_MM)
    return {
        "name": pattern.name or "pattern",
        "kind": pattern.kind,
        "path": path.kind,
        "driver": path.driver,
        "t": [float(x) for x in path.t],
        "energy": _sig(path.energy),
        "corners": corners.tolist(),
        "tileEnergy": _sig(path.tile_energy),
        "rotation": np.round(path.rotation, 6).tolist(),
        "marks": path.mark_frames(),
        "tileSize": float(path.tile_size),
        "tiles": _tile_facts(pattern, pieces),
        "hinges": np.column_stack([top.hinge_tiles, top.hinge_corner]).tolist(),
        "hingePieces": _hinge_pieces(pieces),
        "sheets": list(sheets or []),
        "overlay": _overlay(pattern),
        "tube": _tube3d(pattern, path),
        "problems": list(problems or []),
    }


def _sig(a: np.ndarray) -> list:
    """Floats to 4 significant digits (energies span decades; their colours need no more)."""
    return np.vectorize(lambda v: float(f"{v:.4g}"), otypes=[float])(np.asarray(a)).tolist()


def _tile_facts(pattern: Pattern, pieces: list[dict] | None) -> list[dict]:
    """Per tile: its thinnest width (the fabricability measure) and the assembly pieces that join it."""
    w = widths(_ccw(pattern.corners()))
    facts: list[dict] = [{"width_mm": round(float(x), 4)} for x in w]
    for p in pieces or []:
        for t in p.get("tiles") or []:
            if isinstance(t, int) and 0 <= t < len(facts):
                facts[t].setdefault("pieces", []).append(p.get("piece"))
    return facts


def _hinge_pieces(pieces: list[dict] | None) -> dict[str, list]:
    """Hinge number (as text: a JSON key) -> the assembly pieces that join it."""
    out: dict[str, list] = {}
    for p in pieces or []:
        if isinstance(p.get("hinge"), int):
            out.setdefault(str(p["hinge"]), []).append(p.get("piece"))
    return out


def cut_sheets(folder: str | Path | None) -> tuple[list[dict] | None, list[dict]]:
    """A cut folder's assembly pieces and its sheets as the viewer shows them (SVG data URIs, mm sizes)."""
    if not folder:
        return None, []
    d = Path(folder)
    man_path = d / "manifest.json"
    if not man_path.is_file():
        return None, []
    man = json.loads(man_path.read_text("utf-8"))
    sheets = []
    for sh in man.get("sheets") or []:
        p = d / str(sh.get("svg", ""))
        if sh.get("svg") and p.is_file():
            uri = data_uri(screen_svg(p.read_text("utf-8")).encode("utf-8"), ".svg")
            sheets.append(
                {
                    "name": sh["svg"],
                    "uri": uri,
                    "width_mm": sh["width_mm"],
                    "height_mm": sh["height_mm"],
                }
            )
    return man.get("assembly_pieces"), sheets


def _ccw(corners: np.ndarray) -> np.ndarray:
    """Tiles turned counter-clockwise (the width measure reads a clockwise tile as width 0)."""
    return np.where((signed_areas(corners) < 0)[:, None, None], corners[:, ::-1], corners)


def _overlay(pattern: Pattern) -> dict | None:
    """The deployed target outline and where the outline is farthest from it (None without a target)."""
    target = (pattern.design or {}).get("target")
    if not isinstance(target, dict):
        return None
    from ..design.core import conformance
    from ..design.targets.lookup import target_from_dict

    try:
        tgt = target_from_dict(target)
        conf = conformance.deployed(pattern.nodes, pattern.topology, tgt)
    except (ValueError, KeyError, TypeError):  # an old or hand-edited target: draw none
        return None
    poly = conformance.target_polygon(tgt)
    worst = conf.get("worst") or {}
    return {
        "name": str(target.get("name", "target")),
        "outline": np.round(poly, 3).tolist(),
        "worst": worst.get("at"),
        "nearest": worst.get("nearest"),
        "hausdorff_mm": _finite_or_none(conf.get("hausdorff_mm")),
    }


def _finite_or_none(v: Any) -> float | None:
    return float(v) if isinstance(v, (int, float)) and np.isfinite(v) else None


def _tube3d(pattern: Pattern, path: DeploymentPath) -> dict | None:
    """A tube's frames rolled onto its cylinder (or cone): ``(F, T', k, 3)`` mm, T' the tube's tiles."""
    from ..pattern.kinds.periodic.sheet import seam_of, tube_tiles

    seam = seam_of(pattern)
    if seam is None:
        return None
    from .tube import _frame_of

    frames = []
    for c in path.corners:
        tiles, f, _dev = _frame_of(c, pattern)
        frames.append(np.round(f.roll(tiles), 3).tolist())
    return {
        "tiles": [int(i) for i in np.arange(len(pattern.tiles))[tube_tiles(pattern, seam)]],
        "corners": frames,
    }


def _json_script(data: dict) -> str:
    """The data as an inert script element (``</`` escaped so the JSON cannot end the element)."""
    text = json.dumps(data, separators=(",", ":"), allow_nan=False).replace("</", "<\\/")
    return f'<script type="application/json" id="fabkiri-viewer-data">{text}</script>'


def viewer_fragment(data: dict) -> str:
    """The viewer as a block of HTML to place in a page (once per page: its ids are fixed)."""
    return (
        f'<div id="fabkiri-viewer" class="fkv"><noscript>the viewer needs JavaScript</noscript></div>'
        f"{_json_script(data)}<script>{SCRIPT.read_text(encoding='utf-8')}</script>"
    )


PAGE_CSS = """
body{font:15px/1.45 system-ui,-apple-system,'Segoe UI',sans-serif;margin:0;color:#1d232a;background:#f6f7f9}
header{background:#24313f;color:#fff;padding:14px 24px}header h1{margin:0;font-size:21px}
main{margin:16px 24px;background:#fff;padding:14px 18px;border-radius:8px;box-shadow:0 1px 3px #0002}
"""


def viewer_page(data: dict, title: str = "") -> str:
    """A standalone page holding only the viewer (``fabkiri view``)."""
    name = html.escape(title or data.get("name") or "pattern")
    return (
        f'<!DOCTYPE html><html lang="en"><head><meta charset="utf-8"><title>fabkiri view: {name}</title>'
        f'<meta name="viewport" content="width=device-width, initial-scale=1"><style>{PAGE_CSS}</style>'
        f"</head><body><header><h1>fabkiri view: {name}</h1></header><main>{viewer_fragment(data)}</main>"
        f"</body></html>\n"
    )
