"""Must-show runs of fabrication-aware design (issue 14): design for a material or printer, then cut or
print with no flags. ``PYTHONPATH=. python3 bench/fabrication.py [--quick] [--out DIR]``.

Each line: target, lattice, rigid, what the design was made for, design exit code and status, the
fabrication rows active, thinnest tile (mm), fit max (mm), then the exit code of ``cut``/``print`` with
no flags and the wall time of both.
"""

from __future__ import annotations

import argparse
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


def hausdorff(path: Path) -> float:
    """Hausdorff distance (mm, shapely) between the deployed tip polygon and the target outline."""
    import numpy as np
    import shapely

    from fabkiri.design.constraints import Stencils
    from fabkiri.design.initial import tip_polygon
    from fabkiri.pattern.io import read_pattern

    p = read_pattern(path)
    tips = tip_polygon(p.nodes, Stencils.from_pattern(p))
    target = np.asarray(p.design["target"]["points"])
    return float(shapely.hausdorff_distance(shapely.Polygon(tips), shapely.Polygon(target), densify=0.01))


README_DESIGNS = {  # the designs of README.md's "Designing" section
    "circle 16x16 rigid 120 mm": ["--tiles", "16x16", "--target", "circle", "--size", "120", "--rigid"],
    "heart 8x8": ["--tiles", "8x8", "--target", "heart"],
    "blob-points.csv 8x8": ["--tiles", "8x8", "--target", "templates/targets/blob-points.csv"],
    "square/circle 9x9 rigid": ["--tiles", "9x9", "--rigid", "--contracted-target", "1:square",
                                "--contracted-target", "2:circle"],
    "ellipse 8x8 sym x parallelogram": ["--tiles", "8x8", "--target", "ellipse", "--symmetry", "x", "--holes",
                                        "parallelogram"],
}
TABLE_FOR = {"before": [], "acrylic-3": ["--material", "acrylic-3"],
             "pp-0.5 ligament": ["--material", "pp-0.5", "--hinge", "ligament"]}


def table(out: Path) -> None:
    """Markdown rows: per README design and what it was made for, thinnest tile and the smallest cut width
    per material (its default hinge kind)."""
    from fabkiri.fabricate.materials import available, load_material

    mats = available()
    print("| design | made for | status | thinnest tile mm | " + " | ".join(f"{m} ({load_material(m).hinge}) mm"
                                                                  for m in mats) + " |")
    print("|" + "---|" * (4 + len(mats)))
    for name, args in README_DESIGNS.items():
        for what, flags in TABLE_FOR.items():
            pj = out / f"table-{abs(hash((name, what)))}.json"
            code, err, t = run("design", *args, *flags, "-o", str(pj))
            if not pj.exists():
                print(f"| {name} | {what} | exit {code}: {err.strip().splitlines()[-1][:80]} |")
                continue
            rep = json.loads(pj.read_text())["design"]["report"]
            fb = rep["fabricability"]
            cells = []
            for m in mats:
                c = fb["cut"][m][load_material(m).hinge]
                cells.append("never" if c["min_width_mm"] is None else f"{c['min_width_mm']:.4g}")
            print(f"| {name} | {what} | {rep['status']} ({t:.0f} s) | {fb['thinnest_tile_mm']:.3g} | "
                  + " | ".join(cells) + " |", flush=True)


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--table", action="store_true", help="the README designs' table, before and after")
    ap.add_argument("--hausdorff", nargs="+", metavar="PATTERN", help="only print the Hausdorff distance of these")
    ap.add_argument("--quick", action="store_true", help="8x8 only")
    ap.add_argument("--out", default="/tmp/fabkiri-bench-fabrication")
    ap.add_argument("--configs", default=",".join(CONFIGS))
    a = ap.parse_args()
    if a.table:
        Path(a.out).mkdir(parents=True, exist_ok=True)
        return table(Path(a.out))
    if a.hausdorff:
        for f in a.hausdorff:
            from fabkiri.pattern import fabricability
            from fabkiri.pattern.io import read_pattern

            rep = json.loads(Path(f).read_text())["design"]["report"]
            thin = fabricability.widths(read_pattern(f).contracted[1]).min()
            print(f"{f}: Hausdorff {hausdorff(Path(f)):.4g} mm, thinnest tile {thin:.4g} mm, "
                  f"fit max {rep['fit']['shape']['max_mm']:.4g} mm, status {rep['status']}")
        return
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
                        line += (f" {rep['status']:11s} active {act:3d} thinnest {thin:6.3g} mm fit {fit:7.3g} mm"
                                 f" H {hausdorff(pj):7.3g} mm")
                        c2, e2, t2 = run(after, str(pj), "-o", str(out / stem))
                        line += f"  {after} {c2}  {t + t2:5.1f} s"
                        if c2:
                            line += "  " + e2.strip().splitlines()[-1][:160]
                    else:
                        line += "  " + err.strip().splitlines()[-1][:160]
                    print(line, flush=True)


if __name__ == "__main__":
    main()
