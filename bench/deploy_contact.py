"""The quad (``rotations``) path leaving the mechanism early, with the contact term: overlaps,
E_max and CPU against main's path, both deployed in the same run.

Run from the checkout root:  PYTHONPATH=$PWD python3 bench/deploy_contact.py [PATTERN.json ...]
[--steps 40]
    PYTHONPATH=$PWD python3 bench/deploy_contact.py --table [--base CHECKOUT] [--work DIR]
[--targets heart,star] [--sizes 16,32] [--modes free,full]

``--table`` is issue #37's deploy table: every non-rigid design of bench/shapes.py's table targets
(``free``: the table's non-rigid mode, the CLI defaults; ``full``: ``--solver full``, the sparse
solver over all nodes, which leaves the rigid family and so exercises the elastic path) designed
through the CLI (kept in ``--work`` and reused), then ``deploy`` through the CLI in its own process
under ``nice`` with this checkout and, with ``--base``, with that checkout in the same run. Per
row: the design's exit code and path kind, and per checkout deploy's exit code, its overlaps (tile
pairs × frames) and the deepest (mm), and the CPU seconds of the deploy process; the load average
before and after the row.

Without arguments it deploys the two fixtures of tests/mechanics/test_deploy_contact.py (designed non-rigid
star and ellipse, 16x16). "main" is the path with the residual entering where the first gap folds
(LEAD 0) and no contact term, which is main's path exactly (forward continuation, springs only);
"branch" the defaults. Columns: overlaps (tile pairs × frames) and the deepest (mm), E_max (the
barrier), the narrowest gap against its rigid value, "reach" (the largest distance of the t = 0,
½, 1 frames to their states, tile sizes), factorisations and CPU seconds of the path alone.
"""

from __future__ import annotations

import argparse
import json
import os
import re
import resource
import subprocess
import sys
import time
from pathlib import Path

from fabkiri.api.deploy import overlap_depth
from fabkiri.api.patterns import load_pattern
from fabkiri.mechanics.contact import blend_term, contact_figures, hinge_gaps
from fabkiri.mechanics.deploy import closed_states, deployment_path
from fabkiri.mechanics.drivers import rotations as mechanism

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


MODES = {"free": [], "full": ["--solver", "full"]}
DEEP = re.compile(r"\(([0-9.eE+-]+) mm deep\)")


def _cli(code: Path, argv: list[str]) -> tuple[int, str, float]:
    """``fabkiri ARGV`` with ``code`` first on the path, in its own process under ``nice``: exit
    code, stderr and CPU seconds."""
    env = dict(
        os.environ, PYTHONPATH=os.pathsep.join([str(code), os.environ.get("PYTHONPATH", "")])
    )
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    cmd = ["nice", sys.executable, "-P", "-m", "fabkiri.cli.main", *argv]  # -P: not the cwd first
    done = subprocess.run(cmd, capture_output=True, text=True, env=env)
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = after.ru_utime + after.ru_stime - before.ru_utime - before.ru_stime
    return done.returncode, done.stderr, cpu


def _deploy_cell(code: Path, pattern: Path, out: Path) -> tuple[str, str]:
    """Deploy ``pattern`` with the checkout ``code``: (path kind, "exit, overlaps (deepest), CPU")."""
    rc, err, cpu = _cli(code, ["deploy", str(pattern), "--no-frames", "-o", str(out)])
    try:
        s = json.loads((out / "deploy.json").read_text())
    except (OSError, json.JSONDecodeError):
        return "-", f"exit {rc}: {err.strip().splitlines()[-1] if err.strip() else '?'}"
    depth = s.get("overlap_max_depth_mm")
    if depth is None:  # a checkout that does not write it: the deepest it printed
        depth = max((float(d) for d in DEEP.findall(err)), default=0.0)
    kind = s["path"] if s["path"] == "rigid" else f"elastic ({s['driver']})"
    return kind, f"exit {rc}, {s['overlaps']} ({depth:.3g} mm), {cpu:.1f} s"


def table(a) -> None:
    """Issue #37's deploy table (module docstring), one markdown row per design, as it goes."""
    import importlib.util

    spec = importlib.util.spec_from_file_location("shapes", Path(__file__).with_name("shapes.py"))
    assert spec is not None and spec.loader is not None
    shapes = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(shapes)  # bench/shapes.py: the table's targets
    TABLE_TARGETS, TARGETS = shapes.TABLE_TARGETS, shapes.TARGETS

    here = Path(__file__).resolve().parents[1]
    a.work.mkdir(parents=True, exist_ok=True)
    checkouts = {"branch": here, **({"base": a.base} if a.base else {})}
    print(f"load average {os.getloadavg()[0]:.1f}; deploy CPU s per checkout", flush=True)
    print(
        "| target | tiles | mode | design exit | path | "
        + " | ".join(checkouts)
        + " | load before/after |"
    )
    print("|---|---|---|---|---|" + "---|" * len(checkouts) + "---|")
    for name in (a.targets or ",".join(TABLE_TARGETS)).split(","):
        for n in [int(v) for v in a.sizes.split(",")]:
            for mode in a.modes.split(","):
                load0 = os.getloadavg()[0]
                label = f"{name}-{n}x{n}-{mode}"
                pattern = a.work / f"{label}.json"
                if not (a.work / f"{label}.exit").exists():
                    argv = ["design", "--tiles", f"{n}x{n}", "--target", *TARGETS[name]]
                    argv += [*MODES[mode], "--json", "--no-preview", "-o", str(pattern)]
                    rc = _cli(here, argv)[0]
                    (a.work / f"{label}.exit").write_text(f"{rc}\n")
                design_rc = (a.work / f"{label}.exit").read_text().strip()
                if not pattern.exists():
                    print(f"| {name} | {n}×{n} | {mode} | {design_rc} | (no pattern) |", flush=True)
                    continue
                cells = {
                    k: _deploy_cell(c, pattern, a.work / f"{label}-{k}")
                    for k, c in checkouts.items()
                }
                print(
                    f"| {name} | {n}×{n} | {mode} | {design_rc} | {cells['branch'][0]} | "
                    + " | ".join(c[1] for c in cells.values())
                    + f" | {load0:.1f} / {os.getloadavg()[0]:.1f} |",
                    flush=True,
                )


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("patterns", nargs="*", type=Path, default=FIXTURES)
    ap.add_argument("--steps", type=int, default=40)
    ap.add_argument("--table", action="store_true", help="issue #37's deploy table (docstring)")
    ap.add_argument("--base", type=Path, help="--table: also deploy with this checkout")
    ap.add_argument("--work", type=Path, default=Path("deploy-table"), help="--table: designs here")
    ap.add_argument("--targets", help="--table: comma-separated names (bench/shapes.py's table)")
    ap.add_argument("--sizes", default="16,32", help="--table: comma-separated tiles per side")
    ap.add_argument("--modes", default="free,full", help="--table: free, full (comma-separated)")
    a = ap.parse_args()
    if a.table:
        return table(a)
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
