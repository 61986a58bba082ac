"""``fabkiri report``: one self-contained HTML page (design, states, files made from it)."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from ..api.report_folders import check_report_folders
from ..errors import InputError
from ..fileio import atomic_write
from .argtypes import load_any


def cmd_report(args: argparse.Namespace) -> int:
    from ..mechanics.contract import contract_both
    from ..render.report import SECTIONS, build_report

    out = Path(args.output)
    if out.suffix.lower() not in (".html", ".htm"):
        raise InputError(f"-o {out}: the report is an .html file")
    if out.resolve() == Path(args.file).resolve():
        raise InputError(f"-o {out} would overwrite the input")
    pattern = load_any(args.file)
    check_report_folders(
        pattern,
        {
            "--cut": args.cut,
            "--print": args.print_dir,
            "--deploy": args.deploy,
            "--tolerance": args.tolerance,
        },
    )
    both = contract_both(pattern)
    closes = all(c.max_closure <= 1e-9 * pattern.tile_size for c in both.values())
    states = {s: pattern.contracted.get(s, c.corners) for s, c in both.items()} if closes else None
    page = build_report(
        pattern,
        source=Path(args.file).name,
        cut=args.cut,
        printed=args.print_dir,
        deploy=args.deploy,
        tolerance=args.tolerance,
        states=states,
    )
    atomic_write(out, page)
    given = [
        n
        for n, v in (
            ("cut", args.cut),
            ("print", args.print_dir),
            ("deploy", args.deploy),
            ("tolerance", args.tolerance),
        )
        if v
    ]
    print(
        f"wrote {out}: {len(page) / 1e6:.2f} MB, {len(SECTIONS)} sections"
        f"{' with ' + ', '.join(given) if given else ''}",
        file=sys.stderr,
    )
    return 0


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "report",
        help="one self-contained HTML page: design vs target, states, deployment, "
        "cut and print files, assembly, bill of materials",
    )
    p.add_argument("file", help="pattern (.json or design .obj)")
    p.add_argument("--cut", metavar="DIR", help="a fabkiri cut output folder")
    p.add_argument("--print", dest="print_dir", metavar="DIR", help="a fabkiri print output folder")
    p.add_argument("--deploy", metavar="DIR", help="a fabkiri deploy output folder (--plot --gif)")
    p.add_argument("--tolerance", metavar="DIR", help="a fabkiri tolerance output folder")
    p.add_argument("-o", "--output", required=True, metavar="REPORT.html")
    p.set_defaults(func=cmd_report)
