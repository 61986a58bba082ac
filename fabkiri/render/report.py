"""``fabkiri report``: one self-contained HTML page about a design and what was made from it.

Everything is inlined (images as data URIs, CSS in the page, no network, no
external script), so the file can be mailed or archived alone. Sections, each
a ``<section id=...>``: summary, design vs target (with the conformance
figures in ``design.report.conformance`` when the design stored them), closed
states (vs their outline targets when stored), fabricability
(``design.report.fabricability``), verification, deployment (energy landscape,
animation), cut sheets, print plates, assembly, bill of materials, tolerance.
A section without its data says so ("not computed", "not provided: run ...").

A small inline script counts script errors into ``#console-errors`` so a
headless browser's ``--dump-dom`` shows whether the page ran clean.
"""

from __future__ import annotations

import base64
import html
import io
import json
from pathlib import Path
from typing import TYPE_CHECKING, Any, cast

import numpy as np

from ..mechanics.info import describe
from ..pattern.model import Pattern
from ..verify import verify_pattern
from ..verify.printmanifest import PrintManifest
from .deployment import _pyplot

if TYPE_CHECKING:  # matplotlib is imported where a picture is drawn
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

SECTIONS = ("summary", "design", "states", "fabricability", "verification", "deployment", "cut", "print",
            "assembly", "bom", "tolerance")
MIME = {".png": "image/png", ".gif": "image/gif", ".svg": "image/svg+xml", ".jpg": "image/jpeg"}

CSS = """
ul.steps{list-style:none;padding-left:0}
body{font:15px/1.45 system-ui,-apple-system,'Segoe UI',sans-serif;margin:0;color:#1d232a;background:#f6f7f9}
header{background:#24313f;color:#fff;padding:18px 28px}header h1{margin:0;font-size:24px}
nav{background:#fff;border-bottom:1px solid #dde;padding:8px 28px;position:sticky;top:0}
nav a{margin-right:14px;color:#245;text-decoration:none;font-size:13px}
section{background:#fff;margin:18px 28px;padding:16px 22px;border-radius:8px;box-shadow:0 1px 3px #0002}
h2{margin-top:0;font-size:19px;border-bottom:2px solid #e4e8ee;padding-bottom:6px}
table{border-collapse:collapse;margin:8px 0;font-size:13px}td,th{border:1px solid #dde;padding:3px 8px;text-align:left}
th{background:#f0f3f7}img{max-width:100%;height:auto;border:1px solid #e4e8ee;margin:6px 0}
.missing{color:#8a5a00;background:#fff6e0;padding:6px 10px;border-radius:4px;display:inline-block}
.ok{color:#1b7a2f;font-weight:600}.fail{color:#b3261e;font-weight:600}
pre{background:#f3f5f8;padding:8px;overflow-x:auto;font-size:12px}.grid{display:flex;flex-wrap:wrap;gap:14px}
.grid figure{margin:0;flex:1 1 380px}figcaption{font-size:12px;color:#556}
"""

ERROR_HOOK = """<script>
(function(){var n=0;function show(){var e=document.getElementById('console-errors');
if(e){e.setAttribute('data-count',String(n));e.textContent=n?('script errors: '+n):'';}}
window.addEventListener('error',function(){n++;show();},true);
window.addEventListener('unhandledrejection',function(){n++;show();});
var ce=console.error;console.error=function(){n++;show();return ce.apply(console,arguments);};
document.addEventListener('DOMContentLoaded',function(){
var imgs=document.images,k;for(k=0;k<imgs.length;k++){if(imgs[k].complete&&imgs[k].naturalWidth===0){n++;}}
document.body.setAttribute('data-loaded','1');show();});})();
</script>"""


def data_uri(data: bytes, suffix: str) -> str:
    return f"data:{MIME[suffix]};base64,{base64.b64encode(data).decode('ascii')}"


def _img(data: bytes, suffix: str, alt: str, caption: str = "") -> str:
    cap = f"<figcaption>{html.escape(caption)}</figcaption>" if caption else ""
    return f'<figure><img alt="{html.escape(alt)}" src="{data_uri(data, suffix)}">{cap}</figure>'


