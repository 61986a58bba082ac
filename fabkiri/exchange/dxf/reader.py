"""Reading the written DXF and SVG bytes back into polylines, for the writer's own checks.

:func:`read_dxf_checked` re-reads a DXF fast from its tags when it is fabkiri's canonical layout
(large files, through the tag codec :mod:`fabkiri.exchange.dxfcodec`) and with ezdxf's loader and
auditor otherwise; :func:`read_svg` (:mod:`fabkiri.exchange.svgread`) reads the SVG's paths in its
declared millimetres. The polylines are compared and audited in :mod:`.readback`.
"""

from __future__ import annotations

import io
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, cast

import numpy as np

from .drawing import LAYERS
from .dxfcodec import CANON_CODES, Tags, entities_span, split_tags
from .linework import Polylines, flat_polylines
from .svgread import read_svg_layers as read_svg

if TYPE_CHECKING:  # ezdxf is imported where a file is read
    from ezdxf.audit import Auditor
    from ezdxf.document import Drawing
    from ezdxf.entities import LWPolyline

Entity = tuple[str, tuple[np.ndarray, bool]]  # a modelspace LWPOLYLINE: (layer, (points, closed))

__all__ = [
    "DxfReadback",
    "Polylines",
    "duplicate_segments",
    "flat_polylines",
    "read_dxf",
    "read_dxf_checked",
    "read_svg",
]


def read_dxf(
    data: bytes,
) -> tuple[Drawing, Auditor, dict[str, list[tuple[np.ndarray, bool]]], list[str]]:
    """``(doc, auditor, layers)`` with ``layers[name] = [(points, closed), ...]``."""
    import ezdxf

    doc = ezdxf.read(io.StringIO(data.decode("ascii")))
    auditor = doc.audit()
    layers: dict[str, list[tuple[np.ndarray, bool]]] = {}
    _, _, items, others = _entities_of(doc)
    for item in items:
        if item is not None:
            layers.setdefault(item[0], []).append(item[1])
    return doc, auditor, layers, others


FULL_AUDIT_MAX = (
    2000  # files with at most this many canonical stroke entities are loaded whole by ezdxf
)


@dataclass
class DxfReadback:
    """What the self checks need from a DXF: header facts, audit errors, polylines per layer."""

    insunits: Any
    dxfversion: str
    audit_errors: list[str]
    layers: Mapping[
        str, Sequence[tuple[np.ndarray, bool]]
    ]  # (points, closed) per layer, in file order
    others: list[str]
    bulk_entities: int = 0  # entities checked from their tags instead of being loaded by ezdxf


def _audit_strokes(doc: Drawing, tags: Tags, canon: np.ndarray, layer_of: np.ndarray) -> list[str]:
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
    if len(np.unique(handles)) != len(handles) or any(
        h in doc.entitydb for h in set(handles.tolist())
    ):
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


def _stroke_coords(tags: Tags, errors: list[str]) -> np.ndarray:
    """The 10/20 values of the canonical entities as ``(P, 2)`` floats (NaN, and an
    error, where one is not a number)."""
    tag = np.flatnonzero(~tags.bad[tags.eid] & (tags.off >= len(CANON_CODES)))
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
    span = entities_span(text)
    if span is None:
        return _full(data)
    lo, hi = span
    tags = split_tags(text[lo:hi].split("\n")[:-1])
    if tags is None:
        return _full(data)
    canon = np.flatnonzero(~tags.bad)
    if len(canon) <= full_max:
        return _full(data)
    # ezdxf: everything but the canonical entities
    keep = np.flatnonzero(tags.bad)
    lines, starts, ends = tags.lines, tags.starts, tags.ends
    rest = "".join("\n".join(lines[2 * starts[k] : 2 * ends[k]]) + "\n" for k in keep.tolist())
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
    layers = _layers_in_file_order(
        xy, canon, layer_of, tags.nv[tags.good], tags.flags[tags.good] == "1", items
    )
    return DxfReadback(
        doc.header.get("$INSUNITS"), doc.dxfversion, errors, layers, others, len(canon)
    )


def _layers_in_file_order(
    xy: np.ndarray,
    canon: np.ndarray,
    layer_of: np.ndarray,
    n_canon: np.ndarray,
    closed: np.ndarray,
    items: list[tuple[int, Entity]],
) -> dict[str, Polylines]:
    """Polylines per layer in the file's order: the canonical ones from their tags,
    merged by position with the ``items`` ``(entity, (layer, polyline))`` ezdxf read."""
    point_layer = np.repeat(layer_of, n_canon)
    names = set(layer_of.tolist())
    layers: dict[str, Polylines] = {}
    for name in sorted(
        names | {item[0] for _, item in items}, key=lambda n: LAYERS.index(n) if n in LAYERS else 99
    ):
        sel = layer_of == name
        mine = Polylines(xy[point_layer == name], n_canon[sel], closed[sel])
        extra = [(k, item[1]) for k, item in items if item[0] == name]
        if extra:  # merge by position in the file
            both = sorted(
                [(int(k), pl) for k, pl in zip(canon[sel].tolist(), mine)] + extra,
                key=lambda kv: kv[0],
            )
            mine = Polylines.of([pl for _, pl in both])
        layers[name] = mine
    return layers


def _entities_of(doc: Drawing) -> tuple[None, None, list[Entity | None], list[str]]:
    """``(None, None, items, others)``: per modelspace entity ``(layer, (points, closed))`` or None."""
    items: list[Entity | None] = []
    others: list[str] = []
    for e in doc.modelspace():
        if e.dxftype() != "LWPOLYLINE":
            others.append(e.dxftype())
            items.append(None)
            continue
        lw = cast("LWPolyline", e)  # its dxftype says so
        pts = np.asarray([(p[0], p[1]) for p in lw.get_points("xy")], dtype=float)
        items.append((lw.dxf.layer, (pts, bool(lw.closed))))
    return None, None, items, others


def _full(data: bytes) -> DxfReadback:
    doc, aud, layers, others = read_dxf(data)
    return DxfReadback(
        doc.header.get("$INSUNITS"),
        doc.dxfversion,
        [f"{e.code}: {e.message}" for e in aud.errors],
        layers,
        others,
    )


def _segments(polylines: Sequence[tuple[np.ndarray, bool]]) -> np.ndarray:
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


def duplicate_segments(polylines: Sequence[tuple[np.ndarray, bool]], decimals: int = 6) -> int:
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
