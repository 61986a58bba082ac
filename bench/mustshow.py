"""The issue's "must show" runs through the CLI: prints one line per design.

    PYTHONPATH=. python3 bench/mustshow.py [--sizes 8,16] [--out DIR]

Circle, ellipse (2:1), heart and a user points file at each size, with and
without --rigid; then the square-in-state-1 / circle-in-state-2 design at 9x9
(--rigid). Each line: exit code, status, max equality residual, loop closure of
both states (tile sizes), overlaps (deployed / state 1 / state 2), hinge sums,
fit (mode, max and RMS mm, max relative to the target size) and time.
"""

from __future__ import annotations

import argparse
import contextlib
import io
import json
import tempfile
from pathlib import Path

from fabkiri.cli.main import main as cli

ROOT = Path(__file__).resolve().parents[1]


def run(argv: list[str]) -> tuple[int, dict]:
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        code = cli(argv + ["--json"])
    try:
        return code, json.loads(out.getvalue())
    except json.JSONDecodeError:
        return code, {"error": err.getvalue().strip()}


def line(label: str, code: int, r: dict) -> str:
    if "error" in r:
        return f"{label:<34} exit {code}  {r['error']}"
    c = r["checks"]
    parts = [
        f"{label:<34} exit {code}  {r['status']:<11}",
        f"res {r['max_equality_residual']:.1e}",
        f"closure {max(c['closure_1_rel'], c['closure_2_rel']):.1e}",
        f"overlaps {c['overlaps_deployed']}/{c['overlaps_state_1']}/{c['overlaps_state_2']}",
    ]
    if "hinge_sum_max_rad" in c:
        parts.append(f"hinge sums {c['hinge_sum_max_rad']:.1e}")
    f = r.get("fit", {}).get("shape")
    if f:
        parts.append(
            f"fit {r['shape_matching']} max {f['max_mm']:.3g} mm rms {f['rms_mm']:.3g} mm "
            f"({f['max_rel_size']:.2%} of size)"
        )
    for s, g in r.get("closed_outline_fit", {}).items():
        parts.append(
            f"state {s} vs {g['target']}: max {g['max_mm']:.3g} rms {g['rms_mm']:.3g} mm "
            f"({g['max_rel_size']:.2%})"
        )
    for k, g in (r.get("conformance") or {}).items():
        parts.append(
            f"{k} Hausdorff {g['hausdorff_mm']:.3g} mm ({g['hausdorff_rel']:.2%}) 1-IoU "
            f"{g['one_minus_iou']:.3g} {r['shape'][k]['status']}"
        )
    parts.append(
        f"{r.get('time_s_total', r['time_s']):.1f} s, {r['iterations_total']} it (last attempt)"
        + (
            f", inits {[a['init'] for a in r['attempts']]}"
            if len(r.get("attempts", [])) > 1
            else ""
        )
    )
    return "  ".join(parts)


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--sizes", default="8,16")
    ap.add_argument("--out", default=None, help="keep the pattern files here")
    args = ap.parse_args()
    out = Path(args.out) if args.out else Path(tempfile.mkdtemp(prefix="fabkiri-mustshow-"))
    out.mkdir(parents=True, exist_ok=True)
    targets = [
        "circle",
        "ellipse",
        "heart",
        str(ROOT / "templates" / "targets" / "blob-points.csv"),
    ]
    for n in [int(s) for s in args.sizes.split(",")]:
        for t in targets:
            for rigid in (False, True):
                name = f"{Path(t).stem}-{n}x{n}{'-rigid' if rigid else ''}"
                argv = [
                    "design",
                    "--tiles",
                    f"{n}x{n}",
                    "--target",
                    t,
                    "-o",
                    str(out / f"{name}.json"),
                ]
                code, r = run(argv + (["--rigid"] if rigid else []))
                print(line(name, code, r), flush=True)
    code, r = run(
        [
            "design",
            "--tiles",
            "9x9",
            "--rigid",
            "--contracted-target",
            "1:square",
            "--contracted-target",
            "2:circle",
            "-o",
            str(out / "square-circle-9x9-rigid.json"),
        ]
    )
    print(line("square(1)/circle(2) 9x9 rigid", code, r), flush=True)


if __name__ == "__main__":
    main()
