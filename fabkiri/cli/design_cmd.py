"""``fabkiri design``: inverse design of a reconfigurable quad kirigami pattern.

The policy (initial-guess retries, contraction into both closed states, closure
and overlap checks, outline fits, the shape verdict, fabricability) lives in
:func:`fabkiri.api.design_pattern`; this command parses the options, calls it,
writes ``pattern.json`` and its preview and prints the summary. A run that
misses its tolerance still writes its best iterate, marked
``design.report.status = "unconverged"`` and ``design.valid = false``, and exits 1.
"""

from __future__ import annotations

import argparse
import json
import math
import sys

import numpy as np

from ..api.design import (  # noqa: F401 (names tests and benches import from here)
    BIG_TILES,
    PatternRequest,
    design_pattern,
    overlapping_tiles,
)
from ..api.design_summary import preview_path
from ..api.designers import design_by_kind, design_kinds
from ..api.progress import ProgressLine, on_terminal
from ..design.core import conformance as conf
from ..design.core.stages import listening
from ..design.quad.initial import INITS
from ..errors import InputError
from ..fabricate.cut.materials import HINGE_KINDS
from ..fabricate.fabricability import PRINT_STYLES
from ..fileio import check_output_file
from ..pattern.kinds.tessellation import DEFAULT_KIND
from .argtypes import add_i_know, bounded, length_mm, parse_tiles


def cmd_design(args: argparse.Namespace) -> int:
    if args.tube:  # a periodic sheet: its own solver and checks (docs/tubes.md)
        from .tube_cmd import cmd_design_tube

        return cmd_design_tube(args)
    if args.closed:
        raise InputError("--closed applies to --tube designs only")
    tiles = None if args.tiles is None else parse_tiles(args.tiles)
    check_output_file(args.output)  # fail before a long solve, not after
    if not args.no_preview and args.lattice == DEFAULT_KIND:  # a quad design writes its preview too
        check_output_file(preview_path(args.output))
    request = PatternRequest(
        tiles=tiles,
        target=args.target,
        size=args.size,
        rigid=args.rigid,
        symmetry=args.symmetry,
        lattice_angle=args.lattice_angle,
        holes=args.holes,
        contracted_target=tuple(args.contracted_target or ()),
        init=args.init,
        solver=args.solver,
        fit=args.fit,
        tol=args.tol,
        shape_tol=args.shape_tol,
        material=args.material,
        hinge=args.hinge,
        printer=args.printer,
        style=args.style,
        min_feature=args.min_feature,
        min_hole=args.min_hole,
        min_opening=args.min_opening,
        name=args.name,
        i_know=args.i_know,
        verbose=args.verbose,
        kind=args.lattice,
        trim=args.trim,
    )
    notify, heard, done = _notes()
    with listening(heard):
        out = design_by_kind(request, notify=notify)
    done()
    out.write(args.output, preview=not args.no_preview)
    if args.json:
        print(json.dumps(_jsonable(out.report), indent=2, sort_keys=True))
    for line in out.summary(args.output):
        print(line, file=sys.stderr)
    return out.exit_code


def _notes():
    """design's notes on stderr as they are; on a terminal each with the time so far after it, a
    line with the ETA of a stage whose steps are known (the continuation's, the minimax steps') as
    each step ends, and the total at the end. The retries are decided as the design goes, so the
    ETA is the stage's, not the design's; the status is a line of its own because the solver's log
    also writes to stderr. Returns the notes' callback, the stages' listener and the end."""
    if not sys.stderr.isatty():
        return (lambda text: print(text, file=sys.stderr)), None, (lambda: None)
    status = ProgressLine("design", per_stage=True)
    show = on_terminal(sys.stderr, status, in_place=False)

    def heard(stage: str, fraction: float) -> None:
        text = status.line(stage, fraction)  # a stage's start only starts its clock
        if fraction > 0:
            print(text, file=sys.stderr, flush=True)

    return (lambda text: show("designing", None, text)), heard, (lambda: show("done", None, ""))


