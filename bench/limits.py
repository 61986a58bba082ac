"""Measure how `new` and `design` scale with the tile count (peak memory, wall time).

The figures behind fabkiri.limits.MEASURED: each size runs in a fresh interpreter (imports done
before the clock starts), which reports the CPU time of the command (less noisy than wall time under load) and its peak RSS above the
interpreter's; the script prints the power law through the two largest sizes (what limits.py
extrapolates with) and the load average (timings are noisy on a shared machine).
Run: PYTHONPATH=. python3 bench/limits.py [--quick]
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile

import numpy as np

CHILD = """
import resource, sys, time
from fabkiri.cli.main import build_parser, main
build_parser()  # imports every command module: not part of the figure
def cpu():
    r = resource.getrusage(resource.RUSAGE_SELF)
    return r.ru_utime + r.ru_stime
base = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
t0, c0 = time.perf_counter(), cpu()
rc = main(sys.argv[1:])
peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
print(f"RESULT {rc} {cpu() - c0:.4f} {peak - base} {time.perf_counter() - t0:.4f}")
"""

BASE = {
    "new": [],
    "design full": ["--target", "circle", "--solver", "full", "--init", "rescaled"],
    "design rigid": ["--target", "circle", "--rigid"],
    "design kagome": ["--lattice", "kagome", "--target", "circle"],
    "design tube": ["--tube", "cylinder:100,60"],
}


def run(kind: str, n: int, out: str) -> tuple[float, float]:
    argv = (["new"] if kind == "new" else ["design"]) + [
        "--tiles",
        f"{n}x{n}",
        *BASE[kind],
        "--i-know",
        "-o",
        out,
    ]
    r = subprocess.run(
        [sys.executable, "-c", CHILD, *argv],
        capture_output=True,
        text=True,
        env={**os.environ, "FABKIRI_NO_LIMITS": "1"},
    )
    line = [l for l in r.stdout.splitlines() if l.startswith("RESULT")]
    if not line:
        raise SystemExit(f"{kind} {n}x{n} failed: {r.stderr[-400:]}")
    _, rc, secs, kb, wall = line[0].split()
    return float(secs), max(float(kb), 1.0) / 1024.0, float(wall)


def main() -> None:
    quick = "--quick" in sys.argv
    only = [a for a in sys.argv[1:] if not a.startswith("--")]  # e.g. "design kagome"
    sizes = {
        "new": [64, 128, 256, 512] if not quick else [32, 64],
        "design full": [16, 32] if not quick else [8, 16],  # 64x64: stopped after 458 CPU s
        "design rigid": [32, 64, 128] if not quick else [16, 32],
        "design kagome": [6, 8, 10] if not quick else [4, 6],
        "design tube": [6, 8, 12] if not quick else [6, 8],
    }
    print(f"load average {os.getloadavg()[0]:.2f}")
    fits = {}
    with tempfile.TemporaryDirectory() as d:
        for kind, ns in sizes.items():
            if only and kind not in only:
                continue
            rows = []
            for n in ns:
                secs, mb, wall = run(kind, n, os.path.join(d, "p.json"))
                rows.append((n * n, secs, mb))
                print(
                    f"{kind:13s} {n:4d}x{n:<4d} CPU {secs:8.2f} s (wall {wall:7.2f} s, load "
                    f"{os.getloadavg()[0]:.1f})  peak {mb:8.1f} MB",
                    flush=True,
                )
            (n0, s0, m0), (n1, s1, m1) = rows[-2:]
            pt, pm = np.log(s1 / s0) / np.log(n1 / n0), np.log(m1 / m0) / np.log(n1 / n0)
            fits[kind] = [[n, round(s, 2), round(m, 1)] for n, s, m in rows]
            print(
                f"{kind:13s} from {n1} tiles: time ~ tiles^{pt:.2f}, memory ~ tiles^{pm:.2f}",
                flush=True,
            )
    print("MEASURED =", json.dumps(fits))
    print(f"load average {os.getloadavg()[0]:.2f} at the end")


if __name__ == "__main__":
    main()
