"""``fabkiri make`` over outlines x processes, each cell as a whole process, checked by outside tools.

    PYTHONPATH=. python3 bench/make.py [--cells N] [--filter TEXT ...] [--out DIR] [--baseline DIR]

Outlines: every file in bench/data/make/ (a six-point star CSV, a drop drawn as an SVG path, a
peanut with a waist, a letter L with a reflex corner, a shield and a guitar pick as JSON points).
Processes: acrylic-3 tape at 150 mm, card-0.3 (ligaments) at 120 mm, prusa-mk4 tiles-and-strips at
150 mm, prusa-xl-2t (its default style) at 200 mm. Tiles: as ``make`` chooses them.

Each cell runs ``fabkiri make`` in a subprocess (CPU time of the child from ``getrusage``, wall time)
and reads its ``make.json``; then checks the files from outside: the read-back recorded in the
manifest (cut: the laser files re-read and verified; print: every written mesh re-read as a closed
2-manifold), ``fabkiri verify PATTERN --layout DXF`` for cuts, ``prusa-slicer --export-gcode`` on
every 3MF for prints, and the Hausdorff distance (share of the size). ``make`` runs with
``--shape-tol 3%`` (the issue's bar; its default is 2 %). A cell succeeds when make exits 0, every
check accepts the files and the shape is within 3 %. A refusal is shown as its line; when
``make`` refuses (exit 1) naming checked options (on stdout, one ``fabkiri ...`` line each, as
``make.json`` "alternatives") the first is run as it is, and the cell reads "refused -> alternative
ok" (it exits 0) or "refused -> alternative failed": the issue's "refuses in one line that names
an alternative which then succeeds". A cell whose design ``make`` redid at other tile counts after
a shape miss (``make.json`` "design_retries") reads "ok (at RxC after a miss)" when it then
succeeded (make still exited 0 the first time), and its counts are listed under the table. ``--baseline DIR`` also times the ``design --material/--printer`` + ``cut``/``print``
sequence of another checkout at the same tiles, in the same run (against make's own design and
cut/print steps, "d+f CPU s", timed inside its process; the baseline's figure includes two
interpreter starts).
"""

from __future__ import annotations

import argparse
import json
import os
import shlex
import subprocess
import sys
import tempfile
from dataclasses import dataclass, field
from pathlib import Path

from child import run_cli

ROOT = Path(__file__).resolve().parents[1]
DATA = ROOT / "bench" / "data" / "make"
SHAPE_TOL = 0.03  # the bar for a cell
SLICER_WARNINGS = ("empty layer", "outside", "could not fit", "not printable", "error")

PROCESSES = {  # name: (make's options, size in mm)
    "acrylic-3": (["--material", "acrylic-3", "--hinge", "tape"], 150.0),
    "card-0.3": (["--material", "card-0.3"], 120.0),
    "prusa-mk4": (["--printer", "prusa-mk4", "--style", "tiles-and-strips"], 150.0),
    "prusa-xl-2t": (["--printer", "prusa-xl-2t"], 200.0),
}


@dataclass
class Cell:
    outline: Path
    process: str
    code: int = -1
    cpu_s: float = 0.0
    wall_s: float = 0.0
    tiles: str = "?"
    hausdorff: float | None = None
    failed_step: str | None = None
    refusal: str = ""
    readback: bool | None = None
    outside: bool | None = None  # verify --layout (cut) or PrusaSlicer (print)
    outside_note: str = ""
    alternative: str = ""
    alternative_code: int | None = None
    alternative_cpu_s: float = 0.0
    baseline: dict = field(default_factory=dict)
    steps_cpu_s: float = 0.0  # design + cut/print, in make's process (the baseline's two commands)
    retried: list = field(default_factory=list)  # make's designs after a shape miss (make.json)

    @property
    def name(self) -> str:
        return f"{self.outline.name} / {self.process}"

    @property
    def ok(self) -> bool:
        return (
            self.code == 0
            and bool(self.readback)
            and bool(self.outside)
            and self.hausdorff is not None
            and self.hausdorff <= SHAPE_TOL
        )

    @property
    def outcome(self) -> str:
        """ok (first time), refused -> alternative ok/failed, or failed (no option named)."""
        if self.ok:
            return "ok" + (f" (at {self.tiles} after a miss)" if self.retried else "")
        if self.alternative:
            return f"refused -> alternative {'ok' if self.alternative_code == 0 else 'failed'}"
        return "failed"


