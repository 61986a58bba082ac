"""``fabkiri verify FILE [--layout CUT]``: geometric proof of both compact states.

Exit 0 when every check passes, 1 when any fails (failing checks listed
first), 2 on bad input.
"""

from __future__ import annotations

import argparse
import re
import sys
from pathlib import Path

from ..api.verification import DEFAULT_TOL_MM, verify_files
from ..exchange.obj import import_obj
from ..exchange.pattern_json import read_pattern
from ..mechanics.contract import adopt_state_labels
from ..pattern.model import Pattern
from .argtypes import bounded


def load_for_verify(path: str) -> Pattern:
    """pattern.json, or a design ``.obj``; ``X_design.obj`` picks up ``X_contracted1/2.obj``
    (or ``X_contracted.obj``) beside it as stored closed states."""
    p = Path(path)
    if p.suffix.lower() != ".obj":
        return read_pattern(p)
    contracted: list[Path] = []
    m = re.fullmatch(r"(.*)_design", p.stem)
    if m:
        stem = m.group(1)
        pair = [p.with_name(f"{stem}_contracted{i}.obj") for i in (1, 2)]
        single = p.with_name(f"{stem}_contracted.obj")
        if pair[0].exists():
            contracted = [q for q in pair if q.exists()]
        elif single.exists():
            contracted = [single]
    return adopt_state_labels(import_obj(p, contracted))


_nonneg = bounded(
    float,
    lambda v: 0 < v < float("inf"),
    "expected a number",
    "expected a positive finite number, got {text!r}",
)


def cmd_verify(args: argparse.Namespace) -> int:
    pattern = load_for_verify(args.file)
    tol_mm = DEFAULT_TOL_MM if args.tol_mm is None else args.tol_mm
    report = verify_files(
        pattern,
        args.layout,
        tol_mm=tol_mm,
        exact=args.exact,
        tol_rad=args.tol_rad,
        shape_tol=args.shape_tol,
    )
    if args.json:
        print(report.to_json())
    else:
        print(report.to_text())
    if not report.ok:
        names = ", ".join(c.name for c in report.failed()[:5])
        more = "" if len(report.failed()) <= 5 else f" and {len(report.failed()) - 5} more"
        print(f"fabkiri: verification failed: {names}{more}", file=sys.stderr)
        return 1
    return 0


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "verify", help="prove that a pattern (and its cut layout) closes into both compact states"
    )
    p.add_argument(
        "file",
        help="pattern.json or design .obj (X_design.obj takes X_contracted1/2.obj beside it)",
    )
    p.add_argument(
        "--layout", metavar="CUT", help="cut file (.dxf or .svg) to check against the pattern"
    )
    g = p.add_mutually_exclusive_group()
    g.add_argument(
        "--tol-mm",
        type=_nonneg,
        default=None,
        metavar="MM",
        help=f"fabrication tolerance in mm for the pattern and layout checks (default {DEFAULT_TOL_MM:g}, "
        "the default material's); angle residuals count as their displacement at the tile size",
    )
    g.add_argument(
        "--exact",
        action="store_true",
        help="pattern checks at the relative tier for exported data and solver output (1e-9 of the mean "
        "tile edge, 1e-5 for optimiser output; angles in rad); layout checks keep --tol-mm",
    )
    p.add_argument(
        "--tol-rad",
        type=_nonneg,
        default=1e-6,
        metavar="RAD",
        help="angle tolerance in radians with --exact (default 1e-6)",
    )
    p.add_argument(
        "--shape-tol",
        default="2%",
        metavar="TOL",
        help="largest Hausdorff distance between an outline and its stored target: a percentage of "
        "the target size (default 2%%) or a length like 0.5mm",
    )
    p.add_argument("--json", action="store_true", help="print the report as JSON")
    p.set_defaults(func=cmd_verify)
