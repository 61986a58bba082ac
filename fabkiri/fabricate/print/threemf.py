"""3MF print projects a slicer opens ready to print (``fabkiri print``).

One 3MF per bed holds **one object** (the printable assembly: the closed
pattern's tiles and strips, or one bed of loose strips) whose parts are
*volumes*: triangle ranges of the object's mesh (the 3MF core allows a mesh
per object; PrusaSlicer splits it into parts with ``firstid``/``lastid`` in
``Metadata/Slic3r_PE_model.config``). Each part names its material twice:
per triangle through the core spec's ``<basematerials>`` (read by any 3MF
consumer, Bambu Studio/Orca among them), and as the part's ``extruder`` in
PrusaSlicer's model config. ``Metadata/Slic3r_PE.config`` carries the project
settings the geometry depends on (bed, nozzle, layer heights, one filament per
extruder), so slicing the file as it is gives the intended print.

Bytes are deterministic: fixed zip dates, no UUIDs, vertices written with
coordinates rounded to 1 nm. Registered as the solid format ``3mf``
(:mod:`fabkiri.exchange.file_formats`): plain 3MFs written by :func:`objects_3mf`, projects and
plain files read back by :func:`read_meshes`.
"""

from __future__ import annotations

import io
import zipfile
from dataclasses import dataclass
from xml.sax.saxutils import quoteattr

import numpy as np

from ...exchange.file_formats import Mesh, SolidFormat, register_format
from .printers import MATERIALS, Printer

CONTENT_TYPES = """<?xml version="1.0" encoding="UTF-8"?>
<Types xmlns="http://schemas.openxmlformats.org/package/2006/content-types">
 <Default Extension="rels" ContentType="application/vnd.openxmlformats-package.relationships+xml"/>
 <Default Extension="model" ContentType="application/vnd.ms-package.3dmanufacturing-3dmodel+xml"/>
 <Default Extension="config" ContentType="text/plain"/>
 <Default Extension="xml" ContentType="application/xml"/>
</Types>
"""
RELS = """<?xml version="1.0" encoding="UTF-8"?>
<Relationships xmlns="http://schemas.openxmlformats.org/package/2006/relationships">
 <Relationship Target="/3D/3dmodel.model" Id="rel0" Type="http://schemas.microsoft.com/3dmanufacturing/2013/01/3dmodel"/>
</Relationships>
"""
CORE_NS = "http://schemas.microsoft.com/3dmanufacturing/core/2015/02"
SLIC3R_NS = "http://schemas.slic3r.org/3mf/2017/06"
CHANGE_TYPES = {"colour-change": (0, "M600"), "pause": (1, "M601")}  # PrusaSlicer CustomGCode::Type


@dataclass(frozen=True)
class Part:
    """One volume of the printed object."""

    name: str
    material: str
    vertices: np.ndarray  # (V, 3) mm, bed coordinates
    faces: np.ndarray  # (F, 3)


@dataclass(frozen=True)
class LayerChange:
    """A custom G-code at a print height (a single-extruder material swap)."""

    print_z: float
    kind: str  # key of CHANGE_TYPES
    material: str


def _rows(fmt: str, a: np.ndarray) -> str:
    line = fmt + "\n"
    return "".join(map(line.__mod__, map(tuple, a.tolist())))