def _missing(text: str) -> str:
    return f'<p class="missing">{html.escape(text)}</p>'


def _fmt(v: Any) -> str:
    if v is None:
        return "n/a"
    if isinstance(v, bool):
        return '<span class="ok">yes</span>' if v else '<span class="fail">no</span>'
    if isinstance(v, float):
        return f"{v:.6g}" if abs(v) >= 1e3 else f"{v:.4g}"
    if isinstance(v, (list, tuple)) and len(v) <= 8 and all(not isinstance(x, (dict, list)) for x in v):
        return ", ".join(_fmt(x) for x in v)
    if isinstance(v, (list, tuple)) and len(v) <= 8 and all(isinstance(x, (list, tuple)) and len(x) <= 4 for x in v):
        return "; ".join(" x ".join(_fmt(y) for y in x) for x in v)
    if isinstance(v, dict) and len(v) <= 8 and all(not isinstance(x, (dict, list)) for x in v.values()):
        return "<br>".join(f"{html.escape(str(k))}: {_fmt(x)}" for k, x in v.items())
    if isinstance(v, (dict, list)):
        return f"<pre>{html.escape(json.dumps(v, indent=1)[:3000])}</pre>"
    return html.escape(str(v))


def table(d: dict[str, Any], head: tuple[str, str] = ("", "")) -> str:
    rows = "".join(f"<tr><th>{html.escape(str(k))}</th><td>{_fmt(v)}</td></tr>" for k, v in d.items())
    h = f"<tr><th>{html.escape(head[0])}</th><th>{html.escape(head[1])}</th></tr>" if any(head) else ""
    return f"<table>{h}{rows}</table>"


def rows_table(rows: list[dict[str, Any]], limit: int = 60) -> str:
    if not rows:
        return ""
    keys = list(rows[0])
    body = "".join("<tr>" + "".join(f"<td>{_fmt(r.get(k))}</td>" for k in keys) + "</tr>" for r in rows[:limit])
    more = f"<p>… {len(rows) - limit} more rows in the manifest</p>" if len(rows) > limit else ""
    return ("<table><tr>" + "".join(f"<th>{html.escape(k)}</th>" for k in keys) + f"</tr>{body}</table>{more}")


def _fig_png(fig: Figure) -> bytes:
    buf = io.BytesIO()
    fig.savefig(buf, format="png", metadata={"Software": None}, bbox_inches="tight")
    _pyplot().close(fig)
    return buf.getvalue()


def _tiles(ax: Axes, corners: np.ndarray, color: str = "#b8c7d9") -> None:
    from matplotlib.collections import PolyCollection

    # matplotlib's stubs ask for a sequence of vertex arrays; a (T, k, 2) array is one (and its fast path)
    ax.add_collection(PolyCollection(corners, facecolors=color,  # type: ignore[arg-type]
                                     edgecolors="#34495e", linewidths=0.4))
    lo, hi = corners.reshape(-1, 2).min(0), corners.reshape(-1, 2).max(0)
    pad = 0.04 * float((hi - lo).max())
    ax.set_xlim(lo[0] - pad, hi[0] + pad)
    ax.set_ylim(lo[1] - pad, hi[1] + pad)
    ax.set_aspect("equal")
    ax.ticklabel_format(useOffset=False, style="plain")
    ax.tick_params(labelsize=7)


def design_png(pattern: Pattern) -> bytes:
    """The deployed tiles with the target outline (when the design stored one) drawn over them."""
    plt = _pyplot()
    fig, ax = plt.subplots(figsize=(6.4, 5.2), dpi=110)
    _tiles(ax, pattern.corners())
    target = (pattern.design or {}).get("target") or {}
    pts = np.asarray(target.get("points") or [], dtype=float)
    if len(pts) >= 3:
        ring = np.vstack([pts, pts[:1]])
        ax.plot(ring[:, 0], ring[:, 1], color="#d62728", lw=1.4, label=f"target: {target.get('name', '')}")
        ax.legend(fontsize=8, loc="lower right")
        lo = np.minimum(pts.min(0), pattern.nodes.min(0))
        hi = np.maximum(pts.max(0), pattern.nodes.max(0))
        pad = 0.04 * float((hi - lo).max())
        ax.set_xlim(lo[0] - pad, hi[0] + pad)
        ax.set_ylim(lo[1] - pad, hi[1] + pad)
    ax.set_title("deployed design" + (" vs its target" if len(pts) >= 3 else ""), fontsize=10)
    ax.set_xlabel("mm", fontsize=8)
    return _fig_png(fig)


