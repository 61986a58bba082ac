"""The DXF tag codec: fabkiri's canonical LWPOLYLINE entity, written and read as raw tags.

A DXF is a flat list of (group code, value) line pairs. ezdxf writes and fully reads every file,
but building an ezdxf object per entity is slow, and a large sheet engraves tens of thousands
of label strokes. So the strokes are written, and read back, as text in one canonical form:

    0 LWPOLYLINE / 5 handle / 330 owner / 100 AcDbEntity / 8 layer / 100 AcDbPolyline /
    90 vertex count / 70 flags (0 or 1) / then 10 x, 20 y per vertex

(:data:`CANON_CODES`). The writer (:mod:`.writer`) takes the text of that form from
ezdxf's own export of a prototype (:func:`split_prototype`, :func:`lwpolyline_tags`); the writer's
read-back (:func:`.reader.read_dxf_checked`) splits an ENTITIES section into tags and picks out
the canonical entities (:func:`split_tags`); the reader of any DXF
(:func:`.reader.read_cut_dxf`) reads the entities of one layer of any ASCII DXF from their tags
(:func:`read_layer_tags`), ezdxf taking over for anything else.
"""

from __future__ import annotations

import re
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ...errors import VerifyError
from ..linework import Linework

INSUNITS_MM = {0: 1.0, 1: 25.4, 2: 304.8, 4: 1.0, 5: 10.0, 6: 1000.0, 13: 1e-3, 14: 0.1}
ENTITIES_HEAD = "  0\nSECTION\n  2\nENTITIES\n"
ENTITIES_END = "  0\nENDSEC\n"
CANON_CODES = (
    "  0",
    "  5",
    "330",
    "100",
    "  8",
    "100",
    " 90",
    " 70",
)  # then " 10"/" 20" per vertex


# ------------------------------------------------------------------ writing


def split_prototype(
    text: str, handle: str, points: Sequence[tuple[float, float]]
) -> tuple[str, str] | None:
    """``(head, mid)`` of ezdxf's export ``text`` of an open LWPOLYLINE with ``handle`` and ``points``.

    A canonical entity is ``head + handle + mid + " 90\\n{n}\\n 70\\n{flags}\\n" + vertices``;
    None when the export is not of that form (another ezdxf: the caller writes objects instead).
    """
    head, sep, rest = text.partition(f"  5\n{handle}\n")
    mid, sep2, verts = rest.partition(f" 90\n{len(points)}\n 70\n0\n")
    if not sep or not sep2 or verts != "".join(f" 10\n{x}\n 20\n{y}\n" for x, y in points):
        return None
    if tuple(text.split("\n")[0 : 2 * len(CANON_CODES) : 2]) != CANON_CODES:
        return None  # the reader would not take these entities for canonical ones
    return head + "  5\n", "\n" + mid


def lwpolyline_tags(
    polylines: Sequence[tuple[np.ndarray, bool]], handles: list[str], head: str, mid: str
) -> str:
    """Every polyline as the prototype's tags (vertices formatted like ezdxf: ``%s`` of a float)."""
    if not polylines:
        return ""
    pts = np.concatenate([p for p, _ in polylines])
    vtx = [f" 10\n{x!r}\n 20\n{y!r}\n" for x, y in zip(pts[:, 0].tolist(), pts[:, 1].tolist())]
    counts = [len(p) for p, _ in polylines]
    ends = np.cumsum(counts).tolist()
    out = []
    start = 0
    for h, n, end, (_, closed) in zip(handles, counts, ends, polylines):
        out.append(f"{head}{h}{mid} 90\n{n}\n 70\n{1 if closed else 0}\n")
        out.append("".join(vtx[start:end]))
        start = end
    return "".join(out)


def insert_entities(text: str, entities: str) -> str:
    """The DXF ``text`` with ``entities`` (tag text) opening its ENTITIES section."""
    at = text.index(ENTITIES_HEAD) + len(ENTITIES_HEAD)
    return text[:at] + entities + text[at:]


# ------------------------------------------------------------------ reading fabkiri's own files


def entities_span(text: str) -> tuple[int, int] | None:
    """``(lo, hi)``: the ENTITIES section's body in ``text`` (canonical line ends), or None."""
    at = text.find(ENTITIES_HEAD)
    lo = at + len(ENTITIES_HEAD)
    hi = text.find(ENTITIES_END, lo)
    if at < 0 or hi < 0:
        return None
    return lo, hi


@dataclass(eq=False)
class Tags:
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


def split_tags(lines: list[str]) -> Tags | None:
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
    head = np.array(CANON_CODES)
    expect = np.where(off % 2 == 0, " 10", " 20")
    expect[off < len(head)] = head[off[off < len(head)]]
    bad = np.bincount(eid, weights=(codes != expect), minlength=n_ent) > 0
    bad |= size < len(head) + 4  # at least two vertices
    tags = Tags(
        lines, vals, starts, ends, eid, off, bad, np.zeros(0, bool), np.zeros(0, int), np.zeros(0)
    )
    ok_idx = np.flatnonzero(~bad)
    kind, sub1, sub2 = tags.at(ok_idx, 0), tags.at(ok_idx, 3), tags.at(ok_idx, 5)
    count, tags.flags = tags.at(ok_idx, 6), tags.at(ok_idx, 7)
    tags.nv = (size[ok_idx] - len(head)) // 2
    tags.good = (
        (kind == "LWPOLYLINE")
        & (sub1 == "AcDbEntity")
        & (sub2 == "AcDbPolyline")
        & np.isin(tags.flags, ["0", "1"])
        & (count == tags.nv.astype(str))
    )
    bad[ok_idx[~tags.good]] = True
    return tags