def model_xml(object_name: str, parts: list[Part]) -> str:
    mats = sorted({p.material for p in parts}, key=lambda m: (m not in MATERIALS, m))
    out = [
        f'<?xml version="1.0" encoding="UTF-8"?>\n<model unit="millimeter" xml:lang="en-US" '
        f'xmlns="{CORE_NS}" xmlns:slic3rpe="{SLIC3R_NS}">\n',
        ' <metadata name="slic3rpe:Version3mf">1</metadata>\n',
        ' <metadata name="Application">fabkiri</metadata>\n <resources>\n  <basematerials id="1">\n',
    ]
    for m in mats:
        colour = MATERIALS[m].colour if m in MATERIALS else "#808080"
        out.append(f'   <base name={quoteattr(m)} displaycolor="{colour}FF"/>\n')
    out.append(
        f'  </basematerials>\n  <object id="2" type="model" name={quoteattr(object_name)} pid="1" pindex="0">\n'
        "   <mesh>\n    <vertices>\n"
    )
    offset = 0
    tris = []
    for p in parts:
        v = (
            np.round(np.asarray(p.vertices, dtype=np.float64), 6) + 0.0
        )  # 1 nm; + 0.0 turns -0 into 0
        out.append(_rows('     <vertex x="%.6f" y="%.6f" z="%.6f"/>', v))
        k = mats.index(p.material)
        f = np.asarray(p.faces, dtype=np.int64) + offset
        tris.append(_rows(f'     <triangle v1="%d" v2="%d" v3="%d" pid="1" p1="{k}"/>', f))
        offset += len(v)
    out.append("    </vertices>\n    <triangles>\n")
    out.extend(tris)
    out.append(
        "    </triangles>\n   </mesh>\n  </object>\n </resources>\n"
        ' <build>\n  <item objectid="2"/>\n </build>\n</model>\n'
    )
    return "".join(out)


def model_config_xml(object_name: str, parts: list[Part], printer: Printer) -> str:
    """PrusaSlicer's per-volume metadata: name, part type, extruder."""
    out = [
        '<?xml version="1.0" encoding="UTF-8"?>\n<config>\n <object id="2" instances_count="1">\n',
        f'  <metadata type="object" key="name" value={quoteattr(object_name)}/>\n',
    ]
    first = 0
    for p in parts:
        last = first + len(p.faces) - 1
        out.append(
            f'  <volume firstid="{first}" lastid="{last}">\n'
            f'   <metadata type="volume" key="name" value={quoteattr(p.name)}/>\n'
            '   <metadata type="volume" key="volume_type" value="ModelPart"/>\n'
            f'   <metadata type="volume" key="extruder" value="{printer.extruder_of(p.material)}"/>\n'
            '   <mesh edges_fixed="0" degenerate_facets="0" facets_removed="0" facets_reversed="0" '
            'backwards_edges="0"/>\n  </volume>\n'
        )
        first = last + 1
    out.append(" </object>\n</config>\n")
    return "".join(out)


def extruder_materials(printer: Printer, parts: list[Part]) -> list[str]:
    """The filament loaded in each extruder at the start of this print (one
    extruder: the material of the lowest part, the first one printed)."""
    if printer.extruders > 1:
        return list(printer.materials or (printer.tile_material, printer.strip_material))
    return [min(parts, key=lambda p: float(np.min(p.vertices[:, 2]))).material]


def project_config(printer: Printer, loaded: list[str]) -> dict[str, str]:
    """PrusaSlicer settings (``; key = value``) the printed geometry depends on."""
    bx, by, bz = printer.bed_mm
    n = len(loaded)
    st = [MATERIALS[m] for m in loaded]
    per = lambda vals, sep=",": sep.join(str(v) for v in vals)  # noqa: E731
    cfg = {
        "printer_technology": "FFF",
        "bed_shape": f"0x0,{bx:g}x0,{bx:g}x{by:g},0x{by:g}",
        "max_print_height": f"{bz:g}",
        "nozzle_diameter": per([printer.nozzle_mm] * n),
        "layer_height": f"{printer.layer_mm:g}",
        "first_layer_height": f"{printer.first_layer_mm:g}",
        "filament_type": per([s.slicer_type for s in st], ";"),
        "filament_colour": per([s.colour for s in st], ";"),
        "extruder_colour": per([s.colour for s in st], ";"),
        "temperature": per([s.nozzle_c for s in st]),
        "first_layer_temperature": per([s.nozzle_c for s in st]),
        "bed_temperature": per([max(s.bed_c for s in st)] * n),
        "first_layer_bed_temperature": per([max(s.bed_c for s in st)] * n),
        "gcode_flavor": "marlin2",
        "use_relative_e_distances": "1",
        "layer_gcode": "G92 E0",
        "pause_print_gcode": "M601",
        "color_change_gcode": "M600",
        "perimeters": "2",
        "skirts": "0",  # a skirt round a full bed of strips would run off it
        "wipe_tower": "1" if n > 1 else "0",
    }
    if n > 1:  # the wipe tower in the bed's front-left corner, clear of the centred parts
        cfg.update(
            {
                "wipe_tower_x": "10",
                "wipe_tower_y": "10",
                "wipe_tower_width": "40",
                "wipe_tower_rotation_angle": "0",
            }
        )
    return cfg


