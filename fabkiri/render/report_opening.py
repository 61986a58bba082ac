"""The report's opening figures (:mod:`fabkiri.pattern.opening`): how much the design opens, as a small
table under the closed states, with the warning ``design`` and ``info`` give for one that opens little."""

from __future__ import annotations

import html

from ..pattern.opening import Opening
from .htmlparts import _missing, table


def opening_part(figures: dict) -> str:
    """``<h3>`` and a table of the opening figures (``Opening.to_dict`` form); a note when absent."""
    if not figures:
        return "<h3>opening</h3>" + _missing("opening: not measured")
    o = Opening.from_dict(figures)
    rows: dict[str, object] = {
        "deployed holes / deployed sheet": f"{100 * o.hole_fraction:.1f} %",
        "deployed sheet (mm²)": f"{o.sheet_area_mm2:.4g} ({o.hole_area_mm2:.4g} of it holes)",
    }
    for s in sorted(o.area_ratio):
        rows[f"deployed / closed state {s} area"] = f"{o.area_ratio[s]:.3f}"
    for s in sorted(o.turn_deg):
        rows[f"largest tile turn from state {s}"] = f"{o.turn_deg[s]:.1f}°"
    warn = o.warning()
    note = (
        f'<p class="fail">{html.escape(warn.removeprefix("fabkiri: warning: "))}</p>'
        if warn
        else ""
    )
    return "<h3>opening</h3>" + table(rows) + note
