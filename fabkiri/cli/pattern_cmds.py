"""``fabkiri new | import | info | export``: making, importing and inspecting patterns."""

from __future__ import annotations

import argparse
import json
import re
import sys
from pathlib import Path

from .. import limits
from ..errors import CheckFailed, InputError
from ..fileio import atomic_write
from ..mechanics.contract import adopt_state_labels, contract, with_contracted_states
from ..mechanics.info import DEFAULT_TOL, DEFAULT_TOL_RAD, describe
from ..pattern.io import import_obj, obj_text, read_pattern, write_pattern
from ..pattern.model import Pattern
from ..pattern.periodic import standard_tube
from ..pattern.tessellation import kinds, tessellation
from .argtypes import bounded


def parse_tiles(text: str) -> tuple[int, int]:
    """``ROWSxCOLS`` -> (rows, cols), both >= 1."""
    m = re.fullmatch(r"\s*(\d+)\s*[xX×]\s*(\d+)\s*", text)
    if not m:
        raise InputError(f"--tiles expects ROWSxCOLS such as 8x8, got {text!r}")
    rows, cols = int(m.group(1)), int(m.group(2))
    if rows < 1 or cols < 1:
        raise InputError(f"--tiles needs at least one row and one column, got {rows}x{cols}")
    return rows, cols


def load_any(path: str) -> Pattern:
    """A pattern from ``pattern.json`` or, by suffix, a design ``.obj``."""
    if Path(path).suffix.lower() == ".obj":
        return adopt_state_labels(import_obj(path))
    return read_pattern(path)


def import_other(path: str, scale: float) -> Pattern | None:
    """A FOLD file (``.fold``) or a PyKirigami model folder; None for anything else."""
    p = Path(path)
    if p.suffix.lower() == ".fold":
        from ..pattern.fold import loads_fold
        from ..pattern.io import _read_text

        pat = loads_fold(_read_text(p), str(p))
        if scale != 1.0:
            pat = Pattern(nodes=pat.nodes * scale, tiles=pat.tiles,
                          contracted={k: v * scale for k, v in pat.contracted.items()}, name=pat.name,
                          design=pat.design)
        return adopt_state_labels(limits.check_pattern(pat, str(p)))
    if p.is_dir():
        from ..pattern.pykirigami import read_pykirigami

        return adopt_state_labels(limits.check_pattern(read_pykirigami(p, unit_mm=scale), str(p)))
    return None


_positive = bounded(float, lambda v: 0 < v < float("inf"), "expected a number",
                    "expected a positive finite number, got {text!r}")
_nonneg = bounded(float, lambda v: 0 <= v < float("inf"), "expected a number", "expected a finite number >= 0, got {text!r}")


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
    print(f"wrote {args.output}: standard {what}{rows}x{cols}, tile {args.tile_size:g} mm, "
          f"ψ = {pattern.lattice['angle_deg']:g}°, "
          f"{info.width_mm:.1f} x {info.height_mm:.1f} mm deployed", file=sys.stderr)
    return 0


def cmd_import(args: argparse.Namespace) -> int:
    pattern = None if args.contracted else import_other(args.design, args.scale)
    if pattern is None:
        pattern = adopt_state_labels(import_obj(args.design, args.contracted or [], scale=args.scale))
    info = describe(pattern)
    write_pattern(pattern, args.output)
    print(f"wrote {args.output}: {info.tiles} tiles, {info.holes} holes, "
          f"{len(pattern.contracted)} contracted state(s) stored", file=sys.stderr)
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
    if args.check and (not info.closes_both or not info.supplied_ok):
        print(f"fabkiri: check failed: {'; '.join(info.problems())}", file=sys.stderr)
        return 1
    return 0


def _fabricability(pattern: Pattern) -> dict:
    """The fabricability summary (fabricate.fabricability) for every material and printer preset."""
    from ..fabricate import fabricability as fb

    return fb.summary(pattern)


def _with_state(pattern: Pattern, s: int) -> Pattern:
    """The pattern with closed state ``s`` stored (contracted if missing; it must close)."""
    if s in pattern.contracted:
        return pattern
    c = contract(pattern, s)
    if c.max_closure > DEFAULT_TOL * pattern.tile_size:
        raise CheckFailed(
            f"state {s} does not close (loop closure {c.max_closure / pattern.tile_size:.3g} tile sizes "
            f"at hole {c.worst_hole}); nothing exported"
        )
    return pattern.with_contracted({**pattern.contracted, s: c.corners})


