"""``fabkiri coupon``: calibration test pieces for a laser material or a printer preset."""

from __future__ import annotations

import argparse
import json
import sys

from ..errors import CheckFailed, InputError
from ..fileio import atomic_write_many


def cmd_coupon(args: argparse.Namespace) -> int:
    from ..fabricate import coupon

    if (args.material is None) == (args.printer is None):
        raise InputError("give --material NAME (laser coupon) or --printer NAME (print coupon)")
    if args.notes and args.printer is not None:  # else read by nothing
        raise InputError(
            "--notes is the laser coupon's NOTES layer; a --printer coupon has none: drop it"
        )
    if args.material is not None:
        from ..fabricate.cut.materials import load_material

        c = coupon.laser_coupon(load_material(args.material), notes=args.notes)
    else:
        from ..fabricate.print.printers import load_printer

        c = coupon.printer_coupon(load_printer(args.printer))
        bad = [
            k
            for k, v in c.info["checks"].items()
            if not (v["watertight"] and v["winding_consistent"])
        ]
        bad += [k for k, v in c.info["intersection_mm3"].items() if v > 1e-6]
        if bad:
            raise CheckFailed(
                f"coupon meshes failed their checks ({', '.join(bad)}); nothing written"
            )
    doc = {
        "format": "fabkiri.coupon",
        "version": 1,
        "units": "mm",
        **c.info,
        "instructions": c.instructions,
    }
    files: dict[str, bytes | str] = dict(c.files)
    files["coupon.json"] = json.dumps(doc, indent=2) + "\n"
    atomic_write_many(args.output, files)
    what = (
        f"sheet {c.info['sheet_mm'][0]:g} x {c.info['sheet_mm'][1]:g} mm"
        if "sheet_mm" in c.info
        else f"{c.info['size_mm'][0]:.0f} x {c.info['size_mm'][1]:.0f} x {c.info['size_mm'][2]:.0f} mm"
    )
    print(f"wrote {args.output}: {', '.join(sorted(files))} ({what})", file=sys.stderr)
    for row in c.instructions:
        print(f"- {row['feature']}: {row['measure']} -> {row['sets']}", file=sys.stderr)
    return 0


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "coupon", help="calibration coupon: laser (--material) or print (--printer) test pieces"
    )
    g = p.add_mutually_exclusive_group(required=True)
    g.add_argument(
        "--material",
        metavar="NAME|FILE.json",
        help="laser coupon for a material preset (DXF, SVG, PNG)",
    )
    g.add_argument(
        "--printer", metavar="NAME|FILE.json", help="print coupon for a printer preset (3MF, STL)"
    )
    p.add_argument(
        "--notes", action="store_true", help="laser: add the sheet frame on the NOTES layer"
    )
    p.add_argument(
        "-o", "--output", required=True, metavar="DIR", help="output folder (created if missing)"
    )
    p.set_defaults(func=cmd_coupon)
