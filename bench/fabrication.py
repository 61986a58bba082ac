"""Must-show runs of fabrication-aware design (issue 14) in one run, and the README designs' table.

``PYTHONPATH=. python3 bench/fabrication.py [--quick] [--jobs 2] [--out DIR]``: every target (circle,
ellipse, heart, the blob CSV) at 8x8 and 16x16, rigid and not, designed for acrylic-3 and for pp-0.5
ligaments at 300 mm (then ``cut`` with no flags) and for prusa-mk4 at 200 mm (then ``print`` with no flags
and ``prusa-slicer --export-gcode`` on every 3MF); then the 16x16 heart at 200 mm with and without
acrylic-3, the impossible 64x64 star, and the summary's cost (closed form for every printer preset and
style) against the bisection it replaced, measured in the same run. ``--table``: the README designs.
``--only frontier``: the 16x16 heart's Hausdorff against the tile width at 200 mm (docs/fabricability.md).
"""

from __future__ import annotations

import argparse
import json
import shutil
import subprocess
import sys
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

TARGETS = ("circle", "ellipse", "heart", "templates/targets/blob-points.csv")
CONFIGS = {
    "acrylic-3": (["--size", "300", "--material", "acrylic-3"], "cut"),
    "pp-0.5 ligament": (["--size", "300", "--material", "pp-0.5", "--hinge", "ligament"], "cut"),
    "prusa-mk4": (["--size", "200", "--printer", "prusa-mk4"], "print"),
}


def run(*args: str) -> tuple[int, str, float]:
    t0 = time.perf_counter()
    p = subprocess.run(
        [sys.executable, "-m", "fabkiri.cli.main", *args], capture_output=True, text=True
    )
    return p.returncode, p.stderr, time.perf_counter() - t0


def last(err: str) -> str:
    lines = (
        [ln for ln in err.strip().splitlines() if ln.startswith("fabkiri:")]
        or err.strip().splitlines()
        or [""]
    )
    return lines[-1][:170]


def slice_all(folder: Path) -> str:
    """prusa-slicer on every 3MF of a print folder, no extra flags: 'ok N' or the first failure."""
    exe = shutil.which("prusa-slicer")
    if exe is None:
        return "no prusa-slicer"
    files = sorted(folder.glob("*.3mf"))
    for f in files:
        p = subprocess.run(
            [exe, "--export-gcode", str(f), "-o", str(f.with_suffix(".gcode"))],
            capture_output=True,
            text=True,
            timeout=900,
        )
        if p.returncode or not f.with_suffix(".gcode").exists():
            return f"slice FAIL {f.name}: {(p.stderr or p.stdout).strip().splitlines()[-1:]}"
    return f"sliced {len(files)}"


def one(out: Path, name: str, tgt: str, tiles: str, rigid: bool) -> tuple[str, Path | None]:
    flags, after = CONFIGS[name]
    stem = stem_of(name, tgt, tiles, rigid)
    pj = out / f"{stem}.json"
    code, err, t = run(
        "design",
        "--tiles",
        tiles,
        "--target",
        tgt,
        *flags,
        *(["--rigid"] if rigid else []),
        "--no-preview",
        "-o",
        str(pj),
    )
    line = f"{stem:44s} design {code}"
    if not pj.exists():
        return line + "  " + last(err), None
    rep = json.loads(pj.read_text())["design"]["report"]
    fr = rep.get("fabrication") or {}
    act = sum(fr.get("active", {}).values())
    conf = (rep.get("conformance") or {}).get("deployed") or {}
    thin = rep["fabricability"]["thinnest_tile_mm"]
    line += (
        f" {rep['status']:11s} active {act:3d} thinnest {thin:6.3g} mm Hausdorff "
        f"{100 * conf.get('hausdorff_rel', float('nan')):5.2f} %"
    )
    cont = rep.get("continuation")
    if cont:
        line += f" [{cont['how']}]"
    c2, e2, t2 = run(after, str(pj), "-o", str(out / stem))
    line += f"  {after} {c2}"
    if c2:
        line += "  " + last(e2)
    return line + f"  ({t + t2:.0f} s)", (out / stem if after == "print" and not c2 else None)


def stem_of(name: str, tgt: str, tiles: str, rigid: bool) -> str:
    return f"{Path(tgt).stem}-{tiles}{'-rigid' if rigid else ''}-{name.replace(' ', '-')}"


