"""``fabkiri print``: 3D-printable hinges and tiles (STL, 3MF, optional STEP)."""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

from ..api.print import PrintOptions, print_pattern
from ..errors import InputError
from ..fabricate.print import mesh
from ..fabricate.print.printers import available_printers
from ..fileio import atomic_write_many, left_over
from .argtypes import load_any, positive_number
from .asked import asked, options_on_stdout


def _scale_auto(text: str):
    return "auto" if text.strip().lower() == "auto" else positive_number(text)


# (dest, flag, default) of the options every suggested line keeps, and of the printer field overrides,
# kept only for the printer asked for
PRINT_FLAGS = (
    ("state", "--state", None),
    ("step", "--step", False),
    ("marks", "--marks", False),
    ("material", "--material", None),
    ("force", "--force", False),
)
PRINTER_FLAGS = tuple(
    (dest, f"--{dest.replace('_', '-')}", None)
    for dest in (
        "tile_thickness", "strip_thickness", "strip_width", "strip_reach", "gap",
        "radial_clearance", "axial_clearance",
    )
)  # fmt: skip


def cmd_print(args: argparse.Namespace) -> int:
    t0 = time.perf_counter()
    if (
        args.material is not None and not args.marks
    ):  # else read by nothing: a material asked for in vain
        raise InputError(
            "--material is the laser material of --marks; give --marks too, or drop it"
        )
    pattern = load_any(args.file)
    options = PrintOptions(
        style=args.style,
        state=int(args.state) if args.state else None,
        printer=args.printer,
        scale=args.scale,
        tile_thickness=args.tile_thickness,
        strip_thickness=args.strip_thickness,
        strip_width=args.strip_width,
        strip_reach=args.strip_reach,
        gap=args.gap,
        radial_clearance=args.radial_clearance,
        axial_clearance=args.axial_clearance,
        step=args.step,
        marks=args.marks,
        material=args.material or PrintOptions.material,
        force=args.force,
    )
    with options_on_stdout():
        out = print_pattern(
            pattern,
            options,
            stem=Path(args.file).stem,
            source=Path(args.file).name,
            notify=lambda text: print(text, file=sys.stderr),
            ask=asked(args, PRINT_FLAGS, PRINTER_FLAGS, args.printer),
        )
    stale = left_over(args.output, out.files)
    atomic_write_many(args.output, out.files)
    if stale:
        print(
            f"note: {args.output} also holds {', '.join(stale)} of an earlier run, not of this one",
            file=sys.stderr,
        )
    print(
        f"wrote {len(out.files)} files to {args.output}: {out.describe()}, {time.perf_counter() - t0:.1f} s",
        file=sys.stderr,
    )
    return 0


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("print", help="3D-printable hinges/tiles of a closed state (STL, 3MF, STEP)")
    p.add_argument("file", help="pattern.json (or design .obj)")
    p.add_argument(
        "--style",
        choices=mesh.STYLES,
        help="strips: one flexible strip per hinge for laser-cut tiles; tiles-and-strips: rigid tiles "
        "joined by flexible strips (two materials: recessed with two extruders, stacked with colour "
        "changes on one; the default unless the design was made for another); pinned: "
        "print-in-place pin hinges",
    )
    p.add_argument(
        "--state",
        choices=["1", "2"],
        default=None,
        help="closed state printed (default: the one the design was made for, else 1)",
    )
    p.add_argument(
        "--printer",
        metavar="NAME|FILE.json",
        help=f"printer preset (default prusa-mk4; presets: {', '.join(available_printers())})",
    )
    p.add_argument(
        "--scale",
        type=_scale_auto,
        default=1.0,
        metavar="K|auto",
        help="print the pattern K times its size (default 1; auto: the smallest the plan checks accept)",
    )
    p.add_argument(
        "--step", action="store_true", help="also write STEP (needs the 'cad' extra: build123d)"
    )
    for flag, what in [
        ("tile-thickness", "tile thickness"),
        ("strip-thickness", "strip thickness"),
        ("strip-width", "strip width along the seam"),
        ("strip-reach", "strip reach into each tile"),
        ("gap", "gap between printed tiles"),
        ("radial-clearance", "in-plane print clearance"),
        ("axial-clearance", "clearance between stacked parts"),
    ]:
        p.add_argument(
            f"--{flag}", type=positive_number, metavar="MM", help=f"override the preset's {what}"
        )
    p.add_argument(
        "--marks",
        action="store_true",
        help="strips style: also write the laser files of the tiles (laser/, as 'fabkiri cut --hinge "
        "tape') with every pad outline engraved where its strip is glued",
    )
    p.add_argument(
        "--material",
        default=None,
        metavar="NAME|FILE.json",
        help="laser material for --marks (default acrylic-3)",
    )
    p.add_argument(
        "--force",
        action="store_true",
        help="print even if the pattern does not close in both states (as 'fabkiri cut --force')",
    )
    p.add_argument(
        "-o", "--output", required=True, metavar="DIR", help="output folder (created if missing)"
    )
    p.set_defaults(func=cmd_print)
