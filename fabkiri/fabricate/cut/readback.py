"""Read the written files back and check them; write them only if every check passes.

Two layers of checks:

* :func:`self_checks` — the writer's own promises, read from the bytes:
  the DXF re-reads and audits clean (large files: the stroke entities are
  checked from their tags, everything else by ezdxf's loader and auditor; see
  :func:`read_dxf_checked`), ``$INSUNITS`` = 4, only LWPOLYLINEs on
  known layers, no duplicate segments; the SVG declares mm equal to its
  viewBox; DXF and SVG hold the same polylines after the y flip (1e-6 mm);
  closed contours are valid polygons; the tiles come back from the cut
  linework; webs, holes and labels respect the material.
* the independent verifier, :func:`fabkiri.verify.verify_layout`, which
  trusts nothing but the geometry and the manifest (docs/cut-files.md), run
  on every written DXF and SVG against both closed states.

:func:`write_verified` writes the files all-or-nothing only when both pass.
"""

from __future__ import annotations

import json
import tempfile
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import shapely

from ...errors import CheckFailed, FabkiriError
from ...exchange.drawing import LAYERS
from ...exchange.dxf.reader import read_dxf_checked
from ...exchange.linework import Polylines, duplicate_segments, flat_polylines
from ...exchange.svg import read_svg_layers as read_svg
from ...fileio import atomic_write_many
from ...pattern import thinness as fab
from ...pattern.model import Pattern
from ..gcpause import gc_paused
from .hingekinds import hinge_kind
from .hingekinds.cutting import SheetRead
from .sheets import CutResult

# one sheet's polylines per layer, as the DXF or the SVG read-back gives them
SheetLayers = Mapping[str, Sequence[tuple[np.ndarray, bool]]] | Mapping[str | None, Polylines]

AGREE_MM = 1e-6


@dataclass
class CheckResult:
    name: str
    ok: bool
    detail: str = ""
    value: float | None = None


@dataclass
class Readback:
    checks: list[CheckResult] = field(default_factory=list)
    verifier: dict[str, Any] | None = None

    @property
    def ok(self) -> bool:
        return all(c.ok for c in self.checks) and (
            self.verifier is None or bool(self.verifier.get("ok"))
        )

    def failed(self) -> list[CheckResult]:
        return [c for c in self.checks if not c.ok]

    def add(self, name: str, ok: bool, detail: str = "", value: float | None = None) -> None:
        self.checks.append(CheckResult(name, bool(ok), detail, value))

    def to_dict(self) -> dict[str, Any]:
        return {
            "ok": self.ok,
            "self_checks": [
                {
                    "check": c.name,
                    "ok": c.ok,
                    "detail": c.detail,
                    **({"value": c.value} if c.value is not None else {}),
                }
                for c in self.checks
            ],
            "verifier": self.verifier,
        }


# ------------------------------------------------------------------ self checks


