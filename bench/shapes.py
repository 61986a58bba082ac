"""Shape conformance of `fabkiri design` across targets, lattice sizes and --rigid, in one run.

    PYTHONPATH=. python3 bench/shapes.py [--sizes 16,32] [--quick] [--fit outline,tips] [--targets a,b]

Every design runs through the CLI (`design ... --json --no-preview`, default initial-guess order, retries
included), so the figures are what a user gets. Per line: Hausdorff distance of the boundary-tip polygon to
the target (% of the target size, the larger side of its bounding box), 1 - IoU, tip spacing min/mean
(mm), max equality residual, overlapping tile pairs (deployed / state 1 / state 2), the goal of the issue
and whether it is met, time of all attempts. `--fit tips` runs the previous fit (boundary tips on their
arcs only) in the same run for comparison. `--quick` skips non-rigid designs above 16x16 tiles (about a
minute and a half each on this box).
"""

from __future__ import annotations

import argparse
import contextlib
import io
import json
import tempfile
import time
from pathlib import Path

from fabkiri.cli.main import main as cli

ROOT = Path(__file__).resolve().parents[1]
TARGETS = {
    "circle": ["circle"],
    "ellipse-2:1": ["ellipse"],
    "superellipse": ["superellipse"],
    "hexagon": ["hexagon"],
    "heart": ["heart"],
    "star": ["star"],
    "blob-csv": [str(ROOT / "templates" / "targets" / "blob-points.csv"), "--size", "100"],
    "leaf-svg": [str(ROOT / "bench" / "data" / "leaf.svg"), "--size", "100"],
}
CONVEX = {"circle", "ellipse-2:1", "superellipse", "hexagon"}


def goal(name: str, n: int) -> float | None:
    """The issue's goals (Hausdorff, fraction of the size)."""
    if name in CONVEX:
        return 0.01
    if name == "heart":
        return 0.02
    if name == "star":
        return 0.04 if n >= 32 else 0.06
    return None


def run(argv: list[str]) -> tuple[int, dict, float]:
    out, err = io.StringIO(), io.StringIO()
    t0 = time.perf_counter()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        code = cli(argv + ["--json", "--no-preview"])
    wall = time.perf_counter() - t0
    try:
        return code, json.loads(out.getvalue()), wall
    except json.JSONDecodeError:
        return code, {"error": err.getvalue().strip().splitlines()[-1]}, wall


def line(label: str, code: int, r: dict, wall: float, g: float | None) -> str:
    if "error" in r:
        return f"{label:<36} exit {code}  {r['error']}"
    c = r["conformance"]["deployed"]
    k = r["checks"]
    h = c["hausdorff_rel"]
    verdict = "" if g is None else (f"goal {100 * g:.0f} % " + ("met" if h <= g else "MISSED"))
    return (
        f"{label:<36} exit {code}  {r['status']:<11} H {100 * h:6.2f} %  1-IoU {c['one_minus_iou']:.4f}  "
        f"spacing {c['spacing_min_mm']:6.3f}/{c['spacing_mean_mm']:6.3f} mm  res {r['max_equality_residual']:.1e}"
        f"  overlaps {k['overlaps_deployed']}/{k['overlaps_state_1']}/{k['overlaps_state_2']}  {wall:6.1f} s  "
        f"{verdict}"
    )


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--sizes", default="16,32")
    ap.add_argument("--targets", default=",".join(TARGETS))
    ap.add_argument(
        "--fit", default="outline", help="comma-separated fits to run: outline (default), tips"
    )
    ap.add_argument("--rigid", default="1,0", help="1: --rigid, 0: not (comma-separated)")
    ap.add_argument("--quick", action="store_true", help="skip non-rigid designs above 16x16 tiles")
    ap.add_argument("--out", default=None, help="keep the pattern files here")
    args = ap.parse_args()
    out = Path(args.out) if args.out else Path(tempfile.mkdtemp(prefix="fabkiri-shapes-"))
    out.mkdir(parents=True, exist_ok=True)
    import os

    print(f"load average {os.getloadavg()[0]:.2f}", flush=True)
    for n in [int(s) for s in args.sizes.split(",")]:
        for rigid in [s == "1" for s in args.rigid.split(",")]:
            if args.quick and not rigid and n > 16:
                print(f"(--quick: non-rigid {n}x{n} skipped)", flush=True)
                continue
            for name in args.targets.split(","):
                for fit in args.fit.split(","):
                    label = f"{name}-{n}x{n}{'-rigid' if rigid else ''}{'' if fit == 'outline' else '-tips'}"
                    argv = [
                        "design",
                        "--tiles",
                        f"{n}x{n}",
                        "--target",
                        *TARGETS[name],
                        "--fit",
                        fit,
                        "-o",
                        str(out / f"{label}.json"),
                    ] + (["--rigid"] if rigid else [])
                    code, r, wall = run(argv)
                    print(line(label, code, r, wall, goal(name, n)), flush=True)


if __name__ == "__main__":
    main()