def states_png(pattern: Pattern, states: dict[int, np.ndarray], targets: dict[int, np.ndarray]) -> bytes:
    plt = _pyplot()
    fig, axes = plt.subplots(1, 2, figsize=(10, 4.6), dpi=110)
    for ax, s in zip(axes, (1, 2)):
        _tiles(ax, states[s], "#c9d9b8" if s == 1 else "#e3cfb0")
        if s in targets:
            r = np.vstack([targets[s], targets[s][:1]])
            ax.plot(r[:, 0], r[:, 1], color="#d62728", lw=1.2, label="outline target")
            ax.legend(fontsize=8, loc="lower right")
        ax.set_title(f"closed state {s}", fontsize=10)
        ax.set_xlabel("mm", fontsize=8)
    return _fig_png(fig)


def _contracted_targets(design: dict) -> dict[int, np.ndarray]:
    """Outline targets of the closed states, where the design stored their points."""
    out = {}
    for key in ("contracted_targets", "contracted_target"):
        got = design.get(key)
        if isinstance(got, dict):
            for s, t in got.items():
                pts = t.get("points") if isinstance(t, dict) else t
                try:
                    a = np.asarray(pts, dtype=float)
                except (TypeError, ValueError):
                    continue
                if a.ndim == 2 and a.shape[1] == 2 and len(a) >= 3 and str(s) in ("1", "2"):
                    out[int(s)] = a
    return out


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


def _section(sid: str, title: str, body: str) -> str:
    return f'<section id="{sid}"><h2>{html.escape(title)}</h2>{body}</section>'