def fabkiri(repo: Path, *args: str, timeout: float) -> tuple[int, float, float, str, str]:
    """Run the CLI of ``repo`` as its own process: exit code, CPU s (the child's), wall s, stderr,
    stdout."""
    c = run_cli(repo, *args, timeout=timeout)
    return c.code, c.cpu_s, c.wall_s, c.stderr, c.stdout


def slices(folder: Path) -> tuple[bool, str]:
    """Whether PrusaSlicer slices every 3MF in ``folder`` with exit 0 and no warning in its log."""
    models = sorted(folder.glob("*.3mf"))
    if not models:
        return False, "no 3MF"
    for m in models:
        p = subprocess.run(
            ["prusa-slicer", "--export-gcode", str(m), "-o", str(m.with_suffix(".gcode"))],
            capture_output=True,
            text=True,
            timeout=1800,
        )
        log = "\n".join(
            ln
            for ln in (p.stdout + p.stderr).splitlines()
            if not any(t in ln for t in ("[trace]", "[debug]", "[info]"))
        ).lower()
        bad = [w for w in SLICER_WARNINGS if w in log]
        if p.returncode != 0 or bad:
            return False, f"{m.name}: exit {p.returncode} {', '.join(bad)}"
    return True, f"{len(models)} 3MF sliced"


def read_back(folder: Path, process: str) -> bool:
    man = json.loads((folder / "manifest.json").read_text())
    if process == "cut":
        return bool(man["verification"]["ok"])
    return all(v["ok"] for v in man["checks"]["files"].values())


def run_cell(cell: Cell, out: Path, timeout: float) -> None:
    options, size = PROCESSES[cell.process]
    folder = out / f"{cell.outline.stem}-{cell.process}"
    cell.code, cell.cpu_s, cell.wall_s, err, stdout = fabkiri(
        ROOT,
        "make",
        str(cell.outline),
        "--size",
        f"{size:g}",
        *options,
        "--shape-tol",
        f"{100 * SHAPE_TOL:g}%",
        "-o",
        str(folder),
        timeout=timeout,
    )
    record_file = folder / "make.json"
    if not record_file.exists():  # refused before any step (or crashed): its one line
        cell.refusal = (err.strip().splitlines() or ["(no output)"])[-1]
        return
    record = json.loads(record_file.read_text())
    cell.tiles = "x".join(map(str, record["tiles"]))
    cell.hausdorff = record["figures"].get("hausdorff_rel")
    cell.failed_step = record["failed_step"]
    cell.retried = record.get("design_retries") or []
    cell.steps_cpu_s = sum(
        st["cpu_s"] for st in record["steps"] if st["name"] in ("design", "cut", "print")
    )
    if cell.failed_step:
        step = next(s for s in record["steps"] if s["name"] == cell.failed_step)
        cell.refusal = f"{cell.failed_step}: {step['figures']}"
        if cell.code == 1:
            run_alternative(cell, stdout, timeout)
    stem = cell.outline.stem
    process = record["process"]
    made = folder / process
    if (made / "manifest.json").exists():
        cell.readback = read_back(made, process)
        if process == "cut":
            code, *_ = fabkiri(
                ROOT,
                "verify",
                str(folder / f"{stem}.json"),
                "--layout",
                str(made / f"{stem}.dxf"),
                "--shape-tol",
                f"{100 * SHAPE_TOL:g}%",
                timeout=timeout,
            )
            cell.outside, cell.outside_note = code == 0, f"verify exit {code}"
        else:
            cell.outside, cell.outside_note = slices(made)


def run_alternative(cell: Cell, stdout: str, timeout: float) -> None:
    """A refusal's first named option (its stdout: ``# options ...`` then ``fabkiri ...    # detail``
    lines), run as it is; its exit code and CPU time kept."""
    lines = [ln.split("    # ")[0] for ln in stdout.splitlines() if ln.startswith("fabkiri ")]
    if not lines:
        return
    cell.alternative = lines[0]
    code, cpu, *_ = fabkiri(ROOT, *shlex.split(lines[0])[1:], timeout=timeout)
    cell.alternative_code, cell.alternative_cpu_s = code, cpu


