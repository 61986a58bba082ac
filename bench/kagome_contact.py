"""The homotopy path's contact term on designed kagome patterns: overlaps, E_max and CPU with and
without it (docs/kagome.md, "Contact: hinged tiles must not pass through each other").

Run from the checkout root:  PYTHONPATH=$PWD python3 bench/kagome_contact.py [PATTERN.json ...]
[--steps 40]

Without arguments it deploys the two fixtures of tests/mechanics/test_kagome_contact.py (the designed
ellipse 5x19 and heart 6x11). Each pattern is deployed twice in the same run: springs and
orientation only (contact weight 0, the baseline) and with the contact term (the default).
Columns: overlaps (tile pairs × frames) and the deepest (mm), E_max, the narrowest watched gap
against its rigid value, "reach" (the largest distance of the t = 0, ½, 1 frames to their states,
tile sizes), factorisations and CPU seconds of the path alone.
"""

from __future__ import annotations

import argparse
import os
import time
from pathlib import Path

from fabkiri.api.deploy import overlap_depth
from fabkiri.api.patterns import load_pattern
from fabkiri.mechanics.deploy import deployment_path
from fabkiri.mechanics.drivers.homotopy import Homotopy

FIXTURES = [
    Path(__file__).parents[1] / "tests" / "data" / f"kagome-{n}.json"
    for n in ("ellipse-5x19", "heart-6x11")
]


def row(name: str, p, steps: int, weight: float) -> str:
    old = Homotopy.contact_weight
    Homotopy.contact_weight = weight
    try:
        t0 = time.process_time()
        path = deployment_path(p, steps)
        cpu = time.process_time() - t0
    finally:
        Homotopy.contact_weight = old
    c, sol = path.collisions, path.solver
    deepest = max((overlap_depth(path, o) for o in c.overlaps), default=0.0)
    narrowest = sol["narrowest_gap_to_rigid"]
    reach = max(path.state_mismatch.values()) / p.tile_size
    return (
        f"| {name} | {weight:g} | {len(c.overlaps)} ({deepest:.3g} mm) | {path.energy.max():.4g} | "
        f"{'-' if weight == 0 or narrowest is None else f'{narrowest:.2f}'} | {reach:.1e} | "
        f"{sol['factorizations']} | {cpu:.1f} |"
    )


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("patterns", nargs="*", type=Path, default=FIXTURES)
    ap.add_argument("--steps", type=int, default=40)
    a = ap.parse_args()
    print(f"load average {os.getloadavg()[0]:.1f}")
    print(
        "| pattern | contact weight | overlaps (deepest) | E_max | gap/rigid | reach | "
        "factorisations | CPU s |"
    )
    for f in a.patterns:
        p = load_pattern(f)
        for weight in (0.0, Homotopy.contact_weight):
            print(row(f.stem, p, a.steps, weight), flush=True)
    print(f"load average {os.getloadavg()[0]:.1f}")


if __name__ == "__main__":
    main()