def _jsonable(v):
    from ..exchange.pattern_json import jsonable

    return jsonable(v)


_tol = bounded(
    float,
    lambda v: 0 < v < 1e-2,
    "expected a number",
    "tolerance must lie in (0, 1e-2), got {text!r}",
)
_fraction = bounded(
    float,
    lambda v: bool(np.isfinite(v) and 0 < v < 1),
    "expected a fraction",
    "--min-opening must lie in (0, 1), got {text!r}",
)


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "design", help="inverse design: a reconfigurable quad kirigami fitted to a target shape"
    )
    p.add_argument(
        "--tiles",
        metavar="ROWSxCOLS",
        help="lattice size, e.g. 16x16 (required for quads; kagome: R rows of C triangles, by default "
        "chosen so the lattice's aspect matches the target's)",
    )
    _add_target_args(p)
    _add_solver_args(p)
    _add_fabrication_args(p)
    _add_tolerance_args(p)
    p.add_argument(
        "--no-preview",
        action="store_true",
        help="do not write the preview PNG (tiles over the targets) beside the pattern",
    )
    p.add_argument("--name", help="pattern name stored in the file")
    p.add_argument("--json", action="store_true", help="print the solver report as JSON on stdout")
    p.add_argument(
        "-v", "--verbose", action="store_true", help="progress on stderr even for small solves"
    )
    add_i_know(p)
    p.add_argument("-o", "--output", required=True, metavar="FILE", help="pattern.json to write")
    p.set_defaults(func=cmd_design)


def _add_target_args(p: argparse.ArgumentParser) -> None:
    """The lattice and what it is fitted to: deployed target, tube, symmetry, hole shape, closed-state outlines."""
    p.add_argument(
        "--lattice",
        choices=design_kinds(),
        default="quad",
        help="quad (default) or kagome: the kagome design fits the deployed tips to the target "
        "(docs/kagome.md)",
    )
    p.add_argument(
        "--target",
        metavar="NAME|FILE",
        help="deployed target: a name from templates/targets (circle, ellipse, heart, ...) or a "
        ".csv/.json points file, or an .svg/.dxf drawing of one closed outline",
    )
    p.add_argument(
        "--size",
        type=length_mm,
        metavar="MM",
        help="target size: its larger dimension in mm (named targets default to 100)",
    )
    p.add_argument("--rigid", action="store_true", help="rigid-deployable: hinge angle sums = π")
    p.add_argument(
        "--tube",
        metavar="cylinder:CIRC,LENGTH|cone:R_BOTTOM,R_TOP,LENGTH",
        help="a reconfigurable tube of COLS columns around: the unrolled deployed target in mm; both "
        "closed states roll into cylinders (docs/tubes.md)",
    )
    p.add_argument(
        "--closed",
        choices=["cylinder", "cone"],
        default=None,
        help="with --tube cone:...: cone lets both closed states be cones too (a rigid tube whose seam "
        "turns alike in every state); default cylinder, the closed states' pure-translation seam",
    )
    p.add_argument(
        "--trim",
        action="store_true",
        help="kagome: cut the R x C lattice to the target (the tiles whose centres lie inside it) "
        "instead of bending the whole block onto it (docs/kagome.md)",
    )
    p.add_argument(
        "--symmetry",
        choices=["x", "y", "none"],
        help="reflection symmetry about the x axis (y -> -y) or the y axis (x -> -x); none: free "
        "(the default for quads; a kagome design otherwise takes every mirror its lattice and "
        "target share)",
    )
    p.add_argument(
        "--lattice-angle",
        type=bounded(float, math.isfinite, "expected degrees", "a finite angle, got {text!r}"),
        metavar="DEG",
        help="quad: lay the lattice at DEG degrees counter-clockwise (0: along the drawing's axes); "
        "default: the drawing's axes, then along the outline's mirror axis where that design fails and "
        "neither drawing axis is one",
    )
    p.add_argument(
        "--holes",
        choices=["rhombus", "parallelogram"],
        default=None,
        help="hole shape (parallelogram: one more degree of freedom per hole, implies hinge sums); "
        "default rhombus, but parallelogram for --rigid square/circle --contracted-target "
        "designs up to 11x11 tiles",
    )
    p.add_argument(
        "--contracted-target",
        action="append",
        metavar="STATE:NAME|FILE",
        help="outline of closed state 1 or 2: a target curve, 'rect' or 'rect=W/H' (repeatable)",
    )


