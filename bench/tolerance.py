"""Benchmark of ``fabkiri tolerance`` (target: the 8x8 circle, 1000 samples at kerf sd 0.02 mm, < 30 s).

Prints the load, then for each pattern the fastest of ``--repeat`` runs of the
whole analysis (wall and process CPU time), and as the baseline measured in the
same run the cost of one shapely intersection per seam and sample (the
exact overlay the first-order seam measure replaces).

    PYTHONPATH=. python3 bench/tolerance.py [--n 1000] [--repeat 3]
"""

from __future__ import annotations

import argparse
import os
import time

import numpy as np
import shapely
from fabkiri.exchange.pattern_json import read_pattern
from fabkiri.mechanics.deploy import closed_states
from fabkiri.mechanics.tolerance import seam_edges, tolerance_analysis
from fabkiri.templates import template_dir


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--n", type=int, default=1000)
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args()
    print(f"load before: {os.getloadavg()[0]:.2f}")
    for path in (
        template_dir("patterns") / "circle-8x8.json",
        template_dir("patterns").parents[1] / "tests" / "data" / "heart-16x16-rigid.json",
    ):
        name = path.stem
        p = read_pattern(path)
        runs = []
        for _ in range(args.repeat):
            c0, t0 = time.process_time(), time.perf_counter()
            r = tolerance_analysis(p, kerf_sd=0.02, hinge_sd=0.05, n=args.n)
            runs.append((time.perf_counter() - t0, time.process_time() - c0, r))
        wall, cpu, r = min(runs, key=lambda x: x[0])
        d = r.to_dict()
        print(
            f"{name}: {args.n} samples, fastest {wall:.2f} s wall / {cpu:.2f} s CPU (slowest "
            f"{max(x[0] for x in runs):.2f} s); closure gap p95 state 1 {d['closure_gap_mm']['closed state 1']['p95']:.3f} mm"
        )
        # baseline: exact overlays of the touching tile pairs, for a tenth of the samples
        c = closed_states(p)[1]
        seams = seam_edges(c, 1e-3 * p.tile_size)
        pairs = np.unique(seams[:, [0, 2]], axis=0)
        polys = shapely.polygons(c)
        k = max(1, args.n // 10)
        t0 = time.perf_counter()
        for _ in range(k):
            shapely.area(
                shapely.intersection(
                    polys[pairs[:, 0]], polys[pairs[:, 1]], grid_size=1e-7 * p.tile_size
                )
            )
        dt = time.perf_counter() - t0
        print(
            f"  baseline: snap-rounded shapely overlays of {len(pairs)} pairs x {k} samples {dt:.2f} s "
            f"(x{args.n / k:.0f} for all samples: {dt * args.n / k:.1f} s)"
        )
    print(f"load after: {os.getloadavg()[0]:.2f}")


if __name__ == "__main__":
    main()