@gc_paused
def self_checks(result: CutResult, files: dict[str, bytes], rb: Readback | None = None) -> Readback:
    """The writer's own checks on the bytes it produced (see the module docstring)."""
    rb = rb or Readback()
    man = result.manifest
    mat = man["material"]
    kind = man["hinge"]
    ref = man["reference_square"]
    Q = result.tile_regions
    assert Q is not None and result.tile_sheet is not None  # a cut records where each tile went
    for row in man["sheets"]:
        k = row["index"]
        dxf_layers = svg_layers = None
        if row["dxf"]:
            dx = read_dxf_checked(files[row["dxf"]])
            dxf_layers, others, errs = dx.layers, dx.others, dx.audit_errors
            how = (
                f" ({dx.bulk_entities} stroke entities checked from their tags)"
                if dx.bulk_entities
                else ""
            )
            rb.add(
                f"sheet {k} dxf audit",
                len(errs) == 0,
                f"{len(errs)} errors{how}" + (f": {errs[0]}" if errs else ""),
                len(errs),
            )
            rb.add(
                f"sheet {k} dxf units",
                dx.insunits == 4 and dx.dxfversion == "AC1024",
                f"$INSUNITS={dx.insunits}, {dx.dxfversion}",
            )
            rb.add(
                f"sheet {k} dxf entities",
                not others and set(dxf_layers) <= set(LAYERS),
                f"non-LWPOLYLINE: {sorted(set(others))}, layers {sorted(dxf_layers)}",
            )
            dups = sum(duplicate_segments(v) for v in dxf_layers.values())
            rb.add(f"sheet {k} dxf duplicate segments", dups == 0, f"{dups} duplicates", dups)
        if row["svg"]:
            wmm, hmm, vb, svg_layers = read_svg(files[row["svg"]])
            ok = (
                len(vb) == 4
                and vb[:2] == [0, 0]
                and wmm == vb[2]
                and hmm == vb[3]
                and wmm == row["width_mm"]
                and hmm == row["height_mm"]
            )
            rb.add(f"sheet {k} svg size", ok, f"{wmm}mm x {hmm}mm, viewBox {vb}")
        if dxf_layers is not None and svg_layers is not None:
            worst, same = 0.0, True
            for name in LAYERS:
                (pa, na, ca), (pb, nb, cb) = (
                    flat_polylines(dxf_layers.get(name, [])),
                    flat_polylines(svg_layers.get(name, [])),
                )
                if len(na) != len(nb) or not (np.array_equal(na, nb) and np.array_equal(ca, cb)):
                    same = False
                    continue
                worst = max(worst, float(np.abs(pa - pb).max(initial=0.0)))
            rb.add(
                f"sheet {k} dxf = svg",
                same and worst <= AGREE_MM,
                f"max difference {worst:.2e} mm",
                worst,
            )
        layers = dxf_layers if dxf_layers is not None else svg_layers
        if layers is None:
            continue
        _geometry_checks(rb, k, layers, kind, mat, man, ref, Q, result.tile_sheet)
    return rb


def _linestrings(polylines: Sequence[tuple[np.ndarray, bool]]) -> np.ndarray:
    """One LineString per polyline (closed ones back to their first point), built at once."""
    pts, n, closed = flat_polylines(polylines)
    end = np.cumsum(n)
    reps = np.ones(len(pts), dtype=np.int64)
    reps[end[closed] - 1] = 2  # repeat the last point's slot: filled with the first point below
    coords = np.repeat(pts, reps, axis=0)
    owner = np.repeat(np.repeat(np.arange(len(n)), n), reps)
    closing = np.cumsum(reps)[end[closed] - 1] - 1
    coords[closing] = pts[(end - n)[closed]]
    return shapely.linestrings(coords, indices=owner)


def _geometry_checks(
    rb: Readback,
    k: int,
    layers: SheetLayers,
    kind: str,
    mat: dict[str, Any],
    man: dict[str, Any],
    ref: dict[str, Any] | None,
    Q: np.ndarray,
    tile_sheet: np.ndarray,
) -> None:
    cut = layers.get("CUT", [])
    closed = [p for p, c in cut if c]
    polys = np.array([shapely.Polygon(p) for p in closed], dtype=object)
    invalid = int((~shapely.is_valid(polys)).sum()) if len(polys) else 0
    rb.add(
        f"sheet {k} closed contours valid",
        invalid == 0,
        f"{invalid} invalid of {len(polys)}",
        invalid,
    )
    is_ref = np.zeros(len(closed), dtype=bool)
    if ref and ref["sheet"] == k:
        sq = np.asarray(ref["corners"])
        is_ref = np.array([p.shape == sq.shape and np.allclose(p, sq, atol=1e-9) for p in closed])
        side = float(np.linalg.norm(sq[1] - sq[0]))
        rb.add(
            f"sheet {k} reference square",
            is_ref.sum() == 1 and abs(side - ref["size_mm"]) <= 1e-9,
            f"{int(is_ref.sum())} found, side {side:.6f} mm",
            side,
        )
    on = np.flatnonzero(tile_sheet == k - 1)
    expected = shapely.polygons(Q[on])
    # recover the pieces the laser leaves (each hinge kind knows what its sheet holds)
    square = np.asarray(ref["corners"]) if ref and ref["sheet"] == k else None
    pieces, holes = hinge_kind(kind).recover(SheetRead(cut, polys, is_ref, square, k, man))
    _tiles_recovered(rb, k, expected, pieces, man["tolerance_mm"])
    _webs_and_holes(rb, k, pieces, holes, mat)
    _labels_inside(rb, k, layers, expected)


