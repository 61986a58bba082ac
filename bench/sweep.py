"""Sweep throughput: 48 designs (8 targets x 3 sizes x rigid or not) serially, then on a local Dask cluster,
in one run.

    PYTHONPATH=. python3 bench/sweep.py [--workers N] [--sizes 4x4,5x5,6x6] [--shape-tol 10%]

Serial: every job through `fabkiri.sweep.job.run_job` in this process, one after the other (the code a
worker runs, with the same one-thread BLAS). Cluster: `fabkiri.sweep.sweep` on a LocalCluster of N
single-threaded worker processes (default: one per core), started first and timed apart. Printed: wall and
CPU of both, the throughput ratio (serial wall / cluster wall), the cluster's start-up, and the overhead per
job: (N x cluster wall - the jobs' own wall time on the workers) / jobs, i.e. the worker time not spent in a
job (scheduling, transfer, publishing, idle tail). The load average is printed before and after: on a
shared machine the figures move with it.
"""

from __future__ import annotations

import argparse
import os
import tempfile
import time

from fabkiri.sweep import spec_from_dict, sweep
from fabkiri.sweep.job import run_job

TARGETS = ["circle", "ellipse", "heart", "square", "rectangle", "superellipse", "hexagon", "star"]


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--workers", type=int, default=len(os.sched_getaffinity(0)))
    ap.add_argument("--sizes", default="4x4,5x5,6x6")
    ap.add_argument("--shape-tol", default="10%")
    a = ap.parse_args()
    spec = spec_from_dict(
        {
            "axes": {"target": TARGETS, "tiles": a.sizes.split(","), "rigid": [True, False]},
            "fixed": {"shape_tol": a.shape_tol},
        }
    )
    n = len(spec.jobs)
    print(f"{n} jobs; {os.cpu_count()} cores; load average before {os.getloadavg()}")

    t0, c0 = time.perf_counter(), time.process_time()
    serial = [run_job(job)[0] for job in spec.jobs]
    s_wall, s_cpu = time.perf_counter() - t0, time.process_time() - c0
    print(
        f"serial: {s_wall:.1f} s wall, {s_cpu:.1f} s CPU, {n / s_wall:.3f} jobs/s "
        f"(statuses: {sorted({r['status'] for r in serial})})"
    )

    from distributed import Client, LocalCluster

    t0 = time.perf_counter()
    cluster = LocalCluster(
        n_workers=a.workers,
        threads_per_worker=1,
        processes=True,
        host="127.0.0.1",
        dashboard_address="127.0.0.1:0",
        silence_logs=40,
    )
    client = Client(cluster)
    start = time.perf_counter() - t0
    with tempfile.TemporaryDirectory() as out:
        t0, c0 = time.perf_counter(), time.process_time()
        res = sweep(spec, client, output=out)
        c_wall, c_client_cpu = time.perf_counter() - t0, time.process_time() - c0
        w_cpu = sum(
            client.run(lambda: time.process_time()).values()
        )  # workers' CPU since they started
    client.close()
    cluster.close()
    job_wall = sum(r["time_s"] for r in res.rows)
    job_cpu = sum(r["cpu_s"] for r in res.rows)
    over = (a.workers * c_wall - job_wall) / n
    same = sum(
        abs((r["hausdorff_mm"] or 0) - (s["hausdorff_mm"] or 0)) < 1e-9
        for r, s in zip(res.rows, serial)
    )
    print(
        f"cluster ({a.workers} workers): start-up {start:.1f} s; sweep {c_wall:.1f} s wall, {n / c_wall:.3f} "
        f"jobs/s; jobs' own time {job_wall:.1f} s wall, {job_cpu:.1f} s CPU; workers' CPU incl. imports "
        f"{w_cpu:.1f} s; client CPU {c_client_cpu:.1f} s"
    )
    print(
        f"throughput ratio cluster/serial: {s_wall / c_wall:.2f}x (sweep only), "
        f"{s_wall / (c_wall + start):.2f}x (with the cluster's start-up)"
    )
    print(
        f"overhead per job: {over:.3f} s of worker time ({a.workers} x sweep wall - jobs' wall, over {n} jobs)"
    )
    print(
        f"same Hausdorff distance serial vs cluster: {same}/{n}; load average after {os.getloadavg()}"
    )


if __name__ == "__main__":
    main()
