"""Reading the written DXF and SVG bytes back into polylines, for the writer's own checks.

:func:`read_dxf_checked` re-reads a DXF fast from its tags when it is fabkiri's canonical layout
(large files) and with ezdxf's loader and auditor otherwise; :func:`read_svg` reads the SVG's paths
in its declared millimetres. The polylines are compared and audited in :mod:`.readback`.
"""

from __future__ import annotations

import io
import re
import xml.etree.ElementTree as ET
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from .drawing import LAYERS

SVG_NS = "{http://www.w3.org/2000/svg}"

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
        return cls(*flat_polylines(items))

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


@dataclass(eq=False)
class _Tags:
    """The ENTITIES section of a DXF split into tags, and which entities are canonical."""

    lines: list[str]  # the section's lines (code, value, code, value, ...)
    vals: list[str]  # the tag values
    starts: np.ndarray  # first tag of every entity
    ends: np.ndarray
    eid: np.ndarray  # entity of every tag
    off: np.ndarray  # tag offset within its entity
    bad: np.ndarray  # (entities,) not in the canonical form
    good: np.ndarray  # of the entities with canonical codes: canonical values too
    nv: np.ndarray  # vertex counts of the entities with canonical codes
    flags: np.ndarray

    def at(self, rows: np.ndarray, o: int) -> np.ndarray:
        """The values at tag offset ``o`` of the entities ``rows``."""
        return np.array([self.vals[i] for i in (self.starts[rows] + o).tolist()])


def _split_tags(lines: list[str]) -> _Tags | None:
    """The entities of an ENTITIES section, read by tag codes with numpy; ``None`` if the
    section is not a sequence of (code, value) tags starting with an entity."""
    if len(lines) % 2 or not lines:
        return None
    codes = np.array(lines[0::2])
    vals = lines[1::2]
    starts = np.flatnonzero(codes == "  0")
    if len(starts) == 0 or starts[0] != 0:
        return None
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
    tags = _Tags(lines, vals, starts, ends, eid, off, bad, np.zeros(0, bool), np.zeros(0, int), np.zeros(0))
    ok_idx = np.flatnonzero(~bad)
    kind, sub1, sub2 = tags.at(ok_idx, 0), tags.at(ok_idx, 3), tags.at(ok_idx, 5)
    count, tags.flags = tags.at(ok_idx, 6), tags.at(ok_idx, 7)
    tags.nv = (size[ok_idx] - len(head)) // 2
    tags.good = (kind == "LWPOLYLINE") & (sub1 == "AcDbEntity") & (sub2 == "AcDbPolyline") \
        & np.isin(tags.flags, ["0", "1"]) & (count == tags.nv.astype(str))
    bad[ok_idx[~tags.good]] = True
    return tags


def _audit_strokes(doc, tags: _Tags, canon: np.ndarray, layer_of: np.ndarray) -> list[str]:
    """What ezdxf's audit would say of the canonical entities: handles unique and below
    ``$HANDSEED``, owned by the modelspace, on valid layers of the LAYER table."""
    from ezdxf.lldxf.validator import is_valid_layer_name

    errors = []
    handles, owners = tags.at(canon, 1), tags.at(canon, 2)
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
    names = set(layer_of.tolist())
    invalid = sorted(n for n in names if not is_valid_layer_name(n))
    if invalid:
        errors.append(f"stroke entities with invalid layer names {invalid}")
    missing = sorted(n for n in names if n not in doc.layers)
    if missing:
        errors.append(f"stroke entities on undefined layers {missing}")
    return errors


def _stroke_coords(tags: _Tags, errors: list[str]) -> np.ndarray:
    """The 10/20 values of the canonical entities as ``(P, 2)`` floats (NaN, and an
    error, where one is not a number)."""
    tag = np.flatnonzero(~tags.bad[tags.eid] & (tags.off >= len(_CANON_CODES)))
    try:
        xy = np.array([tags.vals[i] for i in tag.tolist()], dtype=float).reshape(-1, 2)
    except ValueError:
        errors.append("stroke entity with a coordinate that is not a number")
        xy = np.full((len(tag) // 2, 2), np.nan)
    if not np.isfinite(xy).all():
        errors.append("stroke entity with a non-finite coordinate")
    return xy


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
    tags = _split_tags(text[lo:hi].split("\n")[:-1])
    if tags is None:
        return _full(data)
    canon = np.flatnonzero(~tags.bad)
    if len(canon) <= full_max:
        return _full(data)
    # ezdxf: everything but the canonical entities
    keep = np.flatnonzero(tags.bad)
    lines, starts, ends = tags.lines, tags.starts, tags.ends
    rest = "".join("\n".join(lines[2 * starts[k]: 2 * ends[k]]) + "\n" for k in keep.tolist())
    try:
        doc = ezdxf.read(io.StringIO(text[:lo] + rest + text[hi:]))
    except Exception as exc:  # an unreadable file is a failed check, not a crash
        return DxfReadback(None, "", [f"ezdxf cannot read the file: {exc}"], {}, [])
    errors = [f"{e.code}: {e.message}" for e in doc.audit().errors]
    layer_of = tags.at(canon, 4)
    errors += _audit_strokes(doc, tags, canon, layer_of)
    xy = _stroke_coords(tags, errors)
    # polylines per layer in file order: canonical ones from the tags, the others from ezdxf
    _, _, rest_in_order, others = _entities_of(doc)
    if len(rest_in_order) != len(keep):  # entities outside the modelspace: read it all with ezdxf
        return _full(data)
    items = [(int(k), item) for k, item in zip(keep.tolist(), rest_in_order) if item is not None]
    layers = _layers_in_file_order(xy, canon, layer_of, tags.nv[tags.good], tags.flags[tags.good] == "1", items)
    return DxfReadback(doc.header.get("$INSUNITS"), doc.dxfversion, errors, layers, others, len(canon))


def _layers_in_file_order(xy, canon, layer_of, n_canon, closed, items) -> dict[str, Polylines]:
    """Polylines per layer in the file's order: the canonical ones from their tags,
    merged by position with the ``items`` ``(entity, (layer, polyline))`` ezdxf read."""
    point_layer = np.repeat(layer_of, n_canon)
    names = set(layer_of.tolist())
    layers: dict[str, Polylines] = {}
    for name in sorted(names | {item[0] for _, item in items}, key=lambda n: LAYERS.index(n) if n in LAYERS else 99):
        sel = layer_of == name
        mine = Polylines(xy[point_layer == name], n_canon[sel], closed[sel])
        extra = [(k, item[1]) for k, item in items if item[0] == name]
        if extra:  # merge by position in the file
            both = sorted([(int(k), pl) for k, pl in zip(canon[sel].tolist(), mine)] + extra, key=lambda kv: kv[0])
            mine = Polylines.of([pl for _, pl in both])
        layers[name] = mine
    return layers


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


def flat_polylines(polylines) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(points (P, 2), counts, closed)`` of a list of ``(points, closed)``."""
    if isinstance(polylines, Polylines):
        return polylines.pts, polylines.counts, polylines.closed
    if not polylines:
        return np.zeros((0, 2)), np.zeros(0, dtype=np.int64), np.zeros(0, dtype=bool)
    return (np.concatenate([np.asarray(p, dtype=float).reshape(-1, 2) for p, _ in polylines]),
            np.array([len(p) for p, _ in polylines]), np.array([bool(c) for _, c in polylines]))


def _segments(polylines) -> np.ndarray:
    """Every segment ``(S, 2, 2)`` of the polylines (closing segments included), polyline by polyline."""
    pts, n, closed = flat_polylines(polylines)
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
