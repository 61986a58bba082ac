"""``fabkiri new | import | info | export``: making, importing and inspecting patterns."""

from __future__ import annotations

import argparse
import json
import sys

from .. import limits
from ..api.patterns import export_pattern, import_pattern
from ..errors import CheckFailed, InputError
from ..exchange.file_formats import format_names
from ..exchange.pattern_json import write_pattern
from ..fileio import atomic_write, atomic_write_many
from ..mechanics.contract import with_contracted_states
from ..mechanics.info import DEFAULT_TOL, DEFAULT_TOL_RAD, describe
from ..pattern.kinds.periodic.sheet import standard_tube
from ..pattern.kinds.tessellation import kinds, tessellation
from ..pattern.model import Pattern
from ..pattern.opening import Opening
from .argtypes import add_i_know, load_any, parse_tiles, positive_number
from .tube_cmd import cmd_export_tube3d


def cmd_new(args: argparse.Namespace) -> int:
    rows, cols = parse_tiles(args.tiles)
    limits.check_tiles(rows, cols + bool(args.tube), "new", args.i_know)
    limits.check_length(args.tile_size, "--tile-size")
    if args.tube and args.lattice != "quad":
        raise InputError(f"--tube makes quad tubes only, not {args.lattice} ones")
    angle = {} if args.angle is None else {"angle_deg": args.angle}  # None: the kind's open state
    # a tube's sheet has one seam copy column more
    make = standard_tube if args.tube else tessellation(args.lattice).standard
    pattern = make(rows, cols, tile_size=args.tile_size, name=args.name or "", **angle)
    pattern = with_contracted_states(pattern)
    info = describe(pattern)
    if not info.closes_both:  # cannot happen for the standard lattice; never write a wrong file
        raise CheckFailed("; ".join(info.problems()))
    write_pattern(pattern, args.output)
    assert pattern.lattice is not None  # every standard generator records its lattice (and angle)
    what = "tube " if args.tube else ("" if args.lattice == "quad" else f"{args.lattice} ")
    print(
        f"wrote {args.output}: standard {what}{rows}x{cols}, tile {args.tile_size:g} mm, "
        f"ψ = {pattern.lattice['angle_deg']:g}°, "
        f"{info.width_mm:.1f} x {info.height_mm:.1f} mm deployed",
        file=sys.stderr,
    )
    return 0


def cmd_import(args: argparse.Namespace) -> int:
    pattern = import_pattern(args.design, args.contracted or [], scale=args.scale)
    info = describe(pattern)
    write_pattern(pattern, args.output)
    print(
        f"wrote {args.output}: {info.tiles} tiles, {info.holes} holes, "
        f"{len(pattern.contracted)} contracted state(s) stored",
        file=sys.stderr,
    )
    if up := ((pattern.design or {}).get("source") or {}).get("up_axis"):
        print(f"note: every y is 0: read as a Y-up export, up axis {up}", file=sys.stderr)
    for problem in info.problems():
        print(f"note: {problem}", file=sys.stderr)
    return 0


def cmd_info(args: argparse.Namespace) -> int:
    pattern = load_any(args.file)
    info = describe(pattern, tol=args.tol, tol_rad=args.tol_rad)
    # cut and print make quad patterns only (fabricate/gate.py): no fabricability for other kinds
    fabric = _fabricability(pattern) if info.closes_both and pattern.kind == "quad" else None
    if args.json:
        print(json.dumps({**info.to_dict(), "fabricability": fabric}, indent=2))
    else:
        print(info.to_text())
        if fabric:
            from ..fabricate.fabricability import summary_lines

            print("\n".join(summary_lines(fabric)))
    warn = Opening.from_dict(info.opening).warning() if info.opening else None
    if warn:
        print(warn, file=sys.stderr)
    if args.check and (not info.closes_both or not info.supplied_ok):
        print(f"fabkiri: check failed: {'; '.join(info.problems())}", file=sys.stderr)
        return 1
    return 0


def _fabricability(pattern: Pattern) -> dict:
    """The fabricability summary (fabricate.fabricability) for every material and printer preset."""
    from ..fabricate import fabricability as fb

    return fb.summary(pattern)


def cmd_export(args: argparse.Namespace) -> int:
    if args.format == "tube3d":  # a tube's rolled states: not a pattern format (cli/tube_cmd.py)
        return cmd_export_tube3d(args)
    given = [
        f for f, v in (("--copies", args.copies), ("--thickness", args.thickness)) if v is not None
    ]
    if given or args.no_gif:  # else read by nothing
        raise InputError(f"{(given + ['--no-gif'])[0]} is for --format tube3d, not {args.format}")
    out = export_pattern(
        load_any(args.file),
        args.format,
        args.state,
        unit=args.unit,
        force=args.force,
        output=args.output,
        notify=lambda text: print(text, file=sys.stderr),
    )
    if out.files is not None:
        atomic_write_many(args.output, out.files)
    elif out.text is not None:  # an export is one file or a folder
        atomic_write(args.output, out.text)
    print(out.said, file=sys.stderr)
    return 0


def register(sub: argparse._SubParsersAction) -> None:
    _register_new(sub)
    _register_import(sub)
    _register_info(sub)
    _register_export(sub)


