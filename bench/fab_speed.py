"""Fabrication-aware design, timed against a baseline checkout in the same run (issues 32 and 36).

``python3 bench/fab_speed.py [--baseline /work/main] [--only heart-acrylic,...] [--out DIR]``: each case is
``fabkiri design`` (whole process, CPU s of the child, exit code, Hausdorff and max equality residual from the
report) then the fabrication step it was made for at scale 1 (``cut`` or ``print``; the print's 3MF files
sliced by PrusaSlicer), once with this checkout and once with the baseline. The load average is printed with
every row: CPU s are less sensitive to load than wall s, but not immune.
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
from pathlib import Path

from child import run_cli
from fabrication import slice_all

ROOT = Path(__file__).resolve().parents[1]
CASES = {
    "heart-acrylic": (
        ["--tiles", "16x16", "--target", "heart", "--size", "200", "--material", "acrylic-3"],
        "cut",
    ),
    "heart-mk4": (
        ["--tiles", "16x16", "--target", "heart", "--size", "200", "--printer", "prusa-mk4"],
        "print",
    ),
    "star-mk4": (
        ["--tiles", "12x12", "--target", "star", "--size", "150", "--printer", "prusa-mk4"],
        "print",
    ),
    "kagome-circle-mk4": (
        ["--lattice", "kagome", "--tiles", "6x11", "--target", "circle", "--size", "120"]
        + ["--printer", "prusa-mk4"],
        "print",
    ),
}


def run(root: Path, *args: str, timeout: float = 1800) -> tuple[int, float, float, str]:
    """``fabkiri ARGS`` with ``root`` on PYTHONPATH: (exit code, CPU s of the child, wall s, last stderr line)."""
    c = run_cli(root, *args, timeout=timeout)
    lines = [ln for ln in c.stderr.strip().splitlines() if not ln.startswith("[")] or [""]
    return c.code, c.cpu_s, c.wall_s, lines[-1][:160]


def figures(pj: Path) -> str:
    if not pj.exists():
        return "no file"
    rep = json.loads(pj.read_text())["design"]["report"]
    h = (rep.get("conformance") or {}).get("deployed", {}).get("hausdorff_rel")
    if h is None:
        h = rep.get("hausdorff_rel")
    res = rep.get("max_equality_residual")
    return f"H {100 * h:.2f} %, residual {res:.1e}" if h is not None and res is not None else "?"


def case(name: str, root: Path, tag: str, out: Path) -> None:
    flags, then = CASES[name]
    pj = out / f"{name}-{tag}.json"
    code, cpu, wall, last = run(root, "design", *flags, "--no-preview", "-o", str(pj))
    load = os.getloadavg()[0]
    print(
        f"{name:18s} {tag:8s} design exit {code}  {cpu:6.1f} CPU s {wall:6.1f} wall s  load {load:4.1f}  "
        f"{figures(pj)}  {last if code else ''}",
        flush=True,
    )
    if not pj.exists():
        return
    dest = out / f"{name}-{tag}-{then}"
    shutil.rmtree(dest, ignore_errors=True)
    code, cpu, wall, last = run(root, then, str(pj), "-o", str(dest))
    sliced = slice_all(dest) if then == "print" and code == 0 else ""
    print(
        f"{'':18s} {tag:8s} {then:6s} exit {code}  {cpu:6.1f} CPU s {wall:6.1f} wall s  "
        f"load {os.getloadavg()[0]:4.1f}  {sliced}  {last if code else ''}",
        flush=True,
    )


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument(
        "--baseline", default="", help="a checkout of today's main, timed in the same run"
    )
    ap.add_argument("--only", default=",".join(CASES))
    ap.add_argument("--out", default="/tmp/fabkiri-bench-fab-speed")
    a = ap.parse_args()
    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    for name in a.only.split(","):
        case(name, ROOT, "this", out)
        if a.baseline:
            case(name, Path(a.baseline), "baseline", out)


if __name__ == "__main__":
    main()
