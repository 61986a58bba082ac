"""Notebook display shared by the result types: a small HTML block with the summary and picture."""

from __future__ import annotations

import base64
import html


def result_html(name: str, summary: str, png: bytes | None) -> str:
    """``name``'s ``summary`` (escaped) above ``png`` as an inline image; no picture, no image.
    Only the summary and the picture: a result's arrays stay out of the page."""
    parts = [
        '<div class="fabkiri-result">',
        f"<p><b>{html.escape(name)}</b>: {html.escape(summary)}</p>",
    ]
    if png:
        data = base64.b64encode(png).decode("ascii")
        parts.append(f'<img src="data:image/png;base64,{data}" alt="{html.escape(name)}"/>')
    parts.append("</div>")
    return "".join(parts)
