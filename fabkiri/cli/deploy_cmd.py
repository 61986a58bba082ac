"""``fabkiri deploy``: the deployment path, its energy landscape, plot, animation and frames."""

from __future__ import annotations

import argparse
import json
import sys

from ..errors import CheckFailed
from ..fileio import atomic_write_many
from ..mechanics.deploy import DRIVERS, DeploymentPath, deployment_path
from ..pattern.io import dumps
from ..pattern.model import Pattern
from .pattern_cmds import load_any

ZERO_ENERGY = 1e-12


def energy_csv(path: DeploymentPath) -> str:
    """One row per frame: t, E, the largest tile energy and the other per-frame figures."""
    rows = ["t,energy,max_tile_energy,rotation_rad,rotation_spread_rad,hinge_gap_mm,overlaps"]
    per_frame = [0] * path.n_frames
    for o in path.collisions.overlaps:
        per_frame[o.frame] += 1
    rot, spread = path.rotation_magnitude, path.rotation_spread
    for f in range(path.n_frames):
        rows.append(
            f"{path.t[f]:.10f},{path.energy[f]:.6e},{path.max_tile_energy[f]:.6e},{rot[f]:.12f},"
            f"{spread[f]:.3e},{path.hinge_gap[f]:.3e},{per_frame[f]}"
        )
    return "\n".join(rows) + "\n"


def frame_patterns(pattern: Pattern, path: DeploymentPath) -> dict[str, str]:
    """``frames/frame-NNNN.json``: each frame as a pattern whose deployed state is that frame."""
    out = {}
    width = max(4, len(str(path.n_frames - 1)))
    base = pattern.name or "pattern"
    for f in range(path.n_frames):
        frame = Pattern(
            nodes=path.nodes[f],
            tiles=pattern.tiles,
            parity=pattern.parity,
            name=f"{base} deployment frame {f} (t = {path.t[f]:.4f})",
            lattice=pattern.lattice,
            design={"deployment": {"source": base, "path": path.kind, "driver": path.driver, "frame": f,
                                   "t": float(path.t[f]), "energy": float(path.energy[f])}},
        )
        out[f"frames/frame-{f:0{width}d}.json"] = dumps(frame)
    return out


def check_problems(path: DeploymentPath, tol: float = 1e-9) -> list[str]:
    """What ``--check`` fails on, one sentence each."""
    out = []
    size = path.tile_size
    for name, d in path.state_mismatch.items():
        if d > tol * size * max(1.0, path.corners.shape[1] ** 0.5):
            out.append(f"the path misses the {name} by {d:.3g} mm")
    if path.kind == "rigid" and path.energy.max() > ZERO_ENERGY:
        out.append(f"the rigid path has energy {path.energy.max():.3g} > {ZERO_ENERGY:g}")
    c = path.collisions
    if not c.collision_free():
        o = max(c.overlaps, key=lambda o: o.area)
        out.append(f"{len(c.overlaps)} tile overlaps in {len(c.frames)} frames, the largest {o.area:.3g} mm² "
                   f"({overlap_depth(path, o):.3g} mm deep) between tiles {o.tile_a} and {o.tile_b} "
                   f"at t = {path.t[o.frame]:.3f}")
    return out


def overlap_depth(path: DeploymentPath, o) -> float:
    """How far (mm) the two tiles of an overlap reach into each other: the separating-axis depth."""
    from ..verify.geom import sat_penetration

    frame = path.corners[o.frame]
    return float(sat_penetration(frame[[o.tile_a]], frame[[o.tile_b]])[0])


