"""The sweep's tables: ``results.csv``, ``results.parquet`` (with pyarrow) and the gallery ``index.html``."""

from __future__ import annotations

import csv
import html
import io
import re
from pathlib import Path

from ..fileio import atomic_write_many

FIRST = [
    "id",
    "status",
    "error",
    "max_equality_residual",
    "hausdorff_mm",
    "hausdorff_rel",
    "one_minus_iou",
    "shape",
    "thinnest_tile_mm",
    "min_cut_width_mm",
    "energy_barrier",
    "time_s",
    "cpu_s",
    "worker",
]
SHOWN = [
    "status",
    "max_equality_residual",
    "hausdorff_rel",
    "one_minus_iou",
    "thinnest_tile_mm",
    "min_cut_width_mm",
    "energy_barrier",
    "time_s",
    "worker",
]


# row colour per status: a check or the shape missed (yellow), a later stage refused (orange), the job did
# not finish (red); one class per status, ``status-<words joined by ->``, and a grey one for any other
STATUS_COLOURS = {
    "ok": "#eef8f0",
    "unconverged": "#fff4c2",
    "shape missed": "#fff4c2",
    "cut failed": "#ffe0c0",
    "print failed": "#ffe0c0",
    "deploy failed": "#ffe0c0",
    "error": "#fdd",
    "timeout": "#fdd",
}
OTHER = "status-other"


def status_class(status: object) -> str:
    """The row's class: ``status-shape-missed`` for "shape missed"; ``status-other`` for a status
    without a colour (a row written by another runner)."""
    s = str(status)
    return (
        "status-" + re.sub(r"[^a-z0-9]+", "-", s.lower()).strip("-")
        if s in STATUS_COLOURS
        else OTHER
    )


def status_css() -> str:
    rules = [f"tr.{status_class(s)} td {{ background: {c}; }}" for s, c in STATUS_COLOURS.items()]
    return "\n".join([*rules, f"tr.{OTHER} td {{ background: #eceff3; }}"])


def columns(rows: list[dict]) -> list[str]:
    """The parameters (``p_*``) first, then the figures, then anything else, in first-seen order."""
    seen: list[str] = []
    for r in rows:
        seen += [k for k in r if k not in seen]
    params = [k for k in seen if k.startswith("p_")]
    return [
        "id",
        *params,
        *[k for k in FIRST[1:]],
        *[k for k in seen if k not in params and k not in FIRST],
    ]


def csv_text(rows: list[dict]) -> str:
    buf = io.StringIO()
    w = csv.DictWriter(buf, fieldnames=columns(rows), extrasaction="ignore", lineterminator="\n")
    w.writeheader()
    for r in rows:
        w.writerow({k: ("" if v is None else v) for k, v in r.items()})
    return buf.getvalue()


def parquet_bytes(rows: list[dict]) -> bytes | None:
    """The same table as Parquet; None without pyarrow. A column of mixed kinds is stored as text."""
    try:
        import pyarrow as pa
        import pyarrow.parquet as pq
    except ImportError:
        return None
    data = {}
    for c in columns(rows):
        vals = [r.get(c) for r in rows]
        kinds = {type(v) for v in vals if v is not None}
        if kinds == {int, float}:
            vals = [None if v is None else float(v) for v in vals]
        elif len(kinds) > 1:
            vals = [None if v is None else str(v) for v in vals]
        data[c] = vals
    sink = pa.BufferOutputStream()
    pq.write_table(pa.table(data), sink)
    return sink.getvalue().to_pybytes()


def _cell(v) -> str:
    if isinstance(v, float):
        return f"{v:.3g}"
    return html.escape("" if v is None else str(v))


