"""Kagome deployment paths (homotopy driver): the table of docs/kagome.md, "Deploying designed
kagome patterns".

Run from the checkout root:  PYTHONPATH=$PWD python3 bench/kagome_deploy.py [--all] [--steps 40]

Rows: the standard 7×5 (a zero-energy path: the baseline), generic points of the reconfigurable
family near the standard, and patterns designed on the spot by `design --lattice kagome` (the 9×15
circle and the 6×10 ellipse and heart; `--all` adds the other sizes). Columns: "reach" the largest
distance of the t = 0, ½, 1 frames to their states in tile sizes, E at the states, E_max, the largest
node move between two sub-steps against the rigid blend's, tiles turned over, overlaps (tile pairs
× frames; in brackets the pairs already overlapping in the deployed state) and CPU seconds of the
path alone (designing is not timed).
"""

from __future__ import annotations

import argparse
import os
import time
from dataclasses import replace

import fabkiri.design.kagome.constraints as K
from fabkiri.api.kagome import design_kagome
from fabkiri.mechanics.deploy import collisions, deployment_path
from fabkiri.pattern.kinds.kagome.lattice import standard_kagome

DESIGNS = [(9, 15, "circle", 180), (6, 10, "ellipse", 120), (6, 10, "heart", 120)]
MORE = [
    (6, 10, "circle", 120),
    (5, 18, "ellipse", 198),
    (12, 20, "circle", 240),
    (9, 15, "ellipse", 180),
    (8, 28, "ellipse", 300),
    (9, 15, "heart", 180),
    (12, 20, "heart", 240),
]


def generic(rows: int, cols: int, step: float):
    p = standard_kagome(rows, cols, angle_deg=45.0)
    x = K.nearby_solution(p, (1, 2), seed=5, step=step)
    return replace(p, nodes=x * p.tile_size, lattice=None, name=f"generic {rows}x{cols}")


def patterns(everything: bool):
    yield "standard 7x5 (psi = 45)", standard_kagome(7, 5, angle_deg=45.0)
    for r, c, step in ((4, 4, 0.02), (7, 5, 0.02), (6, 10, 0.05)):
        yield f"generic {r}x{c}", generic(r, c, step)
    for r, c, target, size in DESIGNS + (MORE if everything else []):
        yield f"design {r}x{c} {target} {size}", design_kagome(r, c, target, size).pattern


def row(name: str, p, steps: int) -> str:
    t0 = time.process_time()
    path = deployment_path(p, steps)
    cpu = time.process_time() - t0
    s, sol = path.summary(), path.solver
    reach = max(path.state_mismatch.values()) / p.tile_size
    deployed = len(collisions(p.corners()[None], p.tile_size).overlaps)
    return (
        f"| {name} | {p.n_tiles} | {reach:.1e} | {max(s['energy_at_states'].values()):.1e} | "
        f"{s['energy_max']:.3g} | {sol['largest_substep_move_tile_sizes']:.3f} / "
        f"{sol['rigid_blend_largest_substep_move_tile_sizes']:.3f} | {sol['mirrored_tiles_max']} | "
        f"{s['overlaps']} ({deployed}) | {cpu:.1f} |"
    )


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--all", action="store_true", help="every designed size of the docs' table")
    ap.add_argument("--steps", type=int, default=40)
    a = ap.parse_args()
    print(f"load average {os.getloadavg()[0]:.1f}")
    print(
        "| pattern | tiles | reach | E at the states | E_max | step / blend | turned over | "
        "overlaps | CPU s |"
    )
    for name, p in patterns(a.all):
        print(row(name, p, a.steps), flush=True)
    print(f"load average {os.getloadavg()[0]:.1f}")


if __name__ == "__main__":
    main()