def cmd_deploy(args: argparse.Namespace) -> int:
    pattern = load_any(args.file)
    path = deployment_path(pattern, args.steps, path=args.path, driver=args.driver)
    summary = path.summary()
    files: dict[str, bytes | str] = {
        "energy.csv": energy_csv(path),
        "deploy.json": json.dumps(summary, indent=2, sort_keys=True) + "\n",
    }
    title = pattern.name
    if args.plot:
        from ..render.deployment import energy_plot_png

        files["energy.png"] = energy_plot_png(path, title=title)
    if args.gif:
        from ..render.deployment import deployment_gif

        files["deploy.gif"] = deployment_gif(path, color=args.color, max_frames=args.gif_frames)
    if not args.no_frames:
        files.update(frame_patterns(pattern, path))
    atomic_write_many(args.output, files)

    e = path.energy
    marks = summary["energy_at_states"]
    kind = "rigid path" if path.kind == "rigid" else f"elastic path (driver: {path.driver})"
    print(f"{kind}, {path.n_frames} frames: max E = {e.max():.3e} at t = {summary['t_at_energy_max']:.3f}; "
          f"E at closed 1 / deployed / closed 2 = {marks['closed state 1']:.1e} / {marks['deployed']:.1e} / "
          f"{marks['closed state 2']:.1e}", file=sys.stderr)
    print(f"tile rotation from state 1: 0 -> {path.rotation_magnitude[-1]:.6f} rad, spread up to "
          f"{path.rotation_spread.max():.2e} rad", file=sys.stderr)
    for problem in check_problems(path):
        if "misses" in problem:
            print(f"warning: {problem} (try more --steps or the default driver)", file=sys.stderr)
    c = path.collisions
    if c.self_intersecting:
        print(f"warning: self-intersecting tiles {c.self_intersecting}; without them the path is "
              f"{'collision-free' if c.collision_free(c.self_intersecting) else 'NOT collision-free'}",
              file=sys.stderr)
    if c.collision_free():
        print("collisions: none", file=sys.stderr)
    else:
        worst = sorted(c.overlaps, key=lambda o: -o.area)[:4]
        sizes = ", ".join(f"tiles {o.tile_a}/{o.tile_b} {o.area:.3g} mm² ({overlap_depth(path, o):.3g} mm deep) "
                          f"at t = {path.t[o.frame]:.3f}" for o in worst)
        print(f"collisions: {len(c.overlaps)} overlaps in {len(c.frames)} frames, {len(c.pairs())} tile pairs, "
              f"largest {sizes}", file=sys.stderr)
    n_frames = 0 if args.no_frames else path.n_frames
    print(f"wrote {args.output}: {', '.join(k for k in files if not k.startswith('frames/'))}"
          f"{f', frames/ ({n_frames} patterns)' if n_frames else ''}", file=sys.stderr)
    problems = check_problems(path)
    if problems:  # the figures are written either way; a failed check is never exit 0
        raise CheckFailed("; ".join(problems))
    return 0


def _steps(text: str) -> int:
    try:
        v = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a whole number of steps, got {text!r}") from None
    if v < 2 or v > 10000:
        raise argparse.ArgumentTypeError(f"steps must lie in 2..10000, got {v}")
    return v


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("deploy", help="deployment path from closed state 1 to closed state 2: energy, plot, GIF")
    p.add_argument("file", help="pattern (.json or design .obj)")
    p.add_argument("--steps", type=_steps, default=40, metavar="N",
                   help="path steps (rounded up to even so the deployed state is a frame; the elastic path "
                        "adds frames inside its two end segments; default 40)")
    p.add_argument("--path", choices=["auto", "rigid", "elastic"], default="auto",
                   help="auto (default): the exact rigid path if the pattern is rigid-deployable, else elastic")
    p.add_argument("--driver", choices=DRIVERS, default="rotations",
                   help="what the elastic path prescribes: every tile's rotation, following the design's "
                        "zero-energy mechanism until it must leave it (default), or the boundary tips moved linearly")
    p.add_argument("--plot", action="store_true", help="write energy.png, E(t) with the states marked")
    p.add_argument("--gif", action="store_true", help="write deploy.gif, the animated motion")
    p.add_argument("--color", choices=["auto", "energy", "rotation"], default="auto",
                   help="GIF tile colours (auto: rotation for a rigid path, energy otherwise)")
    p.add_argument("--gif-frames", type=_steps, default=61, metavar="K", help="most GIF frames (default 61)")
    p.add_argument("--no-frames", action="store_true", help="do not write the frames as pattern files")
    p.add_argument("--check", action="store_true",
                   help="kept for old scripts: deploy always exits 1 if a tile collides, the path misses a "
                        "state, or a rigid path has energy (the files are written first)")
    p.add_argument("-o", "--output", required=True, metavar="DIR", help="output folder (created if missing)")
    p.set_defaults(func=cmd_deploy)