def gallery_html(rows: list[dict], out: Path) -> str:
    """One page: a thumbnail per design and its figures; click a column header to sort by it."""
    params = [c for c in columns(rows) if c.startswith("p_")]
    heads = ["design", "id", *[p[2:] for p in params], *SHOWN]
    body = []
    for r in rows:
        png = Path("jobs") / r["id"] / "pattern.png"
        img = (
            f'<a href="jobs/{r["id"]}/"><img src="{png.as_posix()}" loading="lazy"></a>'
            if (out / png).is_file()
            else ""
        )
        err = f' title="{html.escape(str(r.get("error", "")))}"' if r.get("error") else ""
        cells = [
            img,
            _cell(r["id"]),
            *[_cell(r.get(p)) for p in params],
            *[_cell(r.get(k)) for k in SHOWN],
        ]
        body.append(
            f'<tr class="{status_class(r.get("status"))}" data-status="{_cell(r.get("status"))}"{err}>'
            + "".join(f"<td>{c}</td>" for c in cells)
            + "</tr>"
        )
    statuses = sorted({str(r.get("status")) for r in rows})
    return PAGE.format(
        css=status_css(),
        options="".join(f'<option value="{_cell(s)}">{_cell(s)}</option>' for s in statuses),
        n=len(rows),
        ok=sum(r.get("status") == "ok" for r in rows),
        head="".join(f"<th>{html.escape(h)}</th>" for h in heads),
        body="\n".join(body),
    )


def write_tables(out: Path, rows: list[dict]) -> list[Path]:
    files: dict[str, bytes | str] = {
        "results.csv": csv_text(rows),
        "index.html": gallery_html(rows, out),
    }
    pq = parquet_bytes(rows) if rows else None
    if pq is not None:
        files["results.parquet"] = pq
    return atomic_write_many(out, files)


PAGE = """<!doctype html>
<html><head><meta charset="utf-8"><title>fabkiri sweep</title>
<style>
body {{ font: 13px sans-serif; margin: 1em; }}
table {{ border-collapse: collapse; }}
th {{ cursor: pointer; background: #eee; position: sticky; top: 0; }}
th, td {{ border: 1px solid #ccc; padding: 2px 6px; text-align: right; }}
img {{ width: 120px; }}
{css}
tr.hidden {{ display: none; }}
</style></head><body>
<h1>fabkiri sweep: {n} designs, {ok} ok</h1>
<p>Click a column to sort; click a design for its files. Red: error or time-out; orange: the cut, print or
deploy stage refused; yellow: unconverged or the shape missed; green: ok.</p>
<p><label>show <select id="status"><option value="">every status</option>{options}</select></label>
<label>filter <input id="q" type="search" placeholder="text in a row"></label> <span id="shown"></span></p>
<table id="t"><thead><tr>{head}</tr></thead><tbody>
{body}
</tbody></table>
<script>
document.querySelectorAll("#t th").forEach((th, i) => th.addEventListener("click", () => {{
  const tb = document.querySelector("#t tbody"), rows = Array.from(tb.rows);
  const dir = th.dataset.dir === "1" ? -1 : 1; th.dataset.dir = dir;
  const key = r => {{ const t = r.cells[i].textContent; const n = parseFloat(t); return isNaN(n) ? t : n; }};
  rows.sort((a, b) => {{ const x = key(a), y = key(b);
    return (typeof x === typeof y ? (x < y ? -1 : x > y ? 1 : 0) : (typeof x === "number" ? -1 : 1)) * dir; }});
  rows.forEach(r => tb.appendChild(r));
}}));
function filter() {{
  const st = document.getElementById("status").value, q = document.getElementById("q").value.toLowerCase();
  let n = 0;
  document.querySelectorAll("#t tbody tr").forEach(r => {{
    const show = (!st || r.dataset.status === st) && (!q || r.textContent.toLowerCase().includes(q));
    r.classList.toggle("hidden", !show); n += show;
  }});
  document.getElementById("shown").textContent = n + " shown";
}}
document.getElementById("status").addEventListener("change", filter);
document.getElementById("q").addEventListener("input", filter);
</script></body></html>
"""
