"""Benchmark: verify a 64x64 pattern and its in-place DXF layout (target: under 2 s in total).

Run: PYTHONPATH=$PWD python3 bench/verify.py [--rows 64] [--repeat 3]
Prints the time of each stage and, as the baseline measured in the same run, the
time of the two contractions alone (fabkiri.mechanics.contract), which every
verification must at least do.
"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))

from fabkiri.mechanics.contract import contract_both, with_contracted_states  # noqa: E402
from fabkiri.pattern import standard_pattern  # noqa: E402
from fabkiri.verify import verify_layout, verify_pattern  # noqa: E402


def main() -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("--rows", type=int, default=64)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--hinge", default="tape", choices=["tape", "separate"])
    ap.add_argument(
        "--writer",
        default="auto",
        choices=["auto", "cut", "fixture"],
        help="who writes the DXF: `fabkiri cut` (the real writer, with labels and marks) "
        "or the minimal test fixture; auto: cut when fabkiri.fabricate is present",
    )
    args = ap.parse_args()
    import numpy as np

    import layout_fixtures as lf

    n = args.rows
    p = with_contracted_states(standard_pattern(n, n, tile_size=10.0, angle_deg=40.0))
    with tempfile.TemporaryDirectory() as tmp:
        writer = args.writer
        if writer == "auto":
            try:
                import fabkiri.fabricate.cut.sheets  # noqa: F401

                writer = "cut"
            except ImportError:
                writer = "fixture"
        if writer == "cut":
            from fabkiri.cli.main import main as cli
            from fabkiri.exchange.pattern_json import write_pattern

            pj = Path(tmp) / "p64.json"
            write_pattern(p, pj)
            t0 = time.perf_counter()
            code = cli(
                [
                    "cut",
                    str(pj),
                    "--material",
                    "acrylic-3",
                    "--hinge",
                    args.hinge,
                    "--formats",
                    "dxf",
                    "--sheet",
                    "3000x3000",
                    "--no-verify",
                    "-o",
                    str(Path(tmp) / "cut"),
                ]
            )
            if code:
                return code
            print(
                f"  (setup: fabkiri cut wrote the layout in {time.perf_counter() - t0:.1f} s, not timed below)"
            )
            path = next((Path(tmp) / "cut").glob("*.dxf"))
        else:
            rng = np.random.default_rng(0)
            C = (
                lf.in_place_corners(p, 1, 0.3)
                if args.hinge == "tape"
                else lf.exploded_corners(p, rng)
            )
            path = lf.write_layout(
                Path(tmp) / "cut",
                p,
                C,
                hinge=args.hinge,
                fmt="dxf",
                kerf_offset=0.1 if args.hinge == "separate" else 0.0,
            )
        size_mb = path.stat().st_size / 1e6
        best = {
            "baseline: contract both states": 1e9,
            "verify_pattern": 1e9,
            "verify_layout": 1e9,
            "total": 1e9,
        }
        for _ in range(args.repeat):
            t0 = time.perf_counter()
            contract_both(p)
            t1 = time.perf_counter()
            rp = verify_pattern(p)
            t2 = time.perf_counter()
            rl = verify_layout(p, path)
            t3 = time.perf_counter()
            for k, v in (
                ("baseline: contract both states", t1 - t0),
                ("verify_pattern", t2 - t1),
                ("verify_layout", t3 - t2),
                ("total", t3 - t1),
            ):
                best[k] = min(best[k], v)
    print(
        f"{n}x{n} tiles ({p.n_tiles}), {args.hinge} DXF layout by {writer} ({size_mb:.1f} MB), "
        f"best of {args.repeat}:"
    )
    for k, v in best.items():
        print(f"  {k:32s} {v:7.3f} s")
    print(
        f"  pattern report ok={rp.ok} ({len(rp.checks)} checks), layout report ok={rl.ok} ({len(rl.checks)} checks)"
    )
    base = best["baseline: contract both states"]
    load = os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")
    print(
        f"  total / baseline = {best['total'] / base:.0f}x (load average {load:.1f} on {os.cpu_count()} cores: "
        f"other work inflates both)"
    )
    print(f"  target: total < 2 s -> {'met' if best['total'] < 2.0 else 'NOT met'}")
    return 0 if rp.ok and rl.ok else 1


if __name__ == "__main__":
    sys.exit(main())
