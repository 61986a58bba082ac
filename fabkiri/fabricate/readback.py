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

import io
import json
import re
import tempfile
import xml.etree.ElementTree as ET
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import shapely

from ..errors import CheckFailed, FabkiriError
from ..fileio import atomic_write_many
from ..pattern import fabricability as fab
from ..pattern.model import Pattern
from .cut import CutResult
from .drawing import LAYERS
from .gcpause import gc_paused
from .hinges import MITRE_LIMIT as hg_MITRE

SVG_NS = "{http://www.w3.org/2000/svg}"
AGREE_MM = 1e-6
UNDO_MITRE = 1000.0  # undoing an outset at the acute notches where a strip meets a tile needs sharp mitres


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
        return all(c.ok for c in self.checks) and (self.verifier is None or bool(self.verifier.get("ok")))

    def failed(self) -> list[CheckResult]:
        return [c for c in self.checks if not c.ok]

    def add(self, name: str, ok: bool, detail: str = "", value: float | None = None) -> None:
        self.checks.append(CheckResult(name, bool(ok), detail, value))

    def to_dict(self) -> dict[str, Any]:
        return {"ok": self.ok,
                "self_checks": [{"check": c.name, "ok": c.ok, "detail": c.detail,
                                 **({"value": c.value} if c.value is not None else {})} for c in self.checks],
                "verifier": self.verifier}


# ------------------------------------------------------------------ readers


def read_dxf(data: bytes):
    """``(doc, auditor, layers)`` with ``layers[name] = [(points, closed), ...]``."""
    import ezdxf

    doc = ezdxf.read(io.StringIO(data.decode("ascii")))
    auditor = doc.audit()
    layers: dict[str, list] = {}
    others = []
    for e in doc.modelspace():
        if e.dxftype() != "LWPOLYLINE":
            others.append(e.dxftype())
            continue
        pts = np.asarray([(p[0], p[1]) for p in e.get_points("xy")], dtype=float)
        layers.setdefault(e.dxf.layer, []).append((pts, bool(e.closed)))
    return doc, auditor, layers, others


class Polylines(Sequence):
    """``(points, closed)`` pairs kept flat (points ``(P, 2)``, counts, closed flags); items made on demand."""

    def __init__(self, pts: np.ndarray, counts: np.ndarray, closed: np.ndarray):
        self.pts = np.asarray(pts, dtype=float).reshape(-1, 2)
        self.counts = np.asarray(counts, dtype=np.int64)
        self.closed = np.asarray(closed, dtype=bool)
        self._items: list | None = None

    @classmethod
    def of(cls, items) -> Polylines:
        return cls(*_flat(items))

    def _list(self) -> list:
        if self._items is None:
            parts = np.split(self.pts, np.cumsum(self.counts)[:-1]) if len(self.counts) else []
            self._items = list(zip(parts, self.closed.tolist()))
        return self._items

    def __len__(self) -> int:
        return len(self.counts)

    def __getitem__(self, i):
        return self._list()[i]

    def __iter__(self):
        return iter(self._list())


FULL_AUDIT_MAX = 2000  # files with at most this many canonical stroke entities are loaded whole by ezdxf
_CANON_CODES = ("  0", "  5", "330", "100", "  8", "100", " 90", " 70")  # then " 10"/" 20" per vertex
ENTITIES_HEAD = "  0\nSECTION\n  2\nENTITIES\n"


@dataclass
class DxfReadback:
    """What the self checks need from a DXF: header facts, audit errors, polylines per layer."""

    insunits: Any
    dxfversion: str
    audit_errors: list[str]
    layers: dict[str, list]
    others: list[str]
    bulk_entities: int = 0  # entities checked from their tags instead of being loaded by ezdxf


