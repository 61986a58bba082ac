"""Benchmark: a 32×32 non-rigid elastic deployment path of 100 steps (target: under 30 s).

Run from the checkout root:  PYTHONPATH=$PWD python3 bench/deploy.py [--size 32] [--steps 100]

The non-rigid design is made on the spot (tests/designs.py: the standard
pattern, smoothly perturbed and projected back onto the reconfigurability
constraints of both states; not timed). Baselines measured in the same run:
the exact rigid path of the standard pattern of the same size and steps (the
cost floor: placement, energy and the collision check), and the elastic solver
on that standard pattern (a zero-energy path, so Newton converges at once).
"""

from __future__ import annotations

import argparse
import time

import numpy as np
from fabkiri.mechanics.deploy import collisions, elastic_path, rigid_path
from fabkiri.pattern import standard_pattern
from fabkiri.pattern.residuals import hinge_sums
from tests.designs import reconfigurable_design

TARGET_S = 30.0


def timed(fn, *a, **k):
    t0 = time.perf_counter()
    out = fn(*a, **k)
    return out, time.perf_counter() - t0


def main() -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("--size", type=int, default=32)
    ap.add_argument("--steps", type=int, default=100)
    args = ap.parse_args()
    n, steps = args.size, args.steps

    design, t_design = timed(reconfigurable_design, n, n, seed=3, amplitude=0.3, waves=10)
    hs = float(np.abs(hinge_sums(design)).max())
    print(
        f"design      {n}x{n} reconfigurable, max hinge sum {hs:.2e} rad (not rigid), made in {t_design:.2f} s "
        f"(not timed)"
    )

    path, t_elastic = timed(elastic_path, design, steps)
    _, t_coll = timed(collisions, path.corners, design.tile_size)
    marks = path.mark_frames()
    e = path.energy
    print(
        f"elastic     {path.n_frames} frames in {t_elastic:.2f} s "
        f"({'PASS' if t_elastic < TARGET_S else 'FAIL'}: target < {TARGET_S:.0f} s); solver {path.solver}"
    )
    print(
        f"            collision check alone {t_coll:.2f} s; overlaps {len(path.collisions.overlaps)}"
    )
    inside = path.in_segments()
    print(
        f"            E at states {[f'{e[f]:.1e}' for f in marks.values()]}, max E {e.max():.3e} at "
        f"t = {path.t[int(np.argmax(e))]:.4f}; elastic end segments {[(round(a, 4), round(b, 4)) for a, b in path.elastic_segments]} "
        f"(E > {e[inside].min():.1e} inside), max E on the mechanism {e[~inside].max():.1e}"
    )
    print(
        f"            state mismatch (mm) { ({k: float(f'{v:.1e}') for k, v in path.state_mismatch.items()}) }"
    )

    tips, t_tips = timed(elastic_path, design, steps, driver="tips")
    print(
        f"tips        same design, tips driver (a Newton solve at every one of {tips.solver['solves']} steps): "
        f"{t_tips:.2f} s ({'PASS' if t_tips < TARGET_S else 'FAIL'}), {tips.solver['factorizations']} "
        f"factorizations, max E {tips.energy.max():.2e}, mismatch {max(tips.state_mismatch.values()):.1e} mm"
    )

    std = standard_pattern(n, n)
    rigid, t_rigid = timed(rigid_path, std, steps)
    print(
        f"baseline    rigid path of the standard {n}x{n}, {rigid.n_frames} frames: {t_rigid:.2f} s "
        f"(max E {rigid.energy.max():.1e})"
    )
    ez, t_ez = timed(elastic_path, std, steps)
    print(
        f"baseline    elastic solver on the standard {n}x{n} (zero-energy path): {t_ez:.2f} s "
        f"(max E {ez.energy.max():.1e}, {ez.solver['factorizations']} factorizations)"
    )
    return 0 if t_elastic < TARGET_S else 1


if __name__ == "__main__":
    raise SystemExit(main())