def matrix(out: Path, sizes, configs, jobs: int, pick: list[str] | None = None) -> None:
    """Designs and cut/print on ``jobs`` workers; the slow slices of each printed folder in the background,
    one at a time, printed as they finish. ``pick``: only the cases whose stem is listed, in that order."""
    cases = [
        (n, tg, ti, r) for n in configs for tg in TARGETS for ti in sizes for r in (False, True)
    ]
    if pick:
        by_stem = {stem_of(*c): c for c in cases}
        cases = [by_stem[s] for s in pick]

    def sliced(folder: Path) -> None:
        t = time.perf_counter()
        print(
            f"{folder.name:44s} {slice_all(folder)}  ({time.perf_counter() - t:.0f} s)", flush=True
        )

    with ThreadPoolExecutor(1) as slicer, ThreadPoolExecutor(jobs) as ex:
        for line, folder in ex.map(lambda c: one(out, *c), cases):
            print(line, flush=True)
            if folder is not None:
                slicer.submit(sliced, folder)


def heart(out: Path) -> None:
    """The 16x16 heart at 200 mm, with and without acrylic-3 (thinnest tile, Hausdorff)."""
    for rigid in ([], ["--rigid"]):
        for what, flags in (("without", []), ("acrylic-3", ["--material", "acrylic-3"])):
            pj = out / f"heart16-200-{what}{''.join(rigid)}.json"
            code, err, t = run(
                "design",
                "--tiles",
                "16x16",
                "--target",
                "heart",
                "--size",
                "200",
                *flags,
                *rigid,
                "--no-preview",
                "-o",
                str(pj),
            )
            name = f"heart 16x16 200 mm {what:9s}{' rigid' if rigid else ''}"
            if not pj.exists():
                print(f"{name}: exit {code} {last(err)}")
                continue
            rep = json.loads(pj.read_text())["design"]["report"]
            conf = rep["conformance"]["deployed"]
            how = (rep.get("continuation") or {}).get("how", "")
            print(
                f"{name}: exit {code} {rep['status']}, thinnest tile "
                f"{rep['fabricability']['thinnest_tile_mm']:.3g} mm, Hausdorff {conf['hausdorff_mm']:.3g} mm "
                f"({100 * conf['hausdorff_rel']:.2f} %) {how} ({t:.0f} s)",
                flush=True,
            )


def frontier(out: Path, widths=(2.0, 3.0, 3.5, 4.0, 4.5, 5.0)) -> None:
    """Hausdorff of the 16x16 heart at 200 mm against the tile width w (hinge spacing w too, as acrylic tape):
    rigid family, one step from the design without rows, then the minimax refinement. Scale-free: 3 mm tiles
    meet the same figure at 200 * 3 / w mm."""
    from dataclasses import replace

    from fabkiri.design.core.conformance import deployed
    from fabkiri.design.core.refine import refine_minimax
    from fabkiri.design.quad.fabrication import FabricationLimits
    from fabkiri.design.quad.solve import DesignRequest, design
    from fabkiri.design.targets.lookup import load_target
    from fabkiri.pattern import thinness as fab

    tgt = load_target("heart", 200)
    base = DesignRequest(
        rows=16, cols=16, target=tgt, rigid=True, init="rescaled", second_opinion=False
    )
    free = design(base).pattern.nodes
    for w in widths:
        c0 = time.process_time()
        req = replace(
            base, fabrication=FabricationLimits(min_width_mm=w, hinge_spacing_mm=w, margin=0.02)
        )
        one = design(replace(req, start=free))
        h0 = deployed(one.pattern.nodes, one.pattern.topology, tgt)["hausdorff_rel"]
        best, trace, _ = refine_minimax(req, one.pattern.nodes)
        kept = best if best is not None and min(trace) < h0 else one
        print(
            f"w {w:4.1f} mm (w/size {w / 200:.4f}): one step H {100 * h0:.2f} %, refined H "
            f"{100 * min([h0, *[t for t in trace if t == t]]):.2f} %, thinnest "
            f"{fab.widths(kept.pattern.corners()).min():.2f} mm; 3 mm tiles at {600 / w:.0f} mm "
            f"({time.process_time() - c0:.1f} CPU s)",
            flush=True,
        )


def impossible(out: Path) -> None:
    pj = out / "star64.json"
    code, err, t = run(
        "design",
        "--tiles",
        "64x64",
        "--target",
        "star",
        "--size",
        "50",
        "--material",
        "acrylic-3",
        "-o",
        str(pj),
    )
    print(f"64x64 star at 50 mm, acrylic-3: exit {code}, wrote {pj.exists()}: {err.strip()}")