def config_text(cfg: dict[str, str]) -> str:
    return "; generated by fabkiri\n\n" + "".join(f"; {k} = {v}\n" for k, v in sorted(cfg.items()))


def custom_gcode_xml(changes: list[LayerChange]) -> str:
    out = ['<?xml version="1.0" encoding="utf-8"?>\n<custom_gcodes_per_print_z>\n']
    for c in sorted(changes, key=lambda c: c.print_z):
        t, code = CHANGE_TYPES[c.kind]
        colour = MATERIALS[c.material].colour if c.material in MATERIALS else "#808080"
        extra = f"load {c.material}"
        out.append(
            f'<code print_z="{c.print_z:.4f}" type="{t}" extruder="1" color="{colour}" '
            f'extra={quoteattr(extra)} gcode="{code}"/>\n'
        )
    out.append('<mode value="SingleExtruder"/>\n</custom_gcodes_per_print_z>\n')
    return "".join(out)


def _zip(entries: dict[str, str]) -> bytes:
    out = io.BytesIO()
    with zipfile.ZipFile(out, "w", compression=zipfile.ZIP_DEFLATED) as zf:
        for name, text in entries.items():
            info = zipfile.ZipInfo(name, date_time=(1980, 1, 1, 0, 0, 0))
            info.compress_type = zipfile.ZIP_DEFLATED
            info.external_attr = 0o644 << 16
            zf.writestr(info, text.encode("utf-8"))
    return out.getvalue()


def objects_3mf(meshes: dict[str, tuple[np.ndarray, np.ndarray]]) -> bytes:
    """A plain 3MF with one object (and build item) per named mesh (vertices, faces),
    for files that are not print projects (e.g. the calibration coupon)."""
    out = [
        f'<?xml version="1.0" encoding="UTF-8"?>\n<model unit="millimeter" xml:lang="en-US" xmlns="{CORE_NS}">\n'
        " <resources>\n"
    ]
    for i, (name, (v, f)) in enumerate(meshes.items(), 1):
        v = np.round(np.asarray(v, dtype=np.float64), 6) + 0.0
        out.append(
            f'  <object id="{i}" type="model" name={quoteattr(name)}>\n   <mesh>\n    <vertices>\n'
        )
        out.append(_rows('     <vertex x="%.6f" y="%.6f" z="%.6f"/>', v))
        out.append("    </vertices>\n    <triangles>\n")
        out.append(_rows('     <triangle v1="%d" v2="%d" v3="%d"/>', np.asarray(f, dtype=np.int64)))
        out.append("    </triangles>\n   </mesh>\n  </object>\n")
    out.append(" </resources>\n <build>\n")
    out.extend(f'  <item objectid="{i}"/>\n' for i in range(1, len(meshes) + 1))
    out.append(" </build>\n</model>\n")
    return _zip(
        {
            "[Content_Types].xml": CONTENT_TYPES,
            "_rels/.rels": RELS,
            "3D/3dmodel.model": "".join(out),
        }
    )


