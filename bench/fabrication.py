"""Must-show runs of fabrication-aware design (issue 14): design for a material or printer, then cut or
print with no flags. ``PYTHONPATH=. python3 bench/fabrication.py [--quick] [--out DIR]``.

Each line: target, lattice, rigid, what the design was made for, design exit code and status, the
fabrication rows active, thinnest tile (mm), fit max (mm), then the exit code of ``cut``/``print`` with
no flags and the wall time of both.
"""

from __future__ import annotations

import argparse
import contextlib
import io
import json
import subprocess
import sys
import time
from pathlib import Path

TARGETS = ("circle", "ellipse", "heart", "templates/targets/blob-points.csv")
CONFIGS = {
    "acrylic-3": (["--size", "300", "--material", "acrylic-3"], "cut"),
    "pp-0.5 ligament": (["--size", "300", "--material", "pp-0.5", "--hinge", "ligament"], "cut"),
    "prusa-mk4": (["--size", "200", "--printer", "prusa-mk4"], "print"),
}


def run(*args: str) -> tuple[int, str, float]:
    t0 = time.perf_counter()
    p = subprocess.run([sys.executable, "-m", "fabkiri.cli.main", *args], capture_output=True, text=True)
    return p.returncode, p.stderr, time.perf_counter() - t0


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--quick", action="store_true", help="8x8 only")
    ap.add_argument("--out", default="/tmp/fabkiri-bench-fabrication")
    ap.add_argument("--configs", default=",".join(CONFIGS))
    a = ap.parse_args()
    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    sizes = ("8x8",) if a.quick else ("8x8", "16x16")
    for name in a.configs.split(","):
        flags, after = CONFIGS[name]
        for tgt in TARGETS:
            for tiles in sizes:
                for rigid in (False, True):
                    stem = f"{Path(tgt).stem}-{tiles}{'-rigid' if rigid else ''}-{name.replace(' ', '-')}"
                    pj = out / f"{stem}.json"
                    code, err, t = run("design", "--tiles", tiles, "--target", tgt, *flags,
                                       *(["--rigid"] if rigid else []), "-o", str(pj))
                    line = f"{stem:44s} design {code}"
                    if pj.exists():
                        rep = json.loads(pj.read_text())["design"]["report"]
                        fr = rep.get("fabrication") or {}
                        act = sum(fr.get("active", {}).values())
                        fit = rep.get("fit", {}).get("shape", {}).get("max_mm", float("nan"))
                        thin = rep["fabricability"]["thinnest_tile_mm"]
                        line += f" {rep['status']:11s} active {act:3d} thinnest {thin:6.3g} mm fit {fit:7.3g} mm"
                        c2, e2, t2 = run(after, str(pj), "-o", str(out / stem))
                        line += f"  {after} {c2}  {t + t2:5.1f} s"
                        if c2:
                            line += "  " + e2.strip().splitlines()[-1][:160]
                    else:
                        line += "  " + err.strip().splitlines()[-1][:160]
                    print(line, flush=True)


if __name__ == "__main__":
    main()
