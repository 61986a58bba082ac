"""The report's sections about what was made from a design: deployment, cut sheets, print plates, assembly,
bill of materials and tolerance, each read from the folder its command wrote (and its manifest)."""

from __future__ import annotations

import html
import json
from pathlib import Path
from typing import cast

from ..verify.printmanifest import PrintManifest
from .deployment import _pyplot
from .htmlparts import MIME, _fig_png, _img, _missing, rows_table, screen_svg, table


def _load_dir(folder: str | None) -> tuple[Path | None, dict | None]:
    if not folder:
        return None, None
    d = Path(folder)
    man = d / "manifest.json"
    return d, (json.loads(man.read_text("utf-8")) if man.is_file() else None)


def _pictures(d: Path, names: list[str], caption: str) -> str:
    out = []
    for n in names:
        p = d / n
        if p.is_file() and p.suffix.lower() in MIME:
            out.append(_img(p.read_bytes(), p.suffix.lower(), n, f"{caption}: {n}"))
    return '<div class="grid">' + "".join(out) + "</div>" if out else ""


def _deploy_section(folder: str | None) -> str:
    if not folder:
        return _missing(
            "not provided: run fabkiri deploy PATTERN --plot --gif -o DIR and pass --deploy DIR"
        )
    d = Path(folder)
    body = _pictures(d, ["energy.png", "deploy.gif"], "deployment")
    summary = d / "deploy.json"
    if summary.is_file():
        s = json.loads(summary.read_text("utf-8"))
        keep = (
            "path",
            "driver",
            "frames",
            "energy_max",
            "t_at_energy_max",
            "energy_at_states",
            "collision_free",
            "hinge_gap_max_mm",
            "state_mismatch_mm",
        )
        body += table({k: s[k] for k in keep if k in s})
    return body or _missing(f"{d}: no energy.png, deploy.gif or deploy.json")


def _cut_section(d: Path | None, man: dict | None) -> str:
    if d is None or man is None:
        return _missing("not provided: run fabkiri cut PATTERN -o DIR and pass --cut DIR")
    previews = [n for n in man.get("files", []) if n.endswith(".png") and n != "assembly.png"]
    v = man.get("verification") or {}
    body = table(
        {
            "material": man["material"]["name"],
            "hinge": man["hinge"],
            "layout": man["layout"],
            "closed state": man["state"],
            "scale": man["scale"],
            "kerf (mm)": man["kerf_mm"],
            "sheets": len(man.get("sheets", [])),
            "read-back verification": v.get("ok"),
            "layout verifier": (v.get("verifier") or {}).get("ok"),
        }
    )
    body += _pictures(d, previews, "preview")
    body += "<h3>sheets (SVG, as sent to the laser)</h3>" + "".join(
        _sheet_picture(d, sh) for sh in man.get("sheets", []) if sh.get("svg")
    )
    return body


def _sheet_picture(d: Path, sheet: dict) -> str:
    p = d / sheet["svg"]
    if not p.is_file():
        return ""
    shown = screen_svg(p.read_text("utf-8"))
    caption = (
        f"sheet {sheet.get('index', '')}: {sheet['svg']}, {sheet.get('width_mm', 0):g} x "
        f"{sheet.get('height_mm', 0):g} mm, {sheet.get('tiles', '?')} tiles, cut "
        f"{sheet.get('cut_length_mm', 0) / 1000:.2f} m (lines drawn 1 px wide here)"
    )
    return _img(shown.encode("utf-8"), ".svg", sheet["svg"], caption)


def _print_section(d: Path | None, man: PrintManifest | None) -> str:
    if d is None or man is None:
        return _missing("not provided: run fabkiri print PATTERN -o DIR and pass --print DIR")
    mesh_check, verifier = man.check("meshes") or {}, man.check("verifier")
    body = table(
        {
            "style": man.style,
            "closed state": man.state,
            "printer": man.printer_name,
            "beds": len(man.beds),
            "meshes ok": mesh_check.get("ok"),
            "tiles check": (man.check("tiles") or {}).get("ok"),
            "verifier": verifier.get("ok") if verifier else "n/a",
        }
    )
    previews = [n for n in man.files if n.endswith(".png") and n != "assembly.png"]
    shown = _pictures(d, previews, "print preview")
    if not shown:  # no preview written by print: draw the plates from the meshes, seen from above
        meshes = [n for n in man.files if n.endswith(".stl") and (d / n).is_file()]
        shown = (
            '<div class="grid">'
            + "".join(
                _img(plate_png(d / n), ".png", n, f"plate seen from above, drawn from {n}")
                for n in meshes[:4]
            )
            + "</div>"
        )
    return body + (
        shown if meshes_or(shown) else _missing("no print previews or meshes in the folder")
    )