def summary_cost() -> None:
    """CPU s of the summary (every material, every printer preset and style, closed form) against the
    bisection on the plan checks for the same presets (what one printer's minimum cost before)."""
    from fabkiri.exchange.pattern_json import read_pattern
    from fabkiri.fabricate import fabricability as fb
    from fabkiri.fabricate.print.printers import available_printers, load_printer

    for name, src in (
        ("circle-8x8-rigid", "templates/patterns"),
        ("heart-16x16-rigid", "tests/data"),
        ("circle-32x32-rigid", "tests/data"),
    ):
        p = read_pattern(Path(src) / f"{name}.json")
        t = time.process_time()
        fb.summary(p)
        ts = time.process_time() - t
        t = time.process_time()
        for pr in available_printers():
            fb.print_minimum(p, "tiles-and-strips", load_printer(pr))
        tb = time.process_time() - t
        print(
            f"summary {name}: {ts:.3f} CPU s (all {len(available_printers())} printers x 3 styles, closed form); "
            f"bisection, tiles-and-strips only: {tb:.2f} CPU s",
            flush=True,
        )


README_DESIGNS = {  # the designs of README.md's "Designing" section
    "circle 16x16 rigid 120 mm": [
        "--tiles",
        "16x16",
        "--target",
        "circle",
        "--size",
        "120",
        "--rigid",
    ],
    "heart 16x16": ["--tiles", "16x16", "--target", "heart"],
    "blob-points.csv 8x8": ["--tiles", "8x8", "--target", "templates/targets/blob-points.csv"],
    "square/circle 9x9 rigid": [
        "--tiles",
        "9x9",
        "--rigid",
        "--contracted-target",
        "1:square",
        "--contracted-target",
        "2:circle",
    ],
    "ellipse 8x8 sym x parallelogram": [
        "--tiles",
        "8x8",
        "--target",
        "ellipse",
        "--symmetry",
        "x",
        "--holes",
        "parallelogram",
    ],
}
TABLE_FOR = {
    "before": [],
    "acrylic-3": ["--material", "acrylic-3"],
    "pp-0.5 ligament": ["--material", "pp-0.5", "--hinge", "ligament"],
}


def table(out: Path, pick: list[str] | None = None) -> None:
    """Markdown rows: per README design and what it was made for, thinnest tile and the smallest cut width
    per material (its default hinge kind); ``pick``: only these designs (README_DESIGNS names)."""
    from fabkiri.fabricate.cut.materials import available, load_material

    mats = available()
    print(
        "| design | made for | status | thinnest tile mm | "
        + " | ".join(f"{m} ({load_material(m).hinge}) mm" for m in mats)
        + " |"
    )
    print("|" + "---|" * (4 + len(mats)))
    for name, args in README_DESIGNS.items():
        if pick and name not in pick:
            continue
        for what, flags in TABLE_FOR.items():
            pj = (
                out
                / f"table-{name.replace('/', '-').replace(' ', '_')}-{what.replace(' ', '_')}.json"
            )
            code, err, t = run("design", *args, *flags, "--no-preview", "-o", str(pj))
            if not pj.exists():
                print(f"| {name} | {what} | exit {code}: {last(err)[:80]} |")
                continue
            rep = json.loads(pj.read_text())["design"]["report"]
            fb = rep["fabricability"]
            cells = []
            for m in mats:
                c = fb["cut"][m][load_material(m).hinge]
                cells.append("never" if c["min_width_mm"] is None else f"{c['min_width_mm']:.4g}")
            shape = (rep.get("conformance") or {}).get("deployed", {}).get("hausdorff_rel")
            extra = "" if shape is None else f", H {100 * shape:.2f} %"
            print(
                f"| {name} | {what} | {rep['status']}{extra} ({t:.0f} s) | {fb['thinnest_tile_mm']:.3g} | "
                + " | ".join(cells)
                + " |",
                flush=True,
            )


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument(
        "--table", action="store_true", help="the README designs' table, before and after"
    )
    ap.add_argument("--quick", action="store_true", help="8x8 only")
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--out", default="/tmp/fabkiri-bench-fabrication")
    ap.add_argument("--configs", default=",".join(CONFIGS))
    ap.add_argument("--pick", default="", help="comma-separated case stems to run, in that order")
    ap.add_argument("--only", default="summary,impossible,heart,matrix", help="parts to run")
    a = ap.parse_args()
    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    if a.table:
        return table(out, [s for s in a.pick.split(",") if s])
    parts = a.only.split(",")
    if "summary" in parts:
        summary_cost()
    if "impossible" in parts:
        impossible(out)
    if "heart" in parts:
        heart(out)
    if "frontier" in parts:
        frontier(out)
    if "matrix" in parts:
        matrix(
            out,
            ("8x8",) if a.quick else ("8x8", "16x16"),
            a.configs.split(","),
            a.jobs,
            [s for s in a.pick.split(",") if s],
        )


if __name__ == "__main__":
    main()
