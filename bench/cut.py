"""Benchmark of ``fabkiri cut``: a 64x64 standard pattern to DXF + SVG + verification (target: < 3 s).

Prints, in one run, the phases of cutting (build + write bytes), the writer's
own read-back checks and the independent verifier, with and without labels
(tile IDs, face letters, tape marks: one DXF entity per stroke), and as the
baseline the library floor measured in the same run: ezdxf writing and
reading back the same number of bare LWPOLYLINEs, and svgwrite writing as
many paths.

    PYTHONPATH=. python3 bench/cut.py [--size 64] [--material acrylic-3] [--hinge tape] [--repeat 3]

The machine is shared, so each configuration runs ``--repeat`` times and the
fastest run (by total) is shown, with the slowest total beside it and the
process CPU time of the fastest run (less sensitive to the other processes);
the load average is printed before and after.
"""

from __future__ import annotations

import argparse
import io
import os
import tempfile
import time
from pathlib import Path

from fabkiri.fabricate.cut import readback as R
from fabkiri.fabricate.cut.materials import load_material
from fabkiri.fabricate.cut.sheets import CutOptions, cut_pattern
from fabkiri.mechanics.contract import with_contracted_states
from fabkiri.pattern.kinds.quad.lattice import standard_pattern


def run(pattern, material, hinge, labels):
    c0 = time.process_time()
    t0 = time.perf_counter()
    r = cut_pattern(
        pattern,
        CutOptions(
            material=load_material(material),
            hinge=hinge,
            formats=("dxf", "svg"),
            labels=labels,
            stem="bench",
        ),
    )
    t1 = time.perf_counter()
    files = dict(r.files)
    files["manifest.json"] = r.manifest_bytes()
    rb = R.self_checks(r, files)
    t2 = time.perf_counter()
    with tempfile.TemporaryDirectory() as tmp:
        for k, v in files.items():
            (Path(tmp) / k).write_bytes(v)
        ver = R.run_verifier(pattern, r, Path(tmp))
    t3 = time.perf_counter()
    cpu = time.process_time() - c0
    n = sum(len(x) for s in r.sheets for x in s.layers.values())
    failed = [c.name for c in rb.failed()]
    for key, rep in ver.get("files", {}).items():
        failed += [f"verifier {key}: {c['name']}" for c in rep.get("checks", []) if not c["ok"]]
    return {
        "cut": t1 - t0,
        "self": t2 - t1,
        "verify": t3 - t2,
        "total": t3 - t0,
        "cpu": cpu,
        "entities": n,
        "sheets": len(r.sheets),
        "failed": failed,
    }


def floor(n: int) -> dict:
    """ezdxf/svgwrite doing nothing but writing (and ezdxf reading) ``n`` 4-point polylines."""
    import ezdxf
    import svgwrite

    t0 = time.perf_counter()
    doc = ezdxf.new("R2010", units=4)
    msp = doc.modelspace()
    for i in range(n):
        msp.add_lwpolyline(
            [(i, 0), (i + 1, 1), (i, 2), (i + 1, 3)], format="xy", dxfattribs={"layer": "CUT"}
        )
    buf = io.StringIO()
    doc.write(buf)
    t1 = time.perf_counter()
    ezdxf.read(io.StringIO(buf.getvalue()))
    t2 = time.perf_counter()
    dwg = svgwrite.Drawing(size=("100mm", "100mm"), debug=False)
    for i in range(n):
        dwg.add(dwg.path(d=f"M{i},0 L{i + 1},1 L{i},2 L{i + 1},3"))
    dwg.tostring()
    t3 = time.perf_counter()
    return {"dxf_write": t1 - t0, "dxf_read": t2 - t1, "svg_write": t3 - t2}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--size", type=int, default=64)
    ap.add_argument("--material", default="acrylic-3")
    ap.add_argument("--hinge", default="tape")
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args()
    n = args.size
    pattern = with_contracted_states(standard_pattern(n, n))
    print(
        f"{n}x{n} standard pattern, 10 mm tiles, {args.material}, {args.hinge} hinges, DXF + SVG (target < 3 s)"
    )
    print("load average before: " + " ".join(f"{x:.2f}" for x in os.getloadavg()))
    print(
        f"{'labels':>7} {'sheets':>6} {'entities':>8} {'cut+write':>9} {'self-check':>10} {'verifier':>8} "
        f"{'total':>7} {'slowest':>7} {'CPU':>6}  failed checks (best of {args.repeat})"
    )
    rows = {}
    for labels in (False, True):
        runs = [run(pattern, args.material, args.hinge, labels) for _ in range(max(1, args.repeat))]
        m = rows[labels] = min(runs, key=lambda r: r["total"])
        failed = sorted({f for r in runs for f in r["failed"]})
        print(
            f"{str(labels):>7} {m['sheets']:>6} {m['entities']:>8} {m['cut']:>8.2f}s {m['self']:>9.2f}s "
            f"{m['verify']:>7.2f}s {m['total']:>6.2f}s {max(r['total'] for r in runs):>6.2f}s {m['cpu']:>5.2f}s  "
            f"{', '.join(failed) or '-'}"
        )
    base = floor(rows[True]["entities"])
    print(
        f"baseline (same run): ezdxf writes {rows[True]['entities']} bare LWPOLYLINEs in {base['dxf_write']:.2f} s "
        f"and reads them in {base['dxf_read']:.2f} s; svgwrite writes as many paths in {base['svg_write']:.2f} s"
    )
    print("load average after: " + " ".join(f"{x:.2f}" for x in os.getloadavg()))


if __name__ == "__main__":
    main()