def meshes_or(html_text: str) -> bool:
    return "<img" in html_text


def plate_png(stl: Path) -> bytes:
    """A mesh seen from above: its triangles projected onto the bed, shaded by height."""
    import trimesh
    from matplotlib.collections import PolyCollection

    m = cast(
        trimesh.Trimesh, trimesh.load(stl, force="mesh")
    )  # force="mesh": a Trimesh, annotated as a Geometry
    up = m.face_normals[:, 2] > 1e-6  # faces seen from above
    tri = m.triangles[up]
    z = tri[:, :, 2].mean(1)
    plt = _pyplot()
    fig, ax = plt.subplots(figsize=(7, 5), dpi=110)
    ax.add_collection(PolyCollection(tri[:, :, :2], array=z, cmap="viridis", edgecolors="none"))
    lo, hi = m.bounds[0], m.bounds[1]
    ax.set_xlim(lo[0] - 2, hi[0] + 2)
    ax.set_ylim(lo[1] - 2, hi[1] + 2)
    ax.set_aspect("equal")
    ax.ticklabel_format(useOffset=False, style="plain")
    ax.set_xlabel("bed x (mm)", fontsize=8)
    ax.set_ylabel("bed y (mm)", fontsize=8)
    ax.tick_params(labelsize=7)
    ax.set_title(
        f"{stl.name}: {len(m.faces)} triangles, {m.bounds[1][0] - lo[0]:.0f} x {hi[1] - lo[1]:.0f} x "
        f"{hi[2] - lo[2]:.1f} mm",
        fontsize=9,
    )
    return _fig_png(fig)


def _assembly_section(
    cut_dir: Path | None, cut_man: dict | None, print_dir: Path | None, print_man: dict | None
) -> str:
    body = ""
    for d, man, what in ((cut_dir, cut_man, "cut"), (print_dir, print_man, "print")):
        if d is None or man is None:  # (a manifest comes with its folder)
            continue
        a = man.get("assembly")
        if isinstance(a, dict) and a.get("steps"):
            steps = "".join(
                f"<li>{html.escape(s)}</li>" for s in a["steps"]
            )  # the steps carry their own numbers
            body += f'<h3>{what}</h3><ul class="steps">{steps}</ul>'
        elif isinstance(a, str):
            body += f"<h3>{what}</h3><p>{html.escape(a)}</p>"
        body += _pictures(d, ["assembly.png"], f"{what} assembly map")
        if man.get("assembly_pieces"):
            body += rows_table(man["assembly_pieces"])
    return body or _missing("not provided: pass --cut DIR and/or --print DIR")


def _bom_section(cut_man: dict | None, print_man: PrintManifest | None) -> str:
    body = ""
    if cut_man is not None:
        bom = cut_man.get("bill_of_materials")
        body += "<h3>cut</h3>" + (
            table(bom) if bom else _missing("the cut manifest has no bill of materials")
        )
    if print_man is not None:
        bom = print_man.bill_of_materials
        if bom:
            body += "<h3>print</h3>" + table(
                {k: v for k, v in bom.items() if k not in ("bodies", "filament")}
            )
            body += rows_table([{"material": m, **f} for m, f in bom["filament"].items()])
        else:
            body += "<h3>print</h3>" + _missing("the print manifest has no bill of materials")
    return body or _missing("not provided: pass --cut DIR and/or --print DIR")


def _tolerance_section(folder: str | None) -> str:
    if not folder:
        return _missing(
            "not provided: run fabkiri tolerance PATTERN -o DIR and pass --tolerance DIR"
        )
    d = Path(folder)
    body = _pictures(d, ["tolerance.png"], "tolerance")
    f = d / "tolerance.json"
    if f.is_file():
        t = json.loads(f.read_text("utf-8"))
        rows = [
            {"measure": k, "state": s, **{q: v[q] for q in ("p50", "p95", "max")}}
            for k in ("closure_gap_mm", "seam_gap_mm", "overlap_max_mm2")
            for s, v in t.get(k, {}).items()
        ]
        ol = t.get("deployed_outline_mm")
        if ol:
            rows.append(
                {
                    "measure": "deployed_outline_mm",
                    "state": "deployed",
                    **{q: ol[q] for q in ("p50", "p95", "max")},
                }
            )
        body += (
            table(t.get("model", {}))
            + rows_table(rows)
            + rows_table(t.get("most_sensitive_tiles", []))
        )
    return body or _missing(f"{d}: no tolerance.png or tolerance.json")
