"""Tube options of ``fabkiri design --tube`` and ``fabkiri export --format tube3d`` (docs/tubes.md).

Parsing and printing only: the policy is in :mod:`fabkiri.api.tube`.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from ..api.patterns import load_pattern
from ..errors import InputError
from ..fileio import atomic_write, atomic_write_many, check_output_file, check_output_folder
from .argtypes import parse_tiles

# design options a tube design does not use, with their defaults
NOT_FOR_TUBES = dict.fromkeys(
    "target size trim symmetry lattice_angle holes contracted_target init material hinge printer "
    "style min_feature min_hole min_opening json".split()
) | {"lattice": "quad", "solver": "auto", "shape_tol": "2%", "fit": "outline"}


def options_not_for_tubes(args: argparse.Namespace) -> list[str]:
    """The design options given away from their defaults that a tube design does not use."""
    return [k for k, v in NOT_FOR_TUBES.items() if getattr(args, k) not in (v, None, False)]


def cmd_design_tube(args: argparse.Namespace) -> int:
    """``design --tube SPEC --tiles ROWSxCOLS``: write the tube's sheet; exit 1 unless it converged and
    verified (the best iterate is still written, marked ``design.valid = false``)."""
    from ..api.tube import design_tube_pattern
    from ..errors import InputError

    if args.tiles is None:
        raise InputError("--tube designs need --tiles ROWSxCOLS")
    unused = options_not_for_tubes(args)
    if unused:  # they were silently ignored: a tube's sheet is set by --tube alone
        raise InputError(f"--{unused[0].replace('_', '-')} does not apply to --tube designs")
    rows, cols = parse_tiles(args.tiles)
    check_output_file(args.output)
    out = design_tube_pattern(
        (rows, cols),
        args.tube,
        rigid=args.rigid,
        tol=args.tol,
        name=args.name or "",
        closed=args.closed or "cylinder",
        i_know=args.i_know,
    )
    atomic_write(args.output, out.text())
    print(f"wrote {args.output}: tube {rows}x{cols}", file=sys.stderr)
    print("\n".join(out.summary()))
    return out.exit_code


def cmd_export_tube3d(args: argparse.Namespace) -> int:
    """``export FILE --format tube3d -o DIR``: every state rolled onto its tube (OBJ, STL, PNG, GIF)."""
    from ..api.tube import tube_3d_files

    if args.unit is not None or args.state != "deployed":  # else read by nothing
        flag = "--unit" if args.unit is not None else "--state"
        raise InputError(f"{flag} is read by nothing: tube3d writes every state, in mm")
    check_output_folder(args.output)
    pattern = load_pattern(args.file)
    files = tube_3d_files(
        pattern,
        stem=Path(args.file).stem,
        copies=1 if args.copies is None else args.copies,
        thickness=1.0 if args.thickness is None else args.thickness,
        gif=not args.no_gif,
    )
    atomic_write_many(args.output, files)
    print(f"wrote {args.output}/: {', '.join(sorted(files))}", file=sys.stderr)
    return 0
