"""What ``fabkiri design`` says about a quad design: the summary lines behind
:meth:`fabkiri.api.design.DesignOutcome.summary`, and the preview picture beside the pattern."""

from __future__ import annotations

from pathlib import Path

from ..design.core import conformance as conf
from ..fabricate import fabricability
from ..pattern.model import Pattern
from .design_opening import summary_lines as opening_lines
from .design_report import DesignReport


def summary_lines(path, report: DesignReport) -> list[str]:
    """What ``fabkiri design`` says on stderr about a quad design written to ``path`` (None: not written): the figures,
    the fabrication rows and fabricability, then one ``fabkiri: design failed: ...`` line per problem."""
    out: list[str] = []
    fit = report.get("fit", {})
    parts = [
        f"{wrote(path)}: {report['status']}",
        f"max equality residual {report['max_equality_residual']:.2e}",
        f"{report['iterations_total']} iterations",
        f"{report['time_s']:.2f} s",
    ]
    if "shape" in fit:
        parts.append(
            f"fit ({report['shape_matching']}) max {fit['shape']['max_mm']:.3g} mm, "
            f"rms {fit['shape']['rms_mm']:.3g} mm"
        )
    for s, f in report.get("closed_outline_fit", {}).items():
        parts.append(
            f"state {s} outline vs {f['target']}: max {f['max_mm']:.3g} mm, rms {f['rms_mm']:.3g} mm"
        )
    for k, c in (report.get("conformance") or {}).items():
        j = report["shape"][k]
        parts.append(
            f"shape {k.replace('_', ' ')}: {j['status']}, Hausdorff {c['hausdorff_mm']:.3g} mm "
            f"({100 * c['hausdorff_rel']:.2f} %, tol {100 * j['tol_rel']:.2g} %), "
            f"1-IoU {c['one_minus_iou']:.3g}, tip spacing min/mean {c['spacing_min_mm']:.3g}/"
            f"{c['spacing_mean_mm']:.3g} mm"
        )
    out.append("; ".join(parts))
    if report.get("mirrored"):  # a request without --symmetry answered by the mirrored design
        out.append(
            f"kept the design mirrored about {report['mirrored']} (the target is symmetric"
            f"{', on the turned lattice' if report.get('lattice_angle_deg') else ''}): "
            f"{report.get('mirrored_why', '')}"
        )
    # api/design_turn.py: the pattern turned back onto the outline
    if report.get("lattice_angle_deg"):
        out.append(
            f"the lattice is laid at {report['lattice_angle_deg']:.1f}° along the outline's mirror axis "
            "(the design of the turned outline, turned back)"
        )
    if st := report.get(
        "strip"
    ):  # api/design_strip.py: other rows and columns than asked, or its corners
        out.append(_strip_line(st))
    out += opening_lines(report)
    fr = report.get("fabrication")
    if fr:
        out.append(
            "fabrication rows: "
            + ", ".join(
                f"{k[len('fabrication_') :]} {fr['active'][k]}/{fr['rows'][k]} active (min slack {fr['min'][k]:.3g}"
                f"{'' if 'angle' in k else ' mm'})"
                for k in fr["rows"]
            )
        )
    if report.get("fabricability"):
        out += fabricability.summary_lines(report["fabricability"])
    for p in report.get("problems", []):
        out.append(f"fabkiri: design failed: {p}")
    for k, c in (report.get("conformance") or {}).items():
        if report["shape"][k]["status"] == "missed":
            out.append(
                f"fabkiri: design failed: {conf.describe_miss(k.replace('_', ' '), report['shape'][k], c)}"
            )
    return out


def wrote(path) -> str:
    """How a summary's first line names the design: the file it was written to, if any."""
    return f"wrote {path}" if path is not None else "designed"


def preview_path(output) -> Path:
    """Where the design preview goes: ``NAME.png`` beside ``NAME.json``."""
    p = Path(output)
    return p.with_name((p.stem if p.suffix.lower() == ".json" else p.name) + ".png")


def _preview(pattern: Pattern, report: DesignReport, output) -> tuple[Path, bytes]:
    """The preview's path and bytes (rendered before anything is written); its name goes in the report."""
    from ..render.conformance import conformance_png

    path = preview_path(output)
    report["preview"] = path.name
    return path, conformance_png(
        pattern, report.get("conformance") or {}, report.get("shape") or {}
    )


def _strip_line(st: dict) -> str:
    """The bent strip's line: its rows and columns where they differ from those asked (the floor of tiles
    across can leave a small count asked as it was, only its corners moved)."""
    (r, c), (ar, ac) = st["tiles"], st["asked"]
    if (r, c) == (ar, ac):
        return f"the lattice is the {r}x{c} tiles asked, laid as a strip bent along the outline: {st['why']}"
    return f"the lattice is {r}x{c} tiles, not the {ar}x{ac} asked: {st['why']}"
