"""``fabkiri tolerance``: Monte-Carlo of cut and hinge placement errors (JSON + histogram PNG)."""

from __future__ import annotations

import argparse
import json
import sys

from ..fileio import atomic_write_many
from ..pattern.fingerprint import KEY, fingerprint
from .argtypes import bounded, load_any, nonnegative_number, positive_number

_count = bounded(
    int,
    lambda v: 2 <= v <= 1_000_000,
    "expected a whole number",
    "samples must lie in 2..1000000, got {v}",
)


def cmd_tolerance(args: argparse.Namespace) -> int:
    from ..mechanics.tolerance import tolerance_analysis
    from ..render.tolerance import tolerance_png

    pattern = load_any(args.file)
    res = tolerance_analysis(
        pattern,
        kerf_sd=args.kerf_sd,
        hinge_sd=args.hinge_sd,
        n=args.n,
        seed=args.seed,
        scale=args.scale,
    )
    d = res.to_dict()
    d["pattern"] = pattern.name
    d[KEY] = fingerprint(pattern)
    files: dict[str, bytes | str] = {"tolerance.json": json.dumps(d, indent=2) + "\n"}
    if not args.no_plot:
        files["tolerance.png"] = tolerance_png(res, title=pattern.name)
    atomic_write_many(args.output, files)
    g, o = d["closure_gap_mm"], d["overlap_max_mm2"]
    print(
        f"{res.n} samples in {res.time_s:.1f} s (kerf sd {res.kerf_sd_mm:g} mm, hinge sd {res.hinge_sd_mm:g} mm, "
        f"tile {res.tile_size_mm:.3g} mm)",
        file=sys.stderr,
    )
    for s in ("closed state 1", "closed state 2"):
        print(
            f"{s}: hinge gap p50/p95 {g[s]['p50']:.3f}/{g[s]['p95']:.3f} mm, seam gap p95 "
            f"{d['seam_gap_mm'][s]['p95']:.3f} mm, largest overlap p95 {o[s]['p95']:.3f} mm²",
            file=sys.stderr,
        )
    ol = d["deployed_outline_mm"]
    print(
        f"deployed: hinge gap p95 {g['deployed']['p95']:.3f} mm, outline error p50/p95 {ol['p50']:.3f}/"
        f"{ol['p95']:.3f} mm",
        file=sys.stderr,
    )
    tiles = ", ".join(
        f"{t['tile']} (r = {t['correlation']:.2f})" for t in d["most_sensitive_tiles"]
    )
    print(f"most sensitive tiles: {tiles}", file=sys.stderr)
    print(f"wrote {args.output}: {', '.join(files)}", file=sys.stderr)
    return 0


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "tolerance", help="Monte-Carlo of cut and hinge errors: closure gaps, overlaps, outline"
    )
    p.add_argument("file", help="pattern (.json or design .obj)")
    p.add_argument(
        "--kerf-sd",
        type=nonnegative_number,
        default=0.02,
        metavar="MM",
        help="sd of each tile edge's position along its normal (default 0.02)",
    )
    p.add_argument(
        "--hinge-sd",
        type=nonnegative_number,
        default=0.05,
        metavar="MM",
        help="sd of each pivot's position off its tile corner, per axis (default 0.05)",
    )
    p.add_argument("--n", type=_count, default=1000, help="samples (default 1000)")
    p.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    p.add_argument(
        "--scale",
        type=positive_number,
        default=1.0,
        metavar="K",
        help="tiles cut K times the pattern's size",
    )
    p.add_argument("--no-plot", action="store_true", help="JSON only")
    p.add_argument(
        "-o", "--output", required=True, metavar="DIR", help="output folder (created if missing)"
    )
    p.set_defaults(func=cmd_tolerance)