def project_3mf(
    object_name: str, parts: list[Part], printer: Printer, changes: list[LayerChange] | None = None
) -> bytes:
    """The 3MF bytes of one bed: one object, one volume per part, project settings."""
    loaded = extruder_materials(printer, parts)
    entries = {
        "[Content_Types].xml": CONTENT_TYPES,
        "_rels/.rels": RELS,
        "3D/3dmodel.model": model_xml(object_name, parts),
        "Metadata/Slic3r_PE_model.config": model_config_xml(object_name, parts, printer),
        "Metadata/Slic3r_PE.config": config_text(project_config(printer, loaded)),
    }
    if changes:
        entries["Metadata/Prusa_Slicer_custom_gcode_per_print_z.xml"] = custom_gcode_xml(changes)
    return _zip(entries)


def read_volumes(data: bytes) -> list[tuple[str, str, int, np.ndarray, np.ndarray]]:
    """Per volume of a project 3MF as written: (name, material, extruder,
    vertices, faces), split by the model config's triangle ranges and
    checked against the triangles' basematerials."""
    import re

    from lxml import etree

    zf = zipfile.ZipFile(io.BytesIO(data))
    text = zf.read("3D/3dmodel.model").decode("utf-8")
    if text.count("<object ") != 1:
        raise ValueError("a fabkiri 3MF project holds exactly one object")
    bases = re.findall(r'<base name="([^"]*)"', text)
    v = np.array(re.findall(r'<vertex x="([^"]+)" y="([^"]+)" z="([^"]+)"', text), dtype=float)
    t = np.array(
        re.findall(r'<triangle v1="(\d+)" v2="(\d+)" v3="(\d+)" pid="1" p1="(\d+)"', text),
        dtype=np.int64,
    )
    if len(t) != text.count("<triangle "):
        raise ValueError("triangles without their basematerial")
    f, mat = t[:, :3], t[:, 3]
    cfg = etree.fromstring(zf.read("Metadata/Slic3r_PE_model.config"))
    out = []
    for vol in cfg.iter("volume"):
        a, b = int(vol.get("firstid")), int(vol.get("lastid")) + 1
        meta = {m.get("key"): m.get("value") for m in vol.iter("metadata")}
        used = np.unique(mat[a:b])
        if len(used) != 1:
            raise ValueError(f"volume {meta.get('name')} mixes materials {used.tolist()}")
        fv = f[a:b]
        keep = np.unique(fv)
        remap = np.full(len(v), -1)
        remap[keep] = np.arange(len(keep))
        out.append(
            (
                meta.get("name", ""),
                bases[int(used[0])],
                int(meta.get("extruder", "1")),
                v[keep],
                remap[fv],
            )
        )
    return out


def read_meshes(data: bytes) -> list[Mesh]:
    """The named meshes of a 3MF as fabkiri writes it: a project's volumes (:func:`read_volumes`),
    or the objects of a plain 3MF (:func:`objects_3mf`)."""
    import re

    zf = zipfile.ZipFile(io.BytesIO(data))
    if "Metadata/Slic3r_PE_model.config" in zf.namelist():
        return [(name, v, f) for name, _, _, v, f in read_volumes(data)]
    text = zf.read("3D/3dmodel.model").decode("utf-8")
    out: list[Mesh] = []
    for name, body in re.findall(
        r'<object id="\d+" type="model" name="([^"]*)">(.*?)</object>', text, re.S
    ):
        v = re.findall(r'<vertex x="([^"]+)" y="([^"]+)" z="([^"]+)"', body)
        f = re.findall(r'<triangle v1="(\d+)" v2="(\d+)" v3="(\d+)"', body)
        out.append(
            (
                name,
                np.array(v, dtype=float).reshape(-1, 3),
                np.array(f, dtype=np.int64).reshape(-1, 3),
            )
        )
    return out


register_format(SolidFormat("3mf", (".3mf",), write=objects_3mf, read=read_meshes))