def _register_new(sub: argparse._SubParsersAction) -> None:
    """``new``: a standard pattern."""
    p = sub.add_parser(
        "new",
        help="write a standard pattern (rotating squares or kagome triangles) with both "
        "closed states",
    )
    p.add_argument(
        "--tiles",
        required=True,
        metavar="ROWSxCOLS",
        help="lattice size, e.g. 8x8 (kagome: ROWS rows of COLS triangles)",
    )
    p.add_argument(
        "--lattice",
        choices=kinds(),
        default="quad",
        help="tessellation: quad (rotating squares, default) or kagome (rotating triangles)",
    )
    p.add_argument(
        "--tile-size",
        type=positive_number,
        default=10.0,
        metavar="MM",
        help="tile edge in mm (default 10)",
    )
    p.add_argument(
        "--angle",
        type=float,
        default=None,
        metavar="DEG",
        help="deployment angle ψ in degrees: quad 0..90 (default 45: square holes), "
        "kagome 0..120 (default 60: hexagonal holes)",
    )
    p.add_argument("--name", help="pattern name stored in the file")
    p.add_argument(
        "--tube",
        action="store_true",
        help="a periodic tube of COLS columns around (even): the sheet's last column is the seam "
        "copy of the first (docs/tubes.md)",
    )
    add_i_know(p)
    p.add_argument("-o", "--output", required=True, metavar="FILE", help="pattern.json to write")
    p.set_defaults(func=cmd_new)


def _register_import(sub: argparse._SubParsersAction) -> None:
    """``import``: an OBJ, FOLD or PyKirigami design into pattern.json."""
    p = sub.add_parser(
        "import",
        help="import an OBJ design (and its contracted states), a .fold file or a "
        "PyKirigami model folder into pattern.json",
    )
    p.add_argument("design", help="deployed design .obj, a .fold file or a PyKirigami folder")
    p.add_argument(
        "--contracted", nargs="+", metavar="OBJ", help="contracted state files: state 1 [state 2]"
    )
    p.add_argument(
        "--scale",
        type=positive_number,
        default=1.0,
        metavar="MM",
        help="millimetres per file unit (default 1)",
    )
    p.add_argument("-o", "--output", required=True, metavar="FILE", help="pattern.json to write")
    p.set_defaults(func=cmd_import)


def _register_info(sub: argparse._SubParsersAction) -> None:
    """``info``: counts, residuals and closure of a pattern."""
    p = sub.add_parser("info", help="counts, residuals and closure of a pattern (.json or .obj)")
    p.add_argument("file")
    p.add_argument("--json", action="store_true", help="machine-readable output")
    p.add_argument(
        "--check", action="store_true", help="exit 1 unless the pattern closes in both states"
    )
    p.add_argument(
        "--tol",
        type=positive_number,
        default=DEFAULT_TOL,
        help=f"closure tolerance relative to the mean tile edge (default {DEFAULT_TOL:g})",
    )
    p.add_argument(
        "--tol-rad",
        type=positive_number,
        default=DEFAULT_TOL_RAD,
        help=f"angle tolerance in radians (default {DEFAULT_TOL_RAD:g})",
    )
    p.set_defaults(func=cmd_info)


def _register_export(sub: argparse._SubParsersAction) -> None:
    """``export``: a pattern to OBJ, FOLD, PyKirigami or tube3d."""
    p = sub.add_parser(
        "export",
        help="write a pattern as OBJ (one state), FOLD (all states) or a PyKirigami folder",
    )
    p.add_argument("file")
    p.add_argument(
        "--state",
        choices=["deployed", "1", "2"],
        default="deployed",
        help="obj: the state written; pykirigami: the closed start state (default 1)",
    )
    p.add_argument(
        "--format",
        choices=[*format_names(writable=True), "tube3d"],
        default="obj",
        help="obj (default); fold: FOLD 1.2 JSON, frame 0 deployed, frames 1, 2 the closed states; "
        "pykirigami: a model folder (vertices.txt, target.txt, constraints.txt) for its simulator; "
        "tube3d: a folder with every state of a tube rolled into 3D (OBJ, thin-plate STL, PNG, GIF)",
    )
    p.add_argument(
        "--copies",
        type=int,
        metavar="K",
        help="tube3d: K copies around the circumference (default 1)",
    )
    p.add_argument(
        "--thickness",
        type=positive_number,
        metavar="MM",
        help="tube3d: plate thickness (default 1)",
    )
    p.add_argument("--no-gif", action="store_true", help="tube3d: skip the 3D deployment GIF")
    p.add_argument(
        "--unit",
        type=positive_number,
        metavar="MM",
        help="pykirigami: mm per file unit (default: the mean tile edge, so tiles are about 1 unit)",
    )
    p.add_argument(
        "--force",
        action="store_true",
        help="export a closed state even if the pattern does not close in both states",
    )
    p.add_argument(
        "-o",
        "--output",
        required=True,
        metavar="OUT",
        help="OUT.obj, OUT.fold or a folder (pykirigami)",
    )
    p.set_defaults(func=cmd_export)
