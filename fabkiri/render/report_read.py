"""The report's figures as tables a person reads: fabricability with ✔/✖ and the smallest scale,
conformance as numbers beside its overlay picture, the verifier's checks one row each.

Fabricability is what ``fabkiri info`` prints (:func:`fabkiri.fabricate.fabricability.summary`, computed
here for any quad pattern that closes, stored or not); a ✔ means the pattern can be made at its stored
size (scale 1), a ✖ gives the smallest ``--scale`` it needs or says it never can.
"""

from __future__ import annotations

import html
from typing import Any

from ..pattern.model import Pattern
from .htmlparts import _img, _missing

OK, NO = "✔", "✖"


def fabricability_summary(pattern: Pattern, closes: bool, stored: Any) -> dict | None:
    """``info``'s fabricability figures: computed for a quad pattern that closes (as ``info``), else stored."""
    if closes and pattern.kind == "quad":
        from ..fabricate.fabricability import summary

        return summary(pattern)
    return stored if isinstance(stored, dict) and isinstance(stored.get("cut"), dict) else None


def fabricability_part(summary: dict | None, why_not: str) -> str:
    """The measures, then one table for cutting (material × hinge kind) and one for printing."""
    if summary is None:
        return _missing(f"fabricability: not computed ({why_not})")
    hp = summary.get("closest_hinge_pair_mm")
    body = _grid(
        ["thinnest tile", "shortest edge", "closest hinge pair"],
        [
            [
                f"{summary['thinnest_tile_mm']:.3g} mm (tile {summary['thinnest_tile']})",
                f"{summary['shortest_edge_mm']:.3g} mm",
                "n/a" if hp is None else f"{hp:.3g} mm",
            ]
        ],
    )
    body += (
        f'<p class="note">{OK}: can be made at the pattern\'s size (scale 1); {NO}: the smallest '
        f"<code>--scale</code> it needs (and the sheet width then), or never. Hover a cell for what "
        f"limits it.</p>"
    )
    cut = summary.get("cut") or {}
    kinds = list(next(iter(cut.values()), {}))
    body += "<h3>laser cut (material × hinge)</h3>" + _grid(
        ["material", *kinds], [[m, *(_cut_cell(cut[m].get(k)) for k in kinds)] for m in cut], raw=1
    )
    prints = summary.get("print") or {}
    if prints:
        styles = list(dict.fromkeys(s for v in prints.values() for s in v))
        body += "<h3>3D print (printer × style)</h3>" + _grid(
            ["printer", *styles],
            [[p, *(_print_cell(prints[p].get(s)) for s in styles)] for p in prints],
            raw=1,
        )
    return body


def _td(m: dict, ok: bool, text: str) -> str:
    """A ✔/✖ cell whose hover title is what limits it."""
    limit = html.escape(str(m.get("limit", "")), quote=True)
    return f'<td class="{"ok" if ok else "fail"}" title="{limit}">{OK if ok else NO} {text}</td>'


def _cut_cell(m: dict | None) -> str:
    if not m:
        return "<td></td>"
    s = m.get("min_scale")
    if s is None:
        return _td(m, False, "never")
    if s <= 1:
        return _td(m, True, f"from {s:g}×")
    return _td(m, False, f"≥ {s:g}× ({m['min_width_mm']:g} mm)")


def _print_cell(m: dict | None) -> str:
    if not m:
        return "<td></td>"
    if m.get("min_scale") is None:
        return _td(m, False, "never")
    low = "" if m.get("exact", True) else "from "
    bed = "" if m.get("max_scale") is None else f"..{m['max_scale']:g}"
    span = f"{low}{m['min_scale']:g}{bed}×"
    if not m.get("fits_bed", True):  # the smallest scale that prints is larger than the bed holds
        span = f"≥ {m['min_scale']:g}×, the bed holds ≤ {m['max_scale']:g}×"
    return _td(m, bool(m.get("ok_at_scale_1")), span)


def _grid(head: list[str], rows: list[list[str]], raw: int = 0) -> str:
    """A table of escaped text; with ``raw`` every cell after the row's first is already a ``<td>``."""
    h = "".join(f"<th>{html.escape(x)}</th>" for x in head)
    body = ""
    for r in rows:
        if raw:
            body += f"<tr><th>{html.escape(r[0])}</th>{''.join(r[1:])}</tr>"
        else:
            body += "<tr>" + "".join(f"<td>{html.escape(str(c))}</td>" for c in r) + "</tr>"
    return f"<table><tr>{h}</tr>{body}</table>"


CONFORMANCE_ROWS = (
    ("Hausdorff (worst gap)", "hausdorff_mm", "mm"),
    ("Hausdorff / target size", "hausdorff_rel", "%"),
    ("mean gap outline → target", "mean_outline_to_target_mm", "mm"),
    ("mean gap target → outline", "mean_target_to_outline_mm", "mm"),
    ("1 − IoU", "one_minus_iou", "%"),
    ("tip spacing (mean)", "spacing_mean_mm", "mm"),
    ("target size", "size_mm", "mm"),
)


def conformance_part(pattern: Pattern, conf: Any) -> str:
    """Each measured outline's figures in one table (outlines as columns) and the overlay picture."""
    if not isinstance(conf, dict) or not any(isinstance(v, dict) for v in conf.values()):
        return _missing("conformance: not computed (design.report.conformance absent)")
    cols = {k: v for k, v in conf.items() if isinstance(v, dict)}
    names = [k.replace("state_", "closed state ") for k in cols]
    rows = []
    for label, key, unit in CONFORMANCE_ROWS:
        cells = [_num(c.get(key), unit) for c in cols.values()]
        if any(cells):
            rows.append([label, *cells])
    rows.append(["worst at (x, y)", *(_at(c) for c in cols.values())])
    body = _grid(["", *names], rows)
    try:
        from .conformance import conformance_png

        body += _img(
            conformance_png(pattern, cols), ".png", "outline over its target, worst gap in red"
        )
    except (KeyError, ValueError, TypeError):  # an old report without the placement: figures only
        pass
    return body


def _num(v: Any, unit: str) -> str:
    if not isinstance(v, (int, float)):
        return ""
    return f"{100 * v:.3g} %" if unit == "%" else f"{v:.3g} {unit}"


def _at(c: dict) -> str:
    w = c.get("worst") or {}
    at = w.get("at")
    if not (isinstance(at, list) and len(at) == 2):
        return ""
    return f"({at[0]:.1f}, {at[1]:.1f}) mm on the {w.get('on', 'outline')}"


def checks_table(checks: list) -> str:
    """The verifier's checks (:class:`fabkiri.verify.report.Check`), one row each, failures first."""
    rows = sorted((c for c in checks if c.applies), key=lambda c: c.ok)
    body = "".join(
        f'<tr><td class="{"ok" if c.ok else "fail"}">{OK if c.ok else NO}</td>'
        f"<td>{html.escape(c.group)}</td><td>{html.escape(c.name)}</td>"
        f"<td>{_g(c.value)} {c.op} {_g(c.tol)} {html.escape(c.unit)}</td>"
        f"<td>{html.escape(c.detail or '')}</td></tr>"
        for c in rows
    )
    head = "<tr><th></th><th>group</th><th>check</th><th>measured vs tolerance</th><th>detail</th></tr>"
    return f"<table>{head}{body}</table>"


def _g(v: Any) -> str:
    return f"{v:.3g}" if isinstance(v, float) else html.escape(str(v))