def cmd_export(args: argparse.Namespace) -> int:
    if args.format == "tube3d":
        from .tube_cmd import cmd_export_tube3d

        return cmd_export_tube3d(args)
    pattern = load_any(args.file)
    state = args.state
    fmt = args.format
    if state != "deployed" or fmt != "obj":  # closed states are what gets fabricated: the fabrication gate
        from ..fabricate.gate import (  # lazy: `design` imports this module
            claimed_states,
            closes_gate,
        )

        states = (1, 2) if fmt == "fold" else claimed_states(pattern, 1 if state == "deployed" else int(state))
        for w in closes_gate(pattern, None, force=args.force, action="export", states=states).warnings:
            print(f"warning: {w}", file=sys.stderr)
    if fmt == "fold":  # every state, one frame each
        from ..pattern.fold import fold_text

        pattern = _with_state(_with_state(pattern, 1), 2)
        atomic_write(args.output, fold_text(pattern))
        print(f"wrote {args.output}: FOLD 1.2, frames deployed / closed 1 / closed 2, {pattern.n_tiles} faces",
              file=sys.stderr)
        return 0
    if fmt == "pykirigami":  # start in a closed state, pulled to the deployed target
        from ..fileio import atomic_write_many
        from ..pattern.pykirigami import pykirigami_files

        s = 1 if state == "deployed" else int(state)
        pattern = _with_state(pattern, s)
        unit = args.unit or pattern.tile_size
        atomic_write_many(args.output, pykirigami_files(pattern, pattern.contracted[s], unit))
        print(f"wrote {args.output}/vertices.txt (closed state {s}), target.txt (deployed), constraints.txt "
              f"({pattern.topology.n_hinges} joints); 1 unit = {unit:.6g} mm", file=sys.stderr)
        return 0
    if state != "deployed":
        pattern = _with_state(pattern, int(state))
    atomic_write(args.output, obj_text(pattern, state))
    print(f"wrote {args.output}: state {state}, {pattern.n_tiles} faces", file=sys.stderr)
    return 0


def add_i_know(p: argparse.ArgumentParser) -> None:
    p.add_argument("--i-know", action="store_true",
                   help="try a lattice larger than the largest tested (the refusal says what it would need)")


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("new", help="write a standard pattern (rotating squares or kagome triangles) with both "
                                    "closed states")
    p.add_argument("--tiles", required=True, metavar="ROWSxCOLS",
                   help="lattice size, e.g. 8x8 (kagome: ROWS rows of COLS triangles)")
    p.add_argument("--lattice", choices=kinds(), default="quad",
                   help="tessellation: quad (rotating squares, default) or kagome (rotating triangles)")
    p.add_argument("--tile-size", type=_positive, default=10.0, metavar="MM", help="tile edge in mm (default 10)")
    p.add_argument("--angle", type=float, default=None, metavar="DEG",
                   help="deployment angle ψ in degrees: quad 0..90 (default 45: square holes), "
                        "kagome 0..120 (default 60: hexagonal holes)")
    p.add_argument("--name", help="pattern name stored in the file")
    p.add_argument("--tube", action="store_true",
                   help="a periodic tube of COLS columns around (even): the sheet's last column is the seam "
                        "copy of the first (docs/tubes.md)")
    add_i_know(p)
    p.add_argument("-o", "--output", required=True, metavar="FILE", help="pattern.json to write")
    p.set_defaults(func=cmd_new)

    p = sub.add_parser("import", help="import an OBJ design (and its contracted states), a .fold file or a "
                                       "PyKirigami model folder into pattern.json")
    p.add_argument("design", help="deployed design .obj, a .fold file or a PyKirigami folder")
    p.add_argument("--contracted", nargs="+", metavar="OBJ", help="contracted state files: state 1 [state 2]")
    p.add_argument("--scale", type=_positive, default=1.0, metavar="MM", help="millimetres per file unit (default 1)")
    p.add_argument("-o", "--output", required=True, metavar="FILE", help="pattern.json to write")
    p.set_defaults(func=cmd_import)

    p = sub.add_parser("info", help="counts, residuals and closure of a pattern (.json or .obj)")
    p.add_argument("file")
    p.add_argument("--json", action="store_true", help="machine-readable output")
    p.add_argument("--check", action="store_true", help="exit 1 unless the pattern closes in both states")
    p.add_argument("--tol", type=_positive, default=DEFAULT_TOL,
                   help=f"closure tolerance relative to the mean tile edge (default {DEFAULT_TOL:g})")
    p.add_argument("--tol-rad", type=_positive, default=DEFAULT_TOL_RAD,
                   help=f"angle tolerance in radians (default {DEFAULT_TOL_RAD:g})")
    p.set_defaults(func=cmd_info)

    p = sub.add_parser("export", help="write a pattern as OBJ (one state), FOLD (all states) or a PyKirigami folder")
    p.add_argument("file")
    p.add_argument("--state", choices=["deployed", "1", "2"], default="deployed",
                   help="obj: the state written; pykirigami: the closed start state (default 1)")
    p.add_argument("--format", choices=["obj", "fold", "pykirigami", "tube3d"], default="obj",
                   help="obj (default); fold: FOLD 1.2 JSON, frame 0 deployed, frames 1, 2 the closed states; "
                        "pykirigami: a model folder (vertices.txt, target.txt, constraints.txt) for its simulator; "
                        "tube3d: a folder with every state of a tube rolled into 3D (OBJ, thin-plate STL, PNG, GIF)")
    p.add_argument("--copies", type=int, default=1, metavar="K", help="tube3d: K copies around the circumference")
    p.add_argument("--thickness", type=_positive, default=1.0, metavar="MM", help="tube3d: plate thickness")
    p.add_argument("--no-gif", action="store_true", help="tube3d: skip the 3D deployment GIF")
    p.add_argument("--unit", type=_positive, metavar="MM",
                   help="pykirigami: mm per file unit (default: the mean tile edge, so tiles are about 1 unit)")
    p.add_argument("--force", action="store_true",
                   help="export a closed state even if the pattern does not close in both states")
    p.add_argument("-o", "--output", required=True, metavar="OUT", help="OUT.obj, OUT.fold or a folder (pykirigami)")
    p.set_defaults(func=cmd_export)