def _tiles_recovered(
    rb: Readback, k: int, expected: np.ndarray, pieces: np.ndarray, tol: float
) -> None:
    """Every expected tile comes back: one piece each, the same shape within ``tol`` (mm)."""
    matched = 0
    worst = 0.0
    if len(pieces) and len(expected):
        tree = shapely.STRtree(pieces)
        idx_e, idx_p = tree.query(shapely.centroid(expected), predicate="within")
        best: dict[int, float] = {}  # expected tile -> Hausdorff distance to its nearest piece
        for e, p in zip(idx_e, idx_p):
            d = shapely.hausdorff_distance(expected[e], pieces[p])
            best[e] = min(best.get(e, np.inf), d)
        matched = sum(1 for d in best.values() if d <= tol)
        worst = max(best.values(), default=np.inf)
    rb.add(
        f"sheet {k} tiles recovered",
        matched == len(expected) and len(pieces) == len(expected),
        f"{matched}/{len(expected)} tiles within {tol:g} mm, {len(pieces)} pieces, worst {worst:.2e} mm",
        worst,
    )


def _webs_and_holes(
    rb: Readback, k: int, pieces: np.ndarray, holes: np.ndarray, mat: dict[str, Any]
) -> None:
    """The thinnest piece against the minimum web, every hole against the minimum hole."""
    # the thinnest width of every piece (pattern.fabricability, the definition cut's own check uses)
    thin = min((fab.polygon_width(shapely.get_coordinates(q)) for q in pieces), default=np.inf)
    rb.add(
        f"sheet {k} min web {mat['min_web_mm']:g} mm",
        thin >= mat["min_web_mm"] - fab.WEB_SLACK_MM,
        f"thinnest piece {thin:.4g} mm wide",
        thin,
    )
    if len(holes):
        # a hole is cuttable when a disc of the minimum hole diameter fits inside it
        core = shapely.buffer(holes, -0.5 * mat["min_hole_mm"] * (1 - 1e-6))
        small = np.flatnonzero(shapely.is_empty(core))
        detail = f"{len(holes)} holes, all fit a {mat['min_hole_mm']:g} mm disc"
        if len(small):
            d = 2 * shapely.maximum_inscribed_circle(holes[small[0]], 1e-3).length
            detail = f"{len(small)} of {len(holes)} holes too small, e.g. one fits only a {d:.3g} mm disc"
        rb.add(f"sheet {k} min hole {mat['min_hole_mm']:g} mm", len(small) == 0, detail, len(small))


def _labels_inside(rb: Readback, k: int, layers: SheetLayers, expected: np.ndarray) -> None:
    """Every engraved stroke inside a tile."""
    eng = layers.get("ENGRAVE", [])
    if eng:
        strokes = _linestrings(eng)
        region = shapely.STRtree(expected)
        ii, _ = region.query(strokes, predicate="within")
        outside = len(strokes) - len(np.unique(ii))
        rb.add(
            f"sheet {k} labels inside tiles",
            outside == 0,
            f"{outside} of {len(strokes)} strokes outside",
            outside,
        )


# ------------------------------------------------------------------ verifier and writing


def _relative(value: Any, prefix: str) -> Any:
    """The report with the scratch folder stripped from paths (the manifest must not depend on it)."""
    if isinstance(value, dict):
        return {k: _relative(v, prefix) for k, v in value.items()}
    if isinstance(value, list):
        return [_relative(v, prefix) for v in value]
    if isinstance(value, str):
        return value.replace(prefix, "")
    return value


