"""The quad (``rotations``) path leaving the mechanism early, with the contact term: overlaps,
E_max and CPU against main's path, both deployed in the same run.

Run from the checkout root:  PYTHONPATH=$PWD python3 bench/deploy_contact.py [PATTERN.json ...]
[--steps 40]

Without arguments it deploys the two fixtures of tests/test_deploy_contact.py (designed non-rigid
star and ellipse, 16x16). "main" is the path with the residual entering where the first gap folds
(LEAD 0) and no contact term, which is main's path exactly (forward continuation, springs only);
"branch" the defaults. Columns: overlaps (tile pairs × frames) and the deepest (mm), E_max (the
barrier), the narrowest gap against its rigid value, "reach" (the largest distance of the t = 0,
½, 1 frames to their states, tile sizes), factorisations and CPU seconds of the path alone.
"""

from __future__ import annotations

import argparse
import os
import time
from pathlib import Path

from fabkiri.api.deploy import overlap_depth
from fabkiri.api.patterns import load_pattern
from fabkiri.mechanics import mechanism
from fabkiri.mechanics.contact import blend_term, contact_figures, hinge_gaps
from fabkiri.mechanics.deploy import closed_states, deployment_path

FIXTURES = [
    Path(__file__).parents[1] / "tests" / "data" / f"{n}-16x16-nonrigid.json"
    for n in ("star", "ellipse")
]
ROUTES = {"main": (0.0, 0.0), "branch": (mechanism.LEAD, mechanism.Rotations.contact_weight)}


def row(name: str, p, steps: int, route: str) -> str:
    lead, weight = mechanism.LEAD, mechanism.Rotations.contact_weight
    mechanism.LEAD, mechanism.Rotations.contact_weight = ROUTES[route]
    try:
        t0 = time.process_time()
        path = deployment_path(p, steps)
        cpu = time.process_time() - t0
        states = closed_states(p)
        gaps = hinge_gaps(p, states)
        rigid = mechanism.Rotations().values(p, states, path.t)
        terms = [blend_term(gaps, gaps.turned(th), weight=1.0, kappa=1.0) for th in rigid]
        narrowest = contact_figures(terms, list(path.nodes.reshape(path.n_frames, -1)))
    finally:
        mechanism.LEAD, mechanism.Rotations.contact_weight = lead, weight
    c, sol = path.collisions, path.solver
    deepest = max((overlap_depth(path, o) for o in c.overlaps), default=0.0)
    gap = narrowest["narrowest_gap_to_rigid"]
    reach = max(path.state_mismatch.values()) / p.tile_size
    return (
        f"| {name} | {route} | {len(c.overlaps)} ({deepest:.3g} mm) | {path.energy.max():.4g} | "
        f"{'-' if gap is None else f'{gap:.3f}'} | {reach:.1e} | {sol['factorizations']} | "
        f"{cpu:.2f} |"
    )


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("patterns", nargs="*", type=Path, default=FIXTURES)
    ap.add_argument("--steps", type=int, default=40)
    a = ap.parse_args()
    print(f"load average {os.getloadavg()[0]:.1f}")
    print(
        "| pattern | path | overlaps (deepest) | E_max | gap/rigid | reach | factorisations | CPU s |"
    )
    for f in a.patterns:
        p = load_pattern(f)
        for route in ROUTES:
            print(row(f.stem, p, a.steps, route), flush=True)
    print(f"load average {os.getloadavg()[0]:.1f}")


if __name__ == "__main__":
    main()
