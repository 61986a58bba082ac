"""PNG preview of the sheets with matplotlib (Agg, headless), sheets side by side."""

from __future__ import annotations

import io

from .drawing import COLORS, LAYERS, SheetDrawing

GAP_MM = 20.0


def png_bytes(sheets: list[SheetDrawing], colors: str = "default", px_per_mm: float = 2.0,
              max_px: int = 2400) -> bytes:
    import matplotlib

    matplotlib.use("Agg", force=False)
    from matplotlib.collections import LineCollection
    from matplotlib.figure import Figure

    total_w = sum(s.width for s in sheets) + GAP_MM * (len(sheets) - 1)
    total_h = max(s.height for s in sheets)
    scale = min(px_per_mm, max_px / max(total_w, total_h))
    dpi = 100
    fig = Figure(figsize=(total_w * scale / dpi, total_h * scale / dpi), dpi=dpi)
    ax = fig.add_axes((0, 0, 1, 1))
    ax.set_xlim(0, total_w)
    ax.set_ylim(0, total_h)
    ax.set_aspect("equal")
    ax.axis("off")
    x0 = 0.0
    for s in sheets:
        for name in LAYERS:
            segs = []
            for pts, closed in s.layers[name]:
                p = pts if not closed else __import__("numpy").vstack([pts, pts[:1]])
                segs.append(p + [x0, 0.0])
            if segs:
                ax.add_collection(LineCollection(segs, colors=COLORS[colors][name][0], linewidths=0.4))
        x0 += s.width + GAP_MM
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=dpi, facecolor="white", metadata={"Software": None})
    return buf.getvalue()
