"""``fabkiri deploy``: the deployment path, its energy landscape, plot, animation and frames."""

from __future__ import annotations

import argparse
import sys

from ..api.deploy import deploy_pattern, overlap_depth
from ..errors import CheckFailed
from ..fileio import atomic_write_many
from ..mechanics.drivers.registry import AUTO, driver_names
from ..mechanics.tube import path_lines
from .argtypes import bounded, load_any


def cmd_deploy(args: argparse.Namespace) -> int:
    pattern = load_any(args.file)
    out = deploy_pattern(
        pattern,
        args.steps,
        path=args.path,
        driver=args.driver,
        plot=args.plot,
        gif=args.gif,
        color=args.color,
        gif_frames=args.gif_frames,
        frames=not args.no_frames,
    )
    path, summary, files = out.path, out.summary, out.files
    atomic_write_many(args.output, files)

    e = path.energy
    marks = summary["energy_at_states"]
    kind = "rigid path" if path.kind == "rigid" else f"elastic path (driver: {path.driver})"
    print(
        f"{kind}, {path.n_frames} frames: max E = {e.max():.3e} at t = {summary['t_at_energy_max']:.3f}; "
        f"E at closed 1 / deployed / closed 2 = {marks['closed state 1']:.1e} / {marks['deployed']:.1e} / "
        f"{marks['closed state 2']:.1e}",
        file=sys.stderr,
    )
    print(
        f"tile rotation from state 1: 0 -> {path.rotation_magnitude[-1]:.6f} rad, spread up to "
        f"{path.rotation_spread.max():.2e} rad",
        file=sys.stderr,
    )
    if "tube" in summary:
        for line in path_lines(summary["tube"]):
            print(line, file=sys.stderr)
    for problem in out.problems:
        if "misses" in problem:
            print(f"warning: {problem} (try more --steps or the default driver)", file=sys.stderr)
    c = path.collisions
    if c.self_intersecting:
        print(
            f"warning: self-intersecting tiles {c.self_intersecting}; without them the path is "
            f"{'collision-free' if c.collision_free(c.self_intersecting) else 'NOT collision-free'}",
            file=sys.stderr,
        )
    if c.collision_free():
        print("collisions: none", file=sys.stderr)
    else:
        worst = sorted(c.overlaps, key=lambda o: -o.area)[:4]
        sizes = ", ".join(
            f"tiles {o.tile_a}/{o.tile_b} {o.area:.3g} mm² ({overlap_depth(path, o):.3g} mm deep) "
            f"at t = {path.t[o.frame]:.3f}"
            for o in worst
        )
        print(
            f"collisions: {len(c.overlaps)} overlaps in {len(c.frames)} frames, {len(c.pairs())} tile pairs, "
            f"largest {sizes}",
            file=sys.stderr,
        )
    n_frames = out.n_frame_files
    print(
        f"wrote {args.output}: {', '.join(k for k in files if not k.startswith('frames/'))}"
        f"{f', frames/ ({n_frames} patterns)' if n_frames else ''}",
        file=sys.stderr,
    )
    if out.problems:  # the figures are written either way; a failed check is never exit 0
        raise CheckFailed("; ".join(out.problems))
    return 0


_steps = bounded(
    int,
    lambda v: 2 <= v <= 10000,
    "expected a whole number of steps",
    "steps must lie in 2..10000, got {v}",
)


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "deploy", help="deployment path from closed state 1 to closed state 2: energy, plot, GIF"
    )
    p.add_argument("file", help="pattern (.json or design .obj)")
    p.add_argument(
        "--steps",
        type=_steps,
        default=40,
        metavar="N",
        help="path steps (rounded up to even so the deployed state is a frame; the elastic path "
        "adds frames inside its two end segments; default 40)",
    )
    p.add_argument(
        "--path",
        choices=["auto", "rigid", "elastic"],
        default="auto",
        help="auto (default): the exact rigid path if the pattern is rigid-deployable, else elastic",
    )
    p.add_argument(
        "--driver",
        choices=(AUTO, *driver_names()),
        default=AUTO,
        help="what the elastic path prescribes (auto, the default: the pattern kind's driver, "
        "rotations for quads, homotopy for kagome): rotations follows the quad design's "
        "zero-energy mechanism until it must leave it, tips moves the boundary tips linearly, "
        "homotopy interpolates every tile's rotation and centre between the states",
    )
    p.add_argument(
        "--plot", action="store_true", help="write energy.png, E(t) with the states marked"
    )
    p.add_argument("--gif", action="store_true", help="write deploy.gif, the animated motion")
    p.add_argument(
        "--color",
        choices=["auto", "energy", "rotation"],
        default="auto",
        help="GIF tile colours (auto: rotation for a rigid path, energy otherwise)",
    )
    p.add_argument(
        "--gif-frames", type=_steps, default=61, metavar="K", help="most GIF frames (default 61)"
    )
    p.add_argument(
        "--no-frames", action="store_true", help="do not write the frames as pattern files"
    )
    p.add_argument(
        "--check",
        action="store_true",
        help="kept for old scripts: deploy always exits 1 if a tile collides, the path misses a "
        "state, or a rigid path has energy (the files are written first)",
    )
    p.add_argument(
        "-o", "--output", required=True, metavar="DIR", help="output folder (created if missing)"
    )
    p.set_defaults(func=cmd_deploy)