def read_dxf_checked(data: bytes, full_max: int = FULL_AUDIT_MAX) -> DxfReadback:
    """Read a DXF once for the self checks, with the ezdxf audit.

    Small files: ezdxf loads and audits everything (:func:`read_dxf`). Large
    ones hold tens of thousands of label strokes, and loading each as an ezdxf
    object costs seconds, so the ENTITIES section is split with numpy: every
    entity in the canonical form of a straight LWPOLYLINE (exactly the tags
    ``0 5 330 100 8 100 90 70`` then ``10 20`` per vertex, ``90`` = vertex
    count, flags 0 or 1, subclass markers ``AcDbEntity``/``AcDbPolyline``) is
    read from its tags and checked the way the audit checks such an entity
    (unique handle below ``$HANDSEED``, owned by the modelspace, on a layer of
    the LAYER table, finite coordinates); ezdxf loads and audits the rest of
    the file (header, tables, blocks, objects and every other entity) in full.
    """
    import ezdxf

    text = data.decode("ascii")
    at = text.find(ENTITIES_HEAD)
    lo = at + len(ENTITIES_HEAD)
    hi = text.find("  0\nENDSEC\n", lo)
    if at < 0 or hi < 0:
        return _full(data)
    lines = text[lo:hi].split("\n")[:-1]
    if len(lines) % 2 or not lines:
        return _full(data)
    codes = np.array(lines[0::2])
    vals = lines[1::2]
    starts = np.flatnonzero(codes == "  0")
    if len(starts) == 0 or starts[0] != 0:
        return _full(data)
    ends = np.append(starts[1:], len(codes))
    size = ends - starts
    n_ent = len(starts)
    # expected code of every tag if its entity were canonical
    eid = np.repeat(np.arange(n_ent), size)
    off = np.arange(len(codes)) - starts[eid]
    head = np.array(_CANON_CODES)
    expect = np.where(off % 2 == 0, " 10", " 20")
    expect[off < len(head)] = head[off[off < len(head)]]
    bad = np.bincount(eid, weights=(codes != expect), minlength=n_ent) > 0
    bad |= size < len(head) + 4  # at least two vertices
    ok_idx = np.flatnonzero(~bad)
    vals_at = lambda rows, o: [vals[i] for i in (starts[rows] + o).tolist()]  # noqa: E731
    kind = np.array(vals_at(ok_idx, 0))
    sub1 = np.array(vals_at(ok_idx, 3))
    sub2 = np.array(vals_at(ok_idx, 5))
    count = np.array(vals_at(ok_idx, 6))
    flags = np.array(vals_at(ok_idx, 7))
    nv = (size[ok_idx] - len(head)) // 2
    good = (kind == "LWPOLYLINE") & (sub1 == "AcDbEntity") & (sub2 == "AcDbPolyline") \
        & np.isin(flags, ["0", "1"]) & (count == nv.astype(str))
    bad[ok_idx[~good]] = True
    canon = np.flatnonzero(~bad)
    if len(canon) <= full_max:
        return _full(data)
    # ezdxf: everything but the canonical entities
    keep = np.flatnonzero(bad)
    rest = "".join("\n".join(lines[2 * starts[k]: 2 * ends[k]]) + "\n" for k in keep.tolist())
    try:
        doc = ezdxf.read(io.StringIO(text[:lo] + rest + text[hi:]))
    except Exception as exc:  # an unreadable file is a failed check, not a crash
        return DxfReadback(None, "", [f"ezdxf cannot read the file: {exc}"], {}, [])
    errors = [f"{e.code}: {e.message}" for e in doc.audit().errors]
    handles = np.array(vals_at(canon, 1))
    owners = np.array(vals_at(canon, 2))
    layer_of = np.array(vals_at(canon, 4))
    try:
        hv = np.array([int(h, 16) for h in handles.tolist()], dtype=np.int64)
        seed = int(doc.header.get("$HANDSEED", "0"), 16)
    except ValueError:
        hv, seed = np.zeros(len(canon), dtype=np.int64), -1
        errors.append("stroke entity with a handle that is not hexadecimal")
    if len(np.unique(handles)) != len(handles) or any(h in doc.entitydb for h in set(handles.tolist())):
        errors.append("stroke entities with duplicate handles")
    if (hv <= 0).any() or (hv >= seed).any():
        errors.append("stroke entity handle not below $HANDSEED")
    foreign = int((owners != doc.modelspace().layout_key).sum())
    if foreign:
        errors.append(f"{foreign} stroke entities not owned by the modelspace")
    from ezdxf.lldxf.validator import is_valid_layer_name

    names = set(layer_of.tolist())
    invalid = sorted(n for n in names if not is_valid_layer_name(n))
    if invalid:
        errors.append(f"stroke entities with invalid layer names {invalid}")
    missing = sorted(n for n in names if n not in doc.layers)
    if missing:
        errors.append(f"stroke entities on undefined layers {missing}")
    # coordinates: the 10/20 values of the canonical entities
    tag = np.flatnonzero(~bad[eid] & (off >= len(head)))
    try:
        xy = np.array([vals[i] for i in tag.tolist()], dtype=float).reshape(-1, 2)
    except ValueError:
        errors.append("stroke entity with a coordinate that is not a number")
        xy = np.full((len(tag) // 2, 2), np.nan)
    if not np.isfinite(xy).all():
        errors.append("stroke entity with a non-finite coordinate")
    n_canon = nv[good]
    closed = flags[good] == "1"
    point_layer = np.repeat(layer_of, n_canon)
    # polylines per layer in file order: canonical ones from the tags, the others from ezdxf
    _, _, rest_in_order, others = _entities_of(doc)
    if len(rest_in_order) != len(keep):  # entities outside the modelspace: read it all with ezdxf
        return _full(data)
    rest = [(int(k), item) for k, item in zip(keep.tolist(), rest_in_order) if item is not None]
    layers: dict[str, Polylines] = {}
    for name in sorted(names | {item[0] for _, item in rest}, key=lambda n: LAYERS.index(n) if n in LAYERS else 99):
        sel = layer_of == name
        mine = Polylines(xy[point_layer == name], n_canon[sel], closed[sel])
        extra = [(k, item[1]) for k, item in rest if item[0] == name]
        if extra:  # merge by position in the file
            both = sorted([(int(k), pl) for k, pl in zip(canon[sel].tolist(), mine)] + extra, key=lambda kv: kv[0])
            mine = Polylines.of([pl for _, pl in both])
        layers[name] = mine
    return DxfReadback(doc.header.get("$INSUNITS"), doc.dxfversion, errors, layers, others, len(canon))


def _entities_of(doc):
    """``(None, None, items, others)``: per modelspace entity ``(layer, (points, closed))`` or None."""
    items, others = [], []
    for e in doc.modelspace():
        if e.dxftype() != "LWPOLYLINE":
            others.append(e.dxftype())
            items.append(None)
            continue
        pts = np.asarray([(p[0], p[1]) for p in e.get_points("xy")], dtype=float)
        items.append((e.dxf.layer, (pts, bool(e.closed))))
    return None, None, items, others


def _full(data: bytes) -> DxfReadback:
    doc, aud, layers, others = read_dxf(data)
    return DxfReadback(doc.header.get("$INSUNITS"), doc.dxfversion,
                       [f"{e.code}: {e.message}" for e in aud.errors], layers, others)


_NUM = re.compile(r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?")


_SUBPATH = re.compile(r"(?=[Mm])")


def read_svg(data: bytes):
    """``(width_mm, height_mm, viewbox, layers)``; layers from ``<g id=...>`` groups, y flipped back to y-up.

    A path with several subpaths (``M ... M ...``: the SVG writes each tile's strokes as one
    path) gives one polyline per subpath.
    """
    root = ET.fromstring(data)
    w, h = root.get("width", ""), root.get("height", "")
    vb = [float(v) for v in root.get("viewBox", "").split()]
    wmm = float(w[:-2]) if w.endswith("mm") else float("nan")
    hmm = float(h[:-2]) if h.endswith("mm") else float("nan")
    H = vb[3] if len(vb) == 4 else float("nan")
    layers: dict[str, list] = {}
    for g in root.iter(f"{SVG_NS}g"):
        name = g.get("id")
        nums: list[str] = []
        counts: list[int] = []
        closed: list[bool] = []
        for el in g:
            tag = el.tag.replace(SVG_NS, "")
            if tag == "path":
                for sub in _SUBPATH.split(el.get("d", "")):
                    if not sub.strip():
                        continue
                    found = _NUM.findall(sub)
                    nums += found
                    counts.append(len(found))
                    closed.append(sub.strip().upper().endswith("Z"))
            elif tag in ("polyline", "polygon"):
                found = _NUM.findall(el.get("points", ""))
                nums += found
                counts.append(len(found))
                closed.append(tag == "polygon")
        if not counts:
            continue
        if any(c % 2 for c in counts):
            raise ValueError(f"SVG group {name}: a path with an odd number of coordinates")
        xy = np.asarray(nums, dtype=float).reshape(-1, 2)
        pl = Polylines(np.column_stack([xy[:, 0], H - xy[:, 1]]), np.asarray(counts) // 2, closed)
        if name in layers:  # two groups with one id: one layer
            old = layers[name]
            pl = Polylines(np.concatenate([old.pts, pl.pts]), np.concatenate([old.counts, pl.counts]),
                           np.concatenate([old.closed, pl.closed]))
        layers[name] = pl
    return wmm, hmm, vb, layers


def _flat(polylines) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(points (P, 2), counts, closed)`` of a list of ``(points, closed)``."""
    if isinstance(polylines, Polylines):
        return polylines.pts, polylines.counts, polylines.closed
    if not polylines:
        return np.zeros((0, 2)), np.zeros(0, dtype=np.int64), np.zeros(0, dtype=bool)
    return (np.concatenate([np.asarray(p, dtype=float).reshape(-1, 2) for p, _ in polylines]),
            np.array([len(p) for p, _ in polylines]), np.array([bool(c) for _, c in polylines]))


def _segments(polylines) -> np.ndarray:
    """Every segment ``(S, 2, 2)`` of the polylines (closing segments included), polyline by polyline."""
    pts, n, closed = _flat(polylines)
    if len(pts) == 0:
        return np.zeros((0, 2, 2))
    end = np.cumsum(n)
    first = end - n
    nxt = np.arange(1, len(pts) + 1)
    nxt[end - 1] = np.where(closed, first, -1)  # the last point goes back to the first, or nowhere
    keep = nxt >= 0
    return np.stack([pts[keep], pts[nxt[keep]]], 1)


def duplicate_segments(polylines, decimals: int = 6) -> int:
    """Segments that appear twice (either direction) — they would be cut twice."""
    s = np.round(_segments(polylines), decimals)
    if len(s) == 0:
        return 0
    a, b = s[:, 0], s[:, 1]
    swap = (a[:, 0] > b[:, 0]) | ((a[:, 0] == b[:, 0]) & (a[:, 1] > b[:, 1]))
    lo = np.where(swap[:, None], b, a)
    hi = np.where(swap[:, None], a, b)
    key = np.concatenate([lo, hi], 1)
    return int(len(key) - len(np.unique(key, axis=0)))


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
    for row in man["sheets"]:
        k = row["index"]
        dxf_layers = svg_layers = None
        if row["dxf"]:
            dx = read_dxf_checked(files[row["dxf"]])
            dxf_layers, others, errs = dx.layers, dx.others, dx.audit_errors
            how = f" ({dx.bulk_entities} stroke entities checked from their tags)" if dx.bulk_entities else ""
            rb.add(f"sheet {k} dxf audit", len(errs) == 0,
                   f"{len(errs)} errors{how}" + (f": {errs[0]}" if errs else ""), len(errs))
            rb.add(f"sheet {k} dxf units", dx.insunits == 4 and dx.dxfversion == "AC1024",
                   f"$INSUNITS={dx.insunits}, {dx.dxfversion}")
            rb.add(f"sheet {k} dxf entities", not others and set(dxf_layers) <= set(LAYERS),
                   f"non-LWPOLYLINE: {sorted(set(others))}, layers {sorted(dxf_layers)}")
            dups = sum(duplicate_segments(v) for v in dxf_layers.values())
            rb.add(f"sheet {k} dxf duplicate segments", dups == 0, f"{dups} duplicates", dups)
        if row["svg"]:
            wmm, hmm, vb, svg_layers = read_svg(files[row["svg"]])
            ok = len(vb) == 4 and vb[:2] == [0, 0] and wmm == vb[2] and hmm == vb[3] \
                and wmm == row["width_mm"] and hmm == row["height_mm"]
            rb.add(f"sheet {k} svg size", ok, f"{wmm}mm x {hmm}mm, viewBox {vb}")
        if dxf_layers is not None and svg_layers is not None:
            worst, same = 0.0, True
            for name in LAYERS:
                (pa, na, ca), (pb, nb, cb) = _flat(dxf_layers.get(name, [])), _flat(svg_layers.get(name, []))
                if len(na) != len(nb) or not (np.array_equal(na, nb) and np.array_equal(ca, cb)):
                    same = False
                    continue
                worst = max(worst, float(np.abs(pa - pb).max(initial=0.0)))
            rb.add(f"sheet {k} dxf = svg", same and worst <= AGREE_MM, f"max difference {worst:.2e} mm", worst)
        layers = dxf_layers if dxf_layers is not None else svg_layers
        if layers is None:
            continue
        _geometry_checks(rb, k, layers, kind, mat, man, ref, Q, result.tile_sheet)
    return rb


def _linestrings(polylines) -> np.ndarray:
    """One LineString per polyline (closed ones back to their first point), built at once."""
    pts, n, closed = _flat(polylines)
    end = np.cumsum(n)
    reps = np.ones(len(pts), dtype=np.int64)
    reps[end[closed] - 1] = 2  # repeat the last point's slot: filled with the first point below
    coords = np.repeat(pts, reps, axis=0)
    owner = np.repeat(np.repeat(np.arange(len(n)), n), reps)
    closing = np.cumsum(reps)[end[closed] - 1] - 1
    coords[closing] = pts[(end - n)[closed]]
    return shapely.linestrings(coords, indices=owner)


def _geometry_checks(rb, k, layers, kind, mat, man, ref, Q, tile_sheet) -> None:
    cut = layers.get("CUT", [])
    closed = [p for p, c in cut if c]
    polys = np.array([shapely.Polygon(p) for p in closed], dtype=object)
    invalid = int((~shapely.is_valid(polys)).sum()) if len(polys) else 0
    rb.add(f"sheet {k} closed contours valid", invalid == 0, f"{invalid} invalid of {len(polys)}", invalid)
    is_ref = np.zeros(len(closed), dtype=bool)
    if ref and ref["sheet"] == k:
        sq = np.asarray(ref["corners"])
        is_ref = np.array([p.shape == sq.shape and np.allclose(p, sq, atol=1e-9) for p in closed])
        side = float(np.linalg.norm(sq[1] - sq[0]))
        rb.add(f"sheet {k} reference square", is_ref.sum() == 1 and abs(side - ref["size_mm"]) <= 1e-9,
               f"{int(is_ref.sum())} found, side {side:.6f} mm", side)
    on = np.flatnonzero(tile_sheet == k - 1)
    expected = shapely.polygons(Q[on])
    off = man["kerf_offset_mm"]
    # recover the pieces the laser leaves
    if kind == "tape":
        sq = np.asarray(ref["corners"]) if ref and ref["sheet"] == k else None
        lines = [shapely.LineString(np.vstack([p, p[:1]]) if c else p) for p, c in cut
                 if not (c and sq is not None and p.shape == sq.shape and np.allclose(p, sq, atol=1e-9))]
        noded = shapely.union_all(lines) if lines else shapely.GeometryCollection()
        pieces = shapely.get_parts(shapely.polygonize(shapely.get_parts(noded))) if lines else np.array([])
        holes = np.array([])
    elif kind == "separate":
        pieces = shapely.buffer(polys[~is_ref], -off, join_style="mitre", mitre_limit=hg_MITRE)
        holes = np.array([])
    else:
        rings = polys[~is_ref]
        # a ring inside another ring is a hole of that material piece
        ii, jj = shapely.STRtree(rings).query(rings, predicate="within")
        inside = (np.bincount(ii[ii != jj], minlength=len(rings)) % 2) == 1
        material = shapely.difference(shapely.union_all(rings[~inside]), shapely.union_all(rings[inside]))
        material = shapely.buffer(material, -off, join_style="mitre", mitre_limit=UNDO_MITRE)
        feats = [shapely.Polygon(f["polygon"]) for f in man["hinge_features"] if f["sheet"] == k]
        cores = shapely.difference(material, shapely.union_all(feats)) if feats else material
        pieces = shapely.get_parts(cores)
        pieces = pieces[shapely.area(pieces) > 1e-6]
        holes = np.array([shapely.Polygon(r) for g in shapely.get_parts(material) for r in g.interiors],
                         dtype=object)
    # every expected tile comes back (one piece each, same shape within the material tolerance)
    tol = man["tolerance_mm"]
    matched = 0
    worst = 0.0
    if len(pieces) and len(expected):
        tree = shapely.STRtree(pieces)
        idx_e, idx_p = tree.query(shapely.centroid(expected), predicate="within")
        best = {}
        for e, p in zip(idx_e, idx_p):
            d = shapely.hausdorff_distance(expected[e], pieces[p])
            best[e] = min(best.get(e, np.inf), d)
        matched = sum(1 for d in best.values() if d <= tol)
        worst = max(best.values(), default=np.inf)
    rb.add(f"sheet {k} tiles recovered", matched == len(expected) and len(pieces) == len(expected),
           f"{matched}/{len(expected)} tiles within {tol:g} mm, {len(pieces)} pieces, worst {worst:.2e} mm", worst)
    # webs and holes
    # the thinnest width of every piece (pattern.fabricability, the definition cut's own check uses)
    thin = min((fab.polygon_width(shapely.get_coordinates(q)) for q in pieces), default=np.inf)
    rb.add(f"sheet {k} min web {mat['min_web_mm']:g} mm", thin >= mat["min_web_mm"] - fab.WEB_SLACK_MM,
           f"thinnest piece {thin:.4g} mm wide", thin)
    if len(holes):
        # a hole is cuttable when a disc of the minimum hole diameter fits inside it
        core = shapely.buffer(holes, -0.5 * mat["min_hole_mm"] * (1 - 1e-6))
        small = np.flatnonzero(shapely.is_empty(core))
        detail = f"{len(holes)} holes, all fit a {mat['min_hole_mm']:g} mm disc"
        if len(small):
            d = 2 * shapely.maximum_inscribed_circle(holes[small[0]], 1e-3).length
            detail = f"{len(small)} of {len(holes)} holes too small, e.g. one fits only a {d:.3g} mm disc"
        rb.add(f"sheet {k} min hole {mat['min_hole_mm']:g} mm", len(small) == 0, detail, len(small))
    # labels inside tiles
    eng = layers.get("ENGRAVE", [])
    if eng:
        strokes = _linestrings(eng)
        region = shapely.STRtree(expected)
        ii, _ = region.query(strokes, predicate="within")
        outside = len(strokes) - len(np.unique(ii))
        rb.add(f"sheet {k} labels inside tiles", outside == 0, f"{outside} of {len(strokes)} strokes outside",
               outside)


# ------------------------------------------------------------------ verifier and writing


def _relative(value, prefix: str):
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
        from ..verify import verify_layout
    except ImportError:
        return {"ok": False, "available": False, "detail": "fabkiri.verify is not installed"}
    out = {"ok": True, "available": True, "files": {}}
    tol = result.manifest["tolerance_mm"]
    manifest = json.loads((folder / "manifest.json").read_text("utf-8"))
    for key in ("dxf", "svg"):  # the verifier reads every sheet of one format from the first
        names = [row[key] for row in result.manifest["sheets"] if row[key]]
        if not names:
            continue
        try:
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


def write_verified(pattern: Pattern, result: CutResult, folder: str | Path, *, use_verifier: bool = True,
                   force: bool = False) -> tuple[Readback, list[Path]]:
    """Verify, then write every file (manifest with the verification report) all-or-nothing.

    Raises :class:`CheckFailed` naming the failed checks, writing nothing. With
    ``force`` (a pattern cut although it does not close) the verifier's verdict
    is recorded in the manifest and returned but does not stop the writing;
    the writer's own checks on the files still do.
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
        raise CheckFailed("read-back verification failed, nothing written: " + "; ".join(failed[:6]))
    files = dict(result.files)
    files["manifest.json"] = result.manifest_bytes()
    return rb, atomic_write_many(folder, files)


def _failed_names(rep: dict) -> str:
    checks = rep.get("checks") or []
    bad = [c.get("name", "?") for c in checks if isinstance(c, dict) and not c.get("ok", True)]
    return ", ".join(bad[:4]) or json.dumps(rep)[:200]
