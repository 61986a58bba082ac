"""``fabkiri make``: design, cut or print, deploy and report in one go (:func:`fabkiri.api.maker.make`)."""

from __future__ import annotations

import argparse
import sys

from ..api.maker import MAKE_STEPS, make
from ..api.progress import ProgressLine, on_terminal
from ..design.core import conformance as conf
from ..fabricate.cut.materials import HINGE_KINDS
from ..fabricate.fabricability import PRINT_STYLES
from .argtypes import length_mm, parse_tiles


def _progress():
    """make's lines on stderr as they are; on a terminal with a status line (step, elapsed, ETA)
    under them, so piped output stays the same bytes. Returns the callback and how to end it."""
    if not sys.stderr.isatty():
        return (lambda text: print(text, file=sys.stderr)), (lambda: None)
    show = on_terminal(sys.stderr, ProgressLine("make", len(MAKE_STEPS)))
    return show, (lambda: show("", None, ""))


def cmd_make(args: argparse.Namespace) -> int:
    progress, done = _progress()
    result = make(
        args.target,
        args.size,
        material=args.material,
        hinge=args.hinge,
        printer=args.printer,
        style=args.style,
        tiles=parse_tiles(args.tiles) if args.tiles else None,
        shape_tol=args.shape_tol,
        min_opening=args.min_opening,
        output=args.output,
        progress=progress,
    )
    done()
    for line in result.summary():
        print(line, file=sys.stderr)
    for line in result.option_lines():  # as cut and print give them: one runnable line each
        print(line)
    return result.exit_code


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "make",
        help="from a target outline to cut or print files in one go: design for the process, "
        "cut or print at the size, deploy, report",
    )
    p.add_argument(
        "target",
        help="a named target (circle, star, ...) or a .csv/.json points file, or an .svg/.dxf drawing of one closed outline",
    )
    p.add_argument(
        "--size", required=True, type=length_mm, metavar="MM", help="the target's larger dimension"
    )
    how = p.add_mutually_exclusive_group(required=True)
    how.add_argument("--material", metavar="NAME|FILE.json", help="laser-cut from this material")
    how.add_argument("--printer", metavar="NAME|FILE.json", help="3D print on this printer")
    p.add_argument("--hinge", choices=HINGE_KINDS, help="with --material: the hinge kind")
    p.add_argument("--style", choices=PRINT_STYLES, help="with --printer: the print style")
    p.add_argument(
        "--tiles",
        metavar="ROWSxCOLS",
        help="lattice size (default: the most tiles that stay comfortably wider than the process's "
        "thinnest feature at --size; the summary says which and why)",
    )
    p.add_argument(
        "--shape-tol",
        default=conf.DEFAULT_SHAPE_TOL,
        metavar="TOL",
        help="largest Hausdorff distance to the target, as for design (default 2%%)",
    )
    p.add_argument(
        "--min-opening",
        type=float,
        metavar="F",
        help="a floor on the deployed hole fraction (0 < F < 1), as for design: a design that opens "
        "at least this much",
    )
    p.add_argument(
        "-o", "--output", required=True, metavar="DIR", help="output folder (created if missing)"
    )
    p.set_defaults(func=cmd_make)