def build_report(pattern: Pattern, *, source: str = "", cut: str | None = None, printed: str | None = None,
                 deploy: str | None = None, tolerance: str | None = None, states: dict[int, np.ndarray] | None = None
                 ) -> str:
    """The HTML page (see the module doc). ``states``: both closed states (corners) if the pattern closes."""
    design = pattern.design or {}
    report = design.get("report") or {}
    info = describe(pattern)
    parts: dict[str, str] = {}

    parts["summary"] = table({
        "pattern": pattern.name or source, "file": source, "tiles": info.tiles, "hinges": info.hinges,
        "holes": info.holes, "deployed size (mm)": f"{info.width_mm:.2f} x {info.height_mm:.2f}",
        "mean tile edge (mm)": info.tile_size_mm, "rigid-deployable": info.rigid_deployable,
        "closes in both states": info.closes_both, "design status": report.get("status", "not recorded"),
    })

    body = _img(design_png(pattern), ".png", "design vs target")
    fit = (report.get("fit") or {}).get("shape")
    body += "<h3>fit to the target (solver)</h3>" + (table(fit) if fit else _missing("no fit recorded"))
    conf = report.get("conformance")
    body += "<h3>conformance</h3>" + (table(conf) if isinstance(conf, dict) and conf else
                                       _missing("conformance: not computed (design.report.conformance absent)"))
    parts["design"] = body

    if states:
        targets = _contracted_targets(design)
        body = _img(states_png(pattern, states, targets), ".png", "closed states")
        if not targets:
            body += _missing("no outline targets stored for the closed states")
        body += rows_table([{"closed state": s.state, "closes": s.closes, "loop closure (tile sizes)": s.max_closure_rel,
                             "edge pairs (mm)": s.edge_pair_max_mm, "rings (rad)": s.ring_max_rad}
                            for s in info.states])
    else:
        body = _missing("the pattern does not close in both states: " + "; ".join(info.problems()))
    parts["states"] = body

    fab = report.get("fabricability")
    parts["fabricability"] = (table(fab) if isinstance(fab, dict) and fab else
                              _missing("fabricability: not computed (design.report.fabricability absent)"))

    ver = verify_pattern(pattern)
    v = f'<p>verdict: <span class="{"ok" if ver.ok else "fail"}">{"PASS" if ver.ok else "FAIL"}</span> ' \
        f'({len(ver.checks) - len(ver.failed())}/{len(ver.checks)} checks pass)</p>'
    parts["verification"] = v + f"<pre>{html.escape(ver.to_text())}</pre>"

    parts["deployment"] = _deploy_section(deploy)
    cut_dir, cut_man = _load_dir(cut)
    print_dir, print_man = _load_dir(printed)
    pm = None if print_man is None else PrintManifest.from_dict(print_man, f"{printed}/manifest.json")
    parts["cut"] = _cut_section(cut_dir, cut_man)
    parts["print"] = _print_section(print_dir, pm)
    parts["assembly"] = _assembly_section(cut_dir, cut_man, print_dir, print_man)
    parts["bom"] = _bom_section(cut_man, pm)
    parts["tolerance"] = _tolerance_section(tolerance)

    titles = {"summary": "Summary", "design": "Design vs target", "states": "Closed states",
              "fabricability": "Fabricability", "verification": "Verification", "deployment": "Deployment",
              "cut": "Cut sheets", "print": "Print plates", "assembly": "Assembly map", "bom": "Bill of materials",
              "tolerance": "Tolerance"}
    nav = "".join(f'<a href="#{s}">{titles[s]}</a>' for s in SECTIONS)
    sections = "".join(_section(s, titles[s], parts[s]) for s in SECTIONS)
    name = html.escape(pattern.name or source or "pattern")
    return (f'<!DOCTYPE html><html lang="en"><head><meta charset="utf-8"><title>fabkiri report: {name}</title>'
            f'<meta name="viewport" content="width=device-width, initial-scale=1">'
            f"<style>{CSS}</style>{ERROR_HOOK}</head><body>"
            f"<header><h1>fabkiri report: {name}</h1></header><nav>{nav}</nav>{sections}"
            f'<div id="console-errors" data-count="0"></div></body></html>\n')


def _deploy_section(folder: str | None) -> str:
    if not folder:
        return _missing("not provided: run fabkiri deploy PATTERN --plot --gif -o DIR and pass --deploy DIR")
    d = Path(folder)
    body = _pictures(d, ["energy.png", "deploy.gif"], "deployment")
    summary = d / "deploy.json"
    if summary.is_file():
        s = json.loads(summary.read_text("utf-8"))
        keep = ("path", "driver", "frames", "energy_max", "t_at_energy_max", "energy_at_states", "collision_free",
                "hinge_gap_max_mm", "state_mismatch_mm")
        body += table({k: s[k] for k in keep if k in s})
    return body or _missing(f"{d}: no energy.png, deploy.gif or deploy.json")


def _cut_section(d: Path | None, man: dict | None) -> str:
    if d is None or man is None:
        return _missing("not provided: run fabkiri cut PATTERN -o DIR and pass --cut DIR")
    sheets = [s["svg"] for s in man.get("sheets", []) if s.get("svg")]
    previews = [n for n in man.get("files", []) if n.endswith(".png") and n != "assembly.png"]
    v = man.get("verification") or {}
    body = table({"material": man["material"]["name"], "hinge": man["hinge"], "layout": man["layout"],
                  "closed state": man["state"], "scale": man["scale"], "kerf (mm)": man["kerf_mm"],
                  "sheets": len(man.get("sheets", [])), "read-back verification": v.get("ok"),
                  "layout verifier": (v.get("verifier") or {}).get("ok")})
    body += _pictures(d, previews, "preview")
    body += "<h3>sheets (SVG, as sent to the laser)</h3>" + _pictures(d, sheets, "sheet")
    return body