# ------------------------------------------------------------------ reading any ASCII DXF


_CUT_LAYER_RE = re.compile(rb"\n[ \t]*8\nCUT[ \t]*(?=\n)", re.IGNORECASE)


def read_layer_tags(p: Path, layer_name: str = "CUT") -> Linework | None:
    """Straight LWPOLYLINEs and LINEs on layer CUT of an ASCII DXF, read from the raw tags.

    A DXF is a flat list of (group code, value) line pairs; cut files carry far
    more engraving than cutting, and building ezdxf entities for all of it
    takes seconds on a 64x64 sheet. Entity starts (code-0 lines) are found with
    numpy on the line table, the CUT layer tags with a regular expression, and
    only those entities are parsed. Anything else (no CUT layer, curves,
    bulges, blocks, binary DXF, odd structure) returns None and the full ezdxf
    reader takes over.
    """
    try:
        raw = p.read_bytes()
        if raw.startswith(b"AutoCAD Binary DXF"):
            return None
        data = b"\n" + raw.replace(b"\r\n", b"\n").replace(b"\r", b"\n")
        if not data.endswith(b"\n"):
            data += b"\n"
        buf = np.frombuffer(data, dtype=np.uint8)
        nl = np.flatnonzero(buf == 10)  # nl[k] opens line k; code lines are even
        k = np.arange(0, len(nl) - 1, 2)
        end = nl[k + 1]
        length = end - nl[k] - 1
        zero = (buf[end - 1] == ord("0")) & ((length == 1) | (buf[end - 2] == ord(" ")))
        starts = nl[k[zero]]  # every "0" code line: an entity, section or table boundary
        m = re.search(rb"\n[ \t]*0\n[ \t]*SECTION[ \t]*\n[ \t]*2\n[ \t]*ENTITIES[ \t]*\n", data)
        if m is None:
            return None
        lo = m.end() - 1
        e = re.compile(rb"\n[ \t]*0\n[ \t]*ENDSEC[ \t]*(?=\n)").search(data, lo)
        hi = e.start() if e else len(data) - 1
        units = re.search(rb"\n[ \t]*9\n[ \t]*\$INSUNITS[ \t]*\n[ \t]*70\n[ \t]*(-?\d+)", data)
        insunits = int(units.group(1)) if units and units.start() < lo else 0
        unit = INSUNITS_MM.get(insunits)
        if unit is None:
            raise VerifyError(f"{p}: unsupported drawing units $INSUNITS={insunits}")
        starts = starts[(starts >= lo) & (starts < hi)]
        bounds = np.append(starts, hi)
        layer_re = (
            _CUT_LAYER_RE
            if layer_name == "CUT"
            else re.compile(rb"\n[ \t]*8\n" + layer_name.encode() + rb"[ \t]*(?=\n)", re.IGNORECASE)
        )
        tags_at = np.array([t.start() for t in layer_re.finditer(data, lo, hi)], dtype=np.int64)
        if len(tags_at) == 0:
            return None  # no CUT layer: a plain file, read it all with ezdxf
        tags_at = tags_at[np.searchsorted(nl, tags_at) % 2 == 0]
        owners = np.unique(np.searchsorted(starts, tags_at, side="right") - 1)
        lw = Linework(p, layer_found=True)
        for o in owners[owners >= 0].tolist():
            text = data[bounds[o] + 1 : bounds[o + 1]].decode("utf-8", "replace")
            if not _add_entity(lw, text, layer_name, unit):
                return None
        return lw
    except VerifyError:
        raise
    except Exception:  # malformed tag stream: let the full reader name the problem
        return None


def _add_entity(lw: Linework, text: str, layer_name: str, unit: float) -> bool:
    """Add one entity's straight linework (its tag lines ``text``) to ``lw`` if it is on ``layer_name``.

    False when the entity needs the full reader (an extrusion direction, a curve, an arc segment,
    odd structure); an entity whose layer tag is not ``layer_name`` is skipped.
    """
    lines = text.split("\n")
    tags = list(zip((c.strip() for c in lines[0::2]), lines[1::2]))
    kind = tags[0][1].strip()
    layer = next((v.strip().upper() for c, v in tags if c == "8"), "")
    if layer != layer_name:
        return True  # the layer was not this entity's layer tag
    if kind == "LINE":
        get = dict(tags)
        lw.add(
            np.array([[float(get["10"]), float(get["20"])], [float(get["11"]), float(get["21"])]])
            * unit,
            False,
        )
        return True
    if any(c in ("210", "220", "230") for c, _ in tags):
        return False  # an extrusion direction (OCS): the full reader maps it to world coordinates
    if kind != "LWPOLYLINE":
        return False  # curves, old-style polylines, blocks: the full reader
    if any(c == "42" and float(v) != 0.0 for c, v in tags):
        return False  # an arc segment
    xs = [float(v) for c, v in tags if c == "10"]
    ys = [float(v) for c, v in tags if c == "20"]
    if len(xs) != len(ys):
        return False
    flags = next((int(v) for c, v in tags if c == "70"), 0)
    lw.add(np.column_stack([xs, ys]).reshape(-1, 2) * unit, bool(flags & 1))
    return True
