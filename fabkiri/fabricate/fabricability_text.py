"""The fabricability summary (:func:`.fabricability.summary`) as a few lines of text (design's stderr,
``info``)."""

from __future__ import annotations


def summary_lines(s: dict) -> list[str]:
    """The summary as a few text lines (design's stderr, ``info``)."""
    lines = [
        f"fabricability: thinnest tile {s['thinnest_tile_mm']:.3g} mm (tile {s['thinnest_tile']}), shortest edge "
        f"{s['shortest_edge_mm']:.3g} mm, closest hinge pair "
        + ("n/a" if s["closest_hinge_pair_mm"] is None else f"{s['closest_hinge_pair_mm']:.3g} mm")
    ]
    cells = []
    for mat, kinds in s["cut"].items():
        part = []
        for kind, m in kinds.items():
            part.append(
                f"{kind} never"
                if m["min_scale"] is None
                else f"{kind} ≥ {m['min_scale']:g}× ({m['min_width_mm']:g} mm)"
            )
        cells.append(f"{mat}: " + ", ".join(part))
    lines.append("  cut (--scale, --width): " + "; ".join(cells))
    if s.get("print"):
        cells = []
        for pr, styles in s["print"].items():
            part = []
            for style, m in styles.items():
                if m["min_scale"] is None:
                    part.append(f"{style} never")
                else:
                    bed = "" if m["max_scale"] is None else f"..{m['max_scale']:g}"
                    low = "" if m.get("exact", True) or "lower bound" not in m["limit"] else " from"
                    part.append(
                        f"{style}{low} {m['min_scale']:g}{bed}×"
                        + ("" if m["fits_bed"] else " (bed too small)")
                    )
            cells.append(f"{pr}: " + ", ".join(part))
        lines.append("  print (--scale): " + "; ".join(cells))
    return lines