def run_baseline(cell: Cell, repo: Path, out: Path, timeout: float) -> None:
    """The old sequence in ``repo``: ``design --tiles (make's) --material/--printer`` then ``cut``/``print``."""
    if cell.tiles == "?":
        return
    options, size = PROCESSES[cell.process]
    folder = out / f"baseline-{cell.outline.stem}-{cell.process}"
    folder.mkdir(parents=True, exist_ok=True)
    pattern = folder / f"{cell.outline.stem}.json"
    code, cpu, wall, *_ = fabkiri(
        repo,
        "design",
        "--tiles",
        cell.tiles,
        "--target",
        str(cell.outline),
        "--size",
        f"{size:g}",
        *options,
        "--shape-tol",
        f"{100 * SHAPE_TOL:g}%",
        "-o",
        str(pattern),
        timeout=timeout,
    )
    cell.baseline = {"design": code, "cpu_s": cpu, "wall_s": wall}
    if pattern.exists():
        step = "cut" if "--material" in options else "print"
        code, c2, w2, *_ = fabkiri(
            repo, step, str(pattern), "-o", str(folder / step), timeout=timeout
        )
        cell.baseline.update({step: code, "cpu_s": cpu + c2, "wall_s": wall + w2})


def table(cells: list[Cell], baseline: bool) -> list[str]:
    head = f"{'outline / process':<28} {'tiles':>5} {'exit':>4} {'CPU s':>7} {'wall s':>7} {'Hd %':>6} {'readback':>8} {'outside':>8} {'outcome':<30}"
    if baseline:
        head += f" {'d+f CPU s':>9} {'base CPU s':>10} {'base exit':>9}"
    rows = [head]
    for c in cells:
        hd = "-" if c.hausdorff is None else f"{100 * c.hausdorff:.2f}"
        rb = "-" if c.readback is None else ("yes" if c.readback else "NO")
        outside = "-" if c.outside is None else ("yes" if c.outside else "NO")
        row = (
            f"{c.name:<28} {c.tiles:>5} {c.code:>4} {c.cpu_s:>7.1f} {c.wall_s:>7.1f} {hd:>6} {rb:>8} "
            f"{outside:>8} {c.outcome:<30}"
        )
        if baseline:
            b = c.baseline
            codes = "/".join(str(b[k]) for k in ("design", "cut", "print") if k in b) or "-"
            row += f" {c.steps_cpu_s:>9.1f} {b.get('cpu_s', float('nan')):>10.1f} {codes:>9}"
        rows.append(row)
    return rows


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--cells", type=int, help="run only the first N cells (after --filter)")
    ap.add_argument(
        "--filter",
        action="append",
        default=[],
        help="keep cells whose 'outline / process' holds TEXT",
    )
    ap.add_argument(
        "--out", type=Path, help="keep the cells' folders here (default: a temp folder)"
    )
    ap.add_argument("--baseline", type=Path, help="another checkout: time design + cut/print there")
    ap.add_argument(
        "--timeout", type=float, default=1200.0, help="seconds per process (default 1200)"
    )
    args = ap.parse_args()
    cells = [Cell(o, p) for o in sorted(DATA.iterdir()) for p in PROCESSES]
    cells = [c for c in cells if all(f in c.name for f in args.filter)][: args.cells]
    out = (args.out or Path(tempfile.mkdtemp(prefix="fabkiri-bench-make-"))).resolve()
    out.mkdir(parents=True, exist_ok=True)
    print(f"{len(cells)} cells into {out}; load average at start {os.getloadavg()}", flush=True)
    for c in cells:
        run_cell(c, out, args.timeout)
        if args.baseline:
            run_baseline(c, args.baseline.resolve(), out, args.timeout)
        print(table([c], bool(args.baseline))[1], flush=True)
    print()
    print("\n".join(table(cells, bool(args.baseline))))
    for c in cells:
        if c.refusal:
            alt = (
                f"; alternative `{c.alternative}` exit {c.alternative_code} "
                f"(CPU {c.alternative_cpu_s:.1f} s)"
                if c.alternative
                else "; no alternative named"
            )
            print(f"  {c.name}: {c.refusal[:300]}{alt}")
        elif c.outside is False:
            print(f"  {c.name}: {c.outside_note}")
        if c.retried:
            print(f"  {c.name}: tile counts designed: {'; '.join(c.retried)}")
    good = sum(c.ok for c in cells)
    led = sum(c.outcome == "refused -> alternative ok" for c in cells)
    print(
        f"{good}/{len(cells)} cells succeeded first time, {led} refused naming an alternative that "
        f"then succeeded; load average at end {os.getloadavg()}"
    )
    return 0 if good + led == len(cells) else 1


if __name__ == "__main__":
    sys.exit(main())
