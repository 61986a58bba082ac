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

import html
from typing import TYPE_CHECKING

import numpy as np

from ..mechanics.info import PatternInfo, describe
from ..pattern.model import Pattern
from ..verify import verify_pattern
from ..verify.printmanifest import PrintManifest
from .deployment import _pyplot
from .htmlparts import MIME, _fig_png, _fmt, _img, _missing, data_uri, rows_table, table  # noqa: F401 (re-exported)
from .report_read import checks_table, conformance_part, fabricability_part, fabricability_summary
from .report_sections import (  # noqa: F401 (re-exported)
    _assembly_section,
    _bom_section,
    _cut_section,
    _deploy_section,
    _load_dir,
    _pictures,
    _print_section,
    _tolerance_section,
    meshes_or,
    plate_png,
)
from .viewer import cut_sheets, viewer_data, viewer_fragment

VIEWER_STEPS = 40  # fabkiri deploy's default

if TYPE_CHECKING:  # matplotlib is imported where a picture is drawn
    from matplotlib.axes import Axes

SECTIONS = (
    "summary",
    "viewer",
    "design",
    "states",
    "fabricability",
    "verification",
    "deployment",
    "cut",
    "print",
    "assembly",
    "bom",
    "tolerance",
)

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
td.ok,td.fail{font-weight:500;white-space:nowrap}td.ok{background:#eef8f0}td.fail{background:#fdf0ef}
p.note{font-size:13px;color:#445}
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


def _tiles(ax: Axes, corners: np.ndarray, color: str = "#b8c7d9") -> None:
    from matplotlib.collections import PolyCollection

    # matplotlib's stubs ask for a sequence of vertex arrays; a (T, k, 2) array is one (and its fast path)
    ax.add_collection(
        PolyCollection(
            corners,  # type: ignore[arg-type]
            facecolors=color,
            edgecolors="#34495e",
            linewidths=0.4,
        )
    )
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
        ax.plot(
            ring[:, 0],
            ring[:, 1],
            color="#d62728",
            lw=1.4,
            label=f"target: {target.get('name', '')}",
        )
        ax.legend(fontsize=8, loc="lower right")
        lo = np.minimum(pts.min(0), pattern.nodes.min(0))
        hi = np.maximum(pts.max(0), pattern.nodes.max(0))
        pad = 0.04 * float((hi - lo).max())
        ax.set_xlim(lo[0] - pad, hi[0] + pad)
        ax.set_ylim(lo[1] - pad, hi[1] + pad)
    ax.set_title("deployed design" + (" vs its target" if len(pts) >= 3 else ""), fontsize=10)
    ax.set_xlabel("mm", fontsize=8)
    return _fig_png(fig)


def states_png(
    pattern: Pattern, states: dict[int, np.ndarray], targets: dict[int, np.ndarray]
) -> bytes:
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


def _section(sid: str, title: str, body: str) -> str:
    return f'<section id="{sid}"><h2>{html.escape(title)}</h2>{body}</section>'


def build_report(
    pattern: Pattern,
    *,
    source: str = "",
    cut: str | None = None,
    printed: str | None = None,
    deploy: str | None = None,
    tolerance: str | None = None,
    states: dict[int, np.ndarray] | None = None,
    viewer: bool = True,
) -> str:
    """The HTML page (see the module doc). ``states``: both closed states (corners) if the pattern closes;
    ``viewer``: embed the interactive deployment viewer (it computes the deployment path)."""
    design = pattern.design or {}
    report = design.get("report") or {}
    info = describe(pattern)
    parts: dict[str, str] = {}
    parts["summary"] = _summary_part(pattern, source, info, report)
    from .report_opening import opening_part  # how much it opens, its own module

    parts["design"] = _design_part(pattern, report) + opening_part(info.opening)
    parts["states"] = _states_part(pattern, states, info)
    fab = fabricability_summary(pattern, info.closes_both, report.get("fabricability"))
    parts["fabricability"] = fabricability_part(
        fab,
        "cut and print make quad patterns only"
        if info.closes_both
        else "the pattern does not close in both states",
    )
    parts["verification"] = _verification_part(pattern)
    parts["deployment"] = _deploy_section(deploy)
    cut_dir, cut_man = _load_dir(cut)
    print_dir, print_man = _load_dir(printed)
    pm = (
        None
        if print_man is None
        else PrintManifest.from_dict(print_man, f"{printed}/manifest.json")
    )
    parts["viewer"] = (
        _viewer_part(pattern, states is not None, cut, (print_man or {}).get("assembly_pieces"))
        if viewer
        else _missing("not drawn (viewer=False)")
    )
    parts["cut"] = _cut_section(cut_dir, cut_man)
    parts["print"] = _print_section(print_dir, pm)
    parts["assembly"] = _assembly_section(cut_dir, cut_man, print_dir, print_man)
    parts["bom"] = _bom_section(cut_man, pm)
    parts["tolerance"] = _tolerance_section(tolerance)
    return _page(pattern.name or source or "pattern", parts)


def _viewer_part(
    pattern: Pattern, closes: bool, cut: str | None, print_pieces: list[dict] | None
) -> str:
    """The interactive viewer along the deployment path ``fabkiri deploy`` computes (default steps), with
    the cut's pieces and sheets (else the print's pieces)."""
    if not closes:
        return _missing("no deployment path: the pattern does not close in both states")
    from ..mechanics.deploy import deployment_path

    pieces, sheets = cut_sheets(cut)
    path = deployment_path(pattern, VIEWER_STEPS)
    return viewer_fragment(viewer_data(pattern, path, pieces=pieces or print_pieces, sheets=sheets))


def _summary_part(pattern: Pattern, source: str, info: PatternInfo, report: dict) -> str:
    """Counts, size, rigid deployability, closure and the design's status."""
    return table(
        {
            "pattern": pattern.name or source,
            "file": source,
            "tiles": info.tiles,
            "hinges": info.hinges,
            "holes": info.holes,
            "deployed size (mm)": f"{info.width_mm:.2f} x {info.height_mm:.2f}",
            "mean tile edge (mm)": info.tile_size_mm,
            "rigid-deployable": info.rigid_deployable,
            "closes in both states": info.closes_both,
            "design status": report.get("status", "not recorded"),
        }
    )


def _design_part(pattern: Pattern, report: dict) -> str:
    """The design over its target, the solver's fit and the conformance figures when stored."""
    body = _img(design_png(pattern), ".png", "design vs target")
    fit = (report.get("fit") or {}).get("shape")
    body += "<h3>fit to the target (solver)</h3>" + (
        table(fit) if fit else _missing("no fit recorded")
    )
    body += "<h3>conformance</h3>" + conformance_part(pattern, report.get("conformance"))
    return body


def _states_part(pattern: Pattern, states: dict[int, np.ndarray] | None, info: PatternInfo) -> str:
    """Both closed states over their outline targets, with closure and residual figures."""
    if not states:
        return _missing("the pattern does not close in both states: " + "; ".join(info.problems()))
    targets = _contracted_targets(pattern.design or {})
    body = _img(states_png(pattern, states, targets), ".png", "closed states")
    if not targets:
        body += _missing("no outline targets stored for the closed states")
    body += rows_table(
        [
            {
                "closed state": s.state,
                "closes": s.closes,
                "loop closure (tile sizes)": s.max_closure_rel,
                "edge pairs (mm)": s.edge_pair_max_mm,
                "rings (rad)": s.ring_max_rad,
            }
            for s in info.states
        ]
    )
    return body


def _verification_part(pattern: Pattern) -> str:
    """The verifier's verdict and its full text."""
    ver = verify_pattern(pattern)
    v = (
        f'<p>verdict: <span class="{"ok" if ver.ok else "fail"}">{"PASS" if ver.ok else "FAIL"}</span> '
        f"({len(ver.checks) - len(ver.failed())}/{len(ver.checks)} checks pass)</p>"
    )
    return v + checks_table(ver.checks)


def _page(title: str, parts: dict[str, str]) -> str:
    """The whole page: head (CSS, error hook), navigation and every section in ``SECTIONS`` order."""
    titles = {
        "summary": "Summary",
        "viewer": "Deployment viewer",
        "design": "Design vs target",
        "states": "Closed states",
        "fabricability": "Fabricability",
        "verification": "Verification",
        "deployment": "Deployment",
        "cut": "Cut sheets",
        "print": "Print plates",
        "assembly": "Assembly map",
        "bom": "Bill of materials",
        "tolerance": "Tolerance",
    }
    nav = "".join(f'<a href="#{s}">{titles[s]}</a>' for s in SECTIONS)
    sections = "".join(_section(s, titles[s], parts[s]) for s in SECTIONS)
    name = html.escape(title)
    return (
        f'<!DOCTYPE html><html lang="en"><head><meta charset="utf-8"><title>fabkiri report: {name}</title>'
        f'<meta name="viewport" content="width=device-width, initial-scale=1">'
        f"<style>{CSS}</style>{ERROR_HOOK}</head><body>"
        f"<header><h1>fabkiri report: {name}</h1></header><nav>{nav}</nav>{sections}"
        f'<div id="console-errors" data-count="0"></div></body></html>\n'
    )
