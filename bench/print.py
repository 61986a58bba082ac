"""Benchmark: a 32x32 pattern to a tiles-and-strips 3MF (target < 10 s); STEP timed separately.

Run from the repository root:  PYTHONPATH=$PWD python3 bench/print.py [--rows 32] [--step]
Prints each stage and, as the baseline measured in the same run, the same job
built the naive way (one boolean per tile instead of one batched extrusion).
"""

from __future__ import annotations

import argparse
import os
import tempfile
import time
from pathlib import Path

from fabkiri.fabricate.print import mesh, solid
from fabkiri.fabricate.print.printers import load_printer
from fabkiri.mechanics.contract import with_contracted_states
from fabkiri.pattern.kinds.quad.lattice import standard_pattern


def stage(label, fn, *a):
    t, c = time.perf_counter(), time.process_time()
    out = fn(*a)
    dt = time.perf_counter() - t
    print(f"  {label:<34} {dt:7.3f} s wall {time.process_time() - c:7.3f} s CPU")
    return out, dt


def naive_tiles(job):
    """Baseline: every tile extruded and pocketed on its own, then unioned."""
    import manifold3d as m3d

    plan, strips, pr = job.plan, job.strips, job.printer
    T, ts = pr.tile_thickness_mm, pr.strip_thickness_mm
    parts = []
    for t, poly in enumerate(plan.tiles):
        ops = [("add", solid.Prism((poly,), 0.0, T))]
        for h in range(plan.n_hinges):
            if t in plan.hinge_tiles[h]:
                s = strips.outline[h]
                z = (T - ts, T + 1) if strips.top[h] else (-1.0, ts)
                ops.append(("sub", solid.Prism((s,), *z)))
        parts.append(solid.realise(solid.Body(f"t{t}", "tile", tuple(ops))))
    return m3d.Manifold.batch_boolean(parts, m3d.OpType.Add)


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--rows", type=int, default=32)
    ap.add_argument("--printer", default="prusa-xl-2t")
    ap.add_argument(
        "--step", action="store_true", help="also time the STEP export (needs build123d)"
    )
    args = ap.parse_args()
    n = args.rows
    printer = load_printer(args.printer)
    pattern = with_contracted_states(standard_pattern(n, n))
    print(f"{n}x{n} tiles ({pattern.topology.n_hinges} hinges), printer {printer.name}")
    t0, c0 = time.perf_counter(), time.process_time()
    job, _ = stage(
        "plan (shrink, faces, strips)", mesh.build_job, pattern, "tiles-and-strips", 1, printer
    )
    r, _ = stage("solids (manifold3d) + meshes", mesh.realise_job, job)
    rep, _ = stage("mesh checks (watertight, clearance)", mesh.check_meshes, r)
    tc, _ = stage("printed tiles vs closed state", mesh.check_printed_tiles, r)
    vr, _ = stage("layout verifier on the top faces", mesh.verify_printed_tiles, pattern, r)
    files, _ = stage("STL + 3MF + preview PNG bytes", mesh.job_files, r, "bench")
    rb, _ = stage("read back the written meshes", mesh.read_back_files, files)
    with tempfile.TemporaryDirectory() as d:
        _, _ = stage("write files", lambda: [Path(d, k).write_bytes(v) for k, v in files.items()])
    total, cpu = time.perf_counter() - t0, time.process_time() - c0
    ok = rep.ok and tc.ok and vr.ok and all(v["ok"] for v in rb.values())
    load = os.getloadavg()[0]  # the machine is shared: wall time counts the other jobs too
    print(
        f"TOTAL pattern -> 3MF + STLs: {total:.2f} s wall (load average {load:.1f} on {os.cpu_count()} cores), "
        f"{cpu:.2f} s CPU (target < 10 s: wall {'met' if total < 10 else 'MISSED'}, CPU {'met' if cpu < 10 else 'MISSED'}); "
        f"checks {'pass' if ok else 'FAIL'}; 3MF {len(files['bench.3mf']) / 1e6:.1f} MB; "
        f"triangles {sum(b['triangles'] for b in rep.bodies)}"
    )
    print("baseline (same run):")
    _, naive = stage("naive per-tile booleans (tiles only)", naive_tiles, job)
    print(
        f"  batched tile solid build is part of 'solids' above; naive tiles alone took {naive:.2f} s"
    )
    if args.step:
        from fabkiri.fabricate.print import step as cad

        t = time.perf_counter()
        import build123d  # noqa: F401

        print(f"  import build123d                   {time.perf_counter() - t:7.3f} s")
        data, _ = stage("STEP (build123d, all bodies)", cad.step_bytes, job.beds[0])
        print(f"  STEP size {len(data) / 1e6:.1f} MB")


if __name__ == "__main__":
    main()