def _add_solver_args(p: argparse.ArgumentParser) -> None:
    """The initial guess and the solver."""
    p.add_argument(
        "--init",
        choices=INITS,
        help="initial guess; by default conformal (harmonic map onto the target), then rescaled "
        "(standard pattern at the target's area), then standard, until a design passes every check "
        "(--rigid from 32x32 tiles: coarse, then rescaled; non-rigid from 16x16 tiles: the rigid "
        "family first, kept when it meets --shape-tol); coarse solves at half resolution "
        "first and maps that design onto the tiles",
    )
    p.add_argument(
        "--solver",
        choices=["auto", "reduced", "full"],
        default="auto",
        help="auto (default): with --rigid and rhombus holes (no --symmetry or --contracted-target) "
        "solve in the closed-form rigid family, and when that fit is least-squares also run the "
        "full solver (up to 16x16 tiles, or up to 32x32 when the fit misses by more than 0.25 %% "
        "of the target size) and keep the better; also the rigid family for --rigid square/circle "
        "--contracted-target outlines (square exact, circle of any size) and for non-rigid rhombus "
        "designs from 32x32 tiles; reduced: the rigid family only; full: the sparse solver over "
        "all nodes",
    )


def _add_fabrication_args(p: argparse.ArgumentParser) -> None:
    """The fabrication group: inequality rows for a material, printer or minimum sizes."""
    g = p.add_argument_group(
        "fabrication (inequality rows at the target's --size; stored for cut and print)"
    )
    g.add_argument(
        "--material",
        metavar="NAME|FILE.json",
        help="laser material preset: every tile at least its minimum web wide at its thinnest (shrunk by "
        "gap/2 for ligaments), hinges its allowance apart",
    )
    g.add_argument("--hinge", choices=HINGE_KINDS, help="hinge kind (default: the material's)")
    g.add_argument(
        "--printer",
        metavar="NAME|FILE.json",
        help="printer preset: tiles two nozzles wide once shrunk by gap/2, hinge corners wide enough for "
        "a strip pad (or pivots far enough apart for pins)",
    )
    g.add_argument("--style", choices=PRINT_STYLES, help="print style (default tiles-and-strips)")
    g.add_argument(
        "--min-feature",
        type=length_mm,
        metavar="MM",
        help="every tile at least this wide at its thinnest",
    )
    g.add_argument(
        "--min-hole", type=length_mm, metavar="MM", help="every deployed hole at least this wide"
    )
    g.add_argument(
        "--min-opening",
        type=_fraction,
        metavar="F",
        help="the deployed holes at least this fraction of the deployed sheet's area (e.g. 0.3; "
        "the 'opening' figure design and info report)",
    )


def _add_tolerance_args(p: argparse.ArgumentParser) -> None:
    """The equality tolerance, the shape tolerance and what is fitted."""
    p.add_argument(
        "--tol", type=_tol, default=1e-10, help="max equality residual relative to the tile size"
    )
    p.add_argument(
        "--shape-tol",
        default=conf.DEFAULT_SHAPE_TOL,
        metavar="TOL",
        help="largest Hausdorff distance between each outline and its target: a percentage of the "
        "target size (larger side of its bounding box) like 2%% (default), or a length like "
        "0.5mm; a design that misses it is still written, marked shape: missed, and exits 1",
    )
    p.add_argument(
        "--fit",
        choices=["outline", "tips"],
        default="outline",
        help="outline (default): fit the whole tip polygon — tips on their arcs, chord midpoints and "
        "samples of the target (its corners and cusps included) to the other curve; tips: only the "
        "boundary tips on their arcs (tips may bunch and cut corners)",
    )