def _print_section(d: Path | None, man: PrintManifest | None) -> str:
    if d is None or man is None:
        return _missing("not provided: run fabkiri print PATTERN -o DIR and pass --print DIR")
    mesh_check, verifier = man.check("meshes") or {}, man.check("verifier")
    body = table({"style": man.style, "closed state": man.state, "printer": man.printer_name, "beds": len(man.beds),
                  "meshes ok": mesh_check.get("ok"), "tiles check": (man.check("tiles") or {}).get("ok"),
                  "verifier": verifier.get("ok") if verifier else "n/a"})
    previews = [n for n in man.files if n.endswith(".png") and n != "assembly.png"]
    shown = _pictures(d, previews, "print preview")
    if not shown:  # no preview written by print: draw the plates from the meshes, seen from above
        meshes = [n for n in man.files if n.endswith(".stl") and (d / n).is_file()]
        shown = '<div class="grid">' + "".join(
            _img(plate_png(d / n), ".png", n, f"plate seen from above, drawn from {n}") for n in meshes[:4]) + "</div>"
    return body + (shown if meshes_or(shown) else _missing("no print previews or meshes in the folder"))


def meshes_or(html_text: str) -> bool:
    return "<img" in html_text


def plate_png(stl: Path) -> bytes:
    """A mesh seen from above: its triangles projected onto the bed, shaded by height."""
    import trimesh
    from matplotlib.collections import PolyCollection

    m = cast(trimesh.Trimesh, trimesh.load(stl, force="mesh"))  # force="mesh": a Trimesh, annotated as a Geometry
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
    ax.set_title(f"{stl.name}: {len(m.faces)} triangles, {m.bounds[1][0] - lo[0]:.0f} x {hi[1] - lo[1]:.0f} x "
                 f"{hi[2] - lo[2]:.1f} mm", fontsize=9)
    return _fig_png(fig)


def _assembly_section(cut_dir: Path | None, cut_man: dict | None, print_dir: Path | None,
                      print_man: dict | None) -> str:
    body = ""
    for d, man, what in ((cut_dir, cut_man, "cut"), (print_dir, print_man, "print")):
        if d is None or man is None:  # (a manifest comes with its folder)
            continue
        a = man.get("assembly")
        if isinstance(a, dict) and a.get("steps"):
            steps = "".join(f"<li>{html.escape(s)}</li>" for s in a["steps"])  # the steps carry their own numbers
            body += f"<h3>{what}</h3><ul class=\"steps\">{steps}</ul>"
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
        body += "<h3>cut</h3>" + (table(bom) if bom else _missing("the cut manifest has no bill of materials"))
    if print_man is not None:
        bom = print_man.bill_of_materials
        if bom:
            body += "<h3>print</h3>" + table({k: v for k, v in bom.items() if k not in ("bodies", "filament")})
            body += rows_table([{"material": m, **f} for m, f in bom["filament"].items()])
        else:
            body += "<h3>print</h3>" + _missing("the print manifest has no bill of materials")
    return body or _missing("not provided: pass --cut DIR and/or --print DIR")


def _tolerance_section(folder: str | None) -> str:
    if not folder:
        return _missing("not provided: run fabkiri tolerance PATTERN -o DIR and pass --tolerance DIR")
    d = Path(folder)
    body = _pictures(d, ["tolerance.png"], "tolerance")
    f = d / "tolerance.json"
    if f.is_file():
        t = json.loads(f.read_text("utf-8"))
        rows = [{"measure": k, "state": s, **{q: v[q] for q in ("p50", "p95", "max")}}
                for k in ("closure_gap_mm", "seam_gap_mm", "overlap_max_mm2") for s, v in t.get(k, {}).items()]
        ol = t.get("deployed_outline_mm")
        if ol:
            rows.append({"measure": "deployed_outline_mm", "state": "deployed", **{q: ol[q] for q in ("p50", "p95", "max")}})
        body += table(t.get("model", {})) + rows_table(rows) + rows_table(t.get("most_sensitive_tiles", []))
    return body or _missing(f"{d}: no tolerance.png or tolerance.json")
