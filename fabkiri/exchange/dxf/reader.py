"""Reading DXF files: the linework of one layer of any DXF, and fabkiri's own DXF for its checks.

:func:`read_cut_dxf` reads the CUT layer (or another named one) of any DXF a laser tool writes,
in millimetres: a fast scan of that layer's tags (:func:`.tags.read_layer_tags`) and ezdxf's full
reader (blocks exploded, curves flattened, any units) for everything else. :func:`read_dxf_checked`
re-reads a DXF fabkiri wrote, for the writer's own checks: fast from its tags when it is the
canonical layout (large files) and with ezdxf's loader and auditor otherwise.
"""

from __future__ import annotations

import io
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any, cast

import numpy as np

from ...errors import VerifyError
from ..drawing import LAYERS
from ..linework import NON_CUT_LAYERS, Linework, Polylines
from .tags import CANON_CODES, INSUNITS_MM, Tags, entities_span, read_layer_tags, split_tags

if TYPE_CHECKING:  # ezdxf is imported where a file is read
    from ezdxf.audit import Auditor
    from ezdxf.document import Drawing
    from ezdxf.entities import LWPolyline

Entity = tuple[str, tuple[np.ndarray, bool]]  # a modelspace LWPOLYLINE: (layer, (points, closed))


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


# ------------------------------------------------------------------ any DXF's linework


def read_cut_dxf(p: Path, layer: str = "CUT") -> Linework:
    """The linework of ``layer`` of a DXF in mm (the tags' fast scan, else ezdxf's full reader)."""
    fast = read_layer_tags(p, layer)
    if fast is not None:
        return fast
    return _read_dxf_full(p, layer)


CURVE_TYPES = {"LWPOLYLINE", "POLYLINE", "LINE", "ARC", "CIRCLE", "SPLINE", "ELLIPSE"}


def _read_dxf_full(p: Path, layer_name: str = "CUT") -> Linework:
    """Every curve of the modelspace in world coordinates, blocks exploded, with its layer and colour.

    ezdxf does the work: ``recover`` reads damaged files, ``disassemble.recursive_decompose``
    expands INSERTs (any depth, with their transforms), ``to_primitives`` gives each entity's path
    in WCS (its OCS applied, curves flattened to 1 µm).
    """
    import ezdxf
    from ezdxf import disassemble, recover
    from ezdxf.lldxf.validator import is_binary_dxf_file

    try:
        # ezdxf's recover reads ASCII DXF only; its plain reader takes binary DXF
        doc = ezdxf.readfile(str(p)) if is_binary_dxf_file(str(p)) else recover.readfile(str(p))[0]
    except (OSError, ezdxf.DXFError, UnicodeDecodeError, ValueError) as exc:
        raise VerifyError(f"{p}: not a readable DXF file ({exc})") from None
    unit = INSUNITS_MM.get(int(doc.header.get("$INSUNITS", 0)))
    if unit is None:
        raise VerifyError(f"{p}: unsupported drawing units $INSUNITS={doc.header.get('$INSUNITS')}")
    lw = Linework(p, layer_found=False)
    layer_colour = {layer.dxf.name.upper(): layer.color for layer in doc.layers}
    flat = 0.001 / unit
    for prim in disassemble.to_primitives(disassemble.recursive_decompose(doc.modelspace()), flat):
        e = prim.entity
        if e is None or e.dxftype() not in CURVE_TYPES or prim.path is None:
            lw.unread.append(e.dxftype() if e is not None else "entity")
            continue
        layer = e.dxf.layer.upper()
        aci = e.dxf.get("color", 256)
        colour = str(layer_colour.get(layer, 7) if aci in (0, 256) else aci)
        closed = bool(
            getattr(e, "closed", False) or getattr(e, "is_closed", False) or e.dxftype() == "CIRCLE"
        )
        for sub in prim.path.sub_paths():
            pts = np.array([(v.x, v.y) for v in sub.flattening(flat)], dtype=float)
            lw.add(pts * unit, closed, layer, colour)
    if layer_name != "CUT" or any(name == "CUT" for name in lw.layers):
        found = any(name == layer_name for name in lw.layers)
        lw = lw.subset(i for i, name in enumerate(lw.layers) if name == layer_name)
        lw.layer_found = found
    else:  # a plain file from another tool: every outline not on an annotation layer
        lw = lw.subset(i for i, name in enumerate(lw.layers) if name not in NON_CUT_LAYERS)
    return lw