@gc_paused
def run_verifier(pattern: Pattern, result: CutResult, folder: Path) -> dict[str, Any]:
    """:func:`fabkiri.verify.verify_layout` on every written DXF and SVG, both closed states."""
    try:
        from ...verify import verify_layout
        from ...verify.manifest import CutManifest
    except ImportError:
        return {"ok": False, "available": False, "detail": "fabkiri.verify is not installed"}
    out: dict[str, Any] = {"ok": True, "available": True, "files": {}}
    tol = result.manifest["tolerance_mm"]
    where = str(folder / "manifest.json")
    try:  # read and checked against its schema once, for every file
        manifest: CutManifest | FabkiriError = CutManifest.from_json(
            (folder / "manifest.json").read_text("utf-8"), where
        )
    except FabkiriError as exc:
        manifest = exc
    for key in ("dxf", "svg"):  # the verifier reads every sheet of one format from the first
        names = [row[key] for row in result.manifest["sheets"] if row[key]]
        if not names:
            continue
        try:
            if isinstance(manifest, FabkiriError):
                raise manifest
            rep = verify_layout(pattern, folder / names[0], manifest=manifest, tol_mm=tol)
        except FabkiriError as exc:
            out["ok"] = False
            out["files"][key] = {"ok": False, "error": str(exc)}
            continue
        out["files"][key] = _relative(rep.to_dict(), str(folder) + "/")
        out["ok"] = out["ok"] and bool(rep.ok)
    return out


def verify_result(pattern: Pattern, result: CutResult, *, use_verifier: bool = True) -> Readback:
    """Self checks on the bytes, then the verifier on the files in a private scratch folder."""
    files = dict(result.files)
    files["manifest.json"] = result.manifest_bytes()
    rb = self_checks(result, files)
    if use_verifier:
        with tempfile.TemporaryDirectory(prefix="fabkiri-cut-") as tmp:
            for name, data in files.items():
                (Path(tmp) / name).write_bytes(data)
            rb.verifier = run_verifier(pattern, result, Path(tmp))
    return rb


def verified_files(
    pattern: Pattern, result: CutResult, *, use_verifier: bool = True, force: bool = False
) -> tuple[Readback, dict[str, bytes]]:
    """Verify, then return every file to write (the manifest with the verification report).

    Raises :class:`CheckFailed` naming the failed checks. With ``force`` (a pattern cut although
    it does not close) the verifier's verdict is recorded in the manifest and returned but does
    not stop the files; the writer's own checks on the files still do.
    """
    rb = verify_result(pattern, result, use_verifier=use_verifier)
    result.manifest["verification"] = rb.to_dict()
    if not rb.ok and not (force and not rb.failed()):
        failed = [f"{c.name} ({c.detail})" for c in rb.failed()]
        if rb.verifier is not None and not rb.verifier.get("ok"):
            v = rb.verifier
            if not v.get("available", True):
                failed.append(f"verifier: {v.get('detail')}")
            for name, rep in v.get("files", {}).items():
                if not rep.get("ok"):
                    failed.append(f"verifier on {name}: {rep.get('error') or _failed_names(rep)}")
        raise CheckFailed(
            "read-back verification failed, nothing written: " + "; ".join(failed[:6])
        )
    files = dict(result.files)
    files["manifest.json"] = result.manifest_bytes()
    return rb, files


def write_verified(
    pattern: Pattern,
    result: CutResult,
    folder: str | Path,
    *,
    use_verifier: bool = True,
    force: bool = False,
) -> tuple[Readback, list[Path]]:
    """:func:`verified_files`, then write them all-or-nothing (a failed check writes nothing)."""
    rb, files = verified_files(pattern, result, use_verifier=use_verifier, force=force)
    return rb, atomic_write_many(folder, files)


def _failed_names(rep: dict) -> str:
    checks = rep.get("checks") or []
    bad = [c.get("name", "?") for c in checks if isinstance(c, dict) and not c.get("ok", True)]
    return ", ".join(bad[:4]) or json.dumps(rep)[:200]
