"""The report's HTML building blocks: inlined images (data URIs), notes for missing data, and tables."""

from __future__ import annotations

import base64
import html
import io
import json
from typing import TYPE_CHECKING, Any

from .deployment import _pyplot

if TYPE_CHECKING:  # matplotlib is imported where a picture is drawn
    from matplotlib.figure import Figure

MIME = {".png": "image/png", ".gif": "image/gif", ".svg": "image/svg+xml", ".jpg": "image/jpeg"}


def data_uri(data: bytes, suffix: str) -> str:
    return f"data:{MIME[suffix]};base64,{base64.b64encode(data).decode('ascii')}"


# a sheet shown on screen: its 0.1 mm hairlines would vanish at screen size, so a rule in the copy shown
# (never in the file) gives every line a screen pixel
HAIRLINES = (
    "<style>path,line,polyline,polygon,rect,circle"
    "{vector-effect:non-scaling-stroke;stroke-width:1.2px}</style>"
)


def screen_svg(text: str) -> str:
    """``text`` (an SVG document) with ``HAIRLINES`` as its first element."""
    end = text.find(">", text.find("<svg"))
    return text[: end + 1] + HAIRLINES + text[end + 1 :] if end > 0 else text


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
    if (
        isinstance(v, (list, tuple))
        and len(v) <= 8
        and all(not isinstance(x, (dict, list)) for x in v)
    ):
        return ", ".join(_fmt(x) for x in v)
    if (
        isinstance(v, (list, tuple))
        and len(v) <= 8
        and all(isinstance(x, (list, tuple)) and len(x) <= 4 for x in v)
    ):
        return "; ".join(" x ".join(_fmt(y) for y in x) for x in v)
    if (
        isinstance(v, dict)
        and len(v) <= 8
        and all(not isinstance(x, (dict, list)) for x in v.values())
    ):
        return "<br>".join(f"{html.escape(str(k))}: {_fmt(x)}" for k, x in v.items())
    if isinstance(v, (dict, list)):
        return f"<pre>{html.escape(json.dumps(v, indent=1)[:3000])}</pre>"
    return html.escape(str(v))


def table(d: dict[str, Any], head: tuple[str, str] = ("", "")) -> str:
    rows = "".join(
        f"<tr><th>{html.escape(str(k))}</th><td>{_fmt(v)}</td></tr>" for k, v in d.items()
    )
    h = (
        f"<tr><th>{html.escape(head[0])}</th><th>{html.escape(head[1])}</th></tr>"
        if any(head)
        else ""
    )
    return f"<table>{h}{rows}</table>"


def rows_table(rows: list[dict[str, Any]], limit: int = 60) -> str:
    if not rows:
        return ""
    keys = list(rows[0])
    body = "".join(
        "<tr>" + "".join(f"<td>{_fmt(r.get(k))}</td>" for k in keys) + "</tr>" for r in rows[:limit]
    )
    more = f"<p>… {len(rows) - limit} more rows in the manifest</p>" if len(rows) > limit else ""
    return (
        "<table><tr>"
        + "".join(f"<th>{html.escape(k)}</th>" for k in keys)
        + f"</tr>{body}</table>{more}"
    )


def _fig_png(fig: Figure) -> bytes:
    buf = io.BytesIO()
    fig.savefig(buf, format="png", metadata={"Software": None}, bbox_inches="tight")
    _pyplot().close(fig)
    return buf.getvalue()
