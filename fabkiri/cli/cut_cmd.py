"""``fabkiri cut``: laser-cut files (DXF, SVG, PNG, manifest) from a pattern, verified before writing."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from ..api.cut import cut_files, cut_material, parse_sheet
from ..errors import InputError
from ..exchange.drawing import COLORS
from ..exchange.svg import STROKE_MM
from ..fabricate.cut.formats import sheet_format_names
from ..fabricate.cut.layout import LAYOUTS
from ..fabricate.cut.materials import HINGE_KINDS, available
from ..fabricate.cut.sheets import FORMATS, CutOptions
from ..fileio import atomic_write_many, left_over
from .argtypes import load_any, nonnegative_number, positive_number
from .asked import asked, options_on_stdout


def _formats(text: str) -> tuple[str, ...]:
    known = sheet_format_names()
    out = tuple(f.strip().lower() for f in text.split(",") if f.strip())
    bad = [f for f in out if f not in known]
    if bad or not out:
        raise InputError(f"--formats takes a comma list of {', '.join(known)}, got {text!r}")
    return tuple(f for f in known if f in out)


def _scale_or_auto(text: str):
    if text.strip().lower() == "auto":
        return "auto"
    try:
        return float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number or 'auto', got {text!r}") from None


# (dest, flag, default) of the options every suggested line keeps, and of those kept only for the
# material asked for (its field overrides)
CUT_FLAGS = (
    ("state", "--state", 1),
    ("sheet", "--sheet", "600x400"),
    ("margin", "--margin", 5.0),
    ("layout", "--layout", None),
    ("formats", "--formats", ",".join(FORMATS)),
    ("colors", "--colors", None),
    ("no_labels", "--no-labels", False),
    ("label_height", "--label-height", None),
    ("reference", "--reference", 50.0),
    ("no_notes", "--no-notes", False),
    ("stroke", "--stroke", STROKE_MM),
    ("exact", "--exact", False),
    ("force", "--force", False),
)
MATERIAL_FLAGS = tuple(
    (dest, f"--{dest.replace('_', '-')}", None)
    for dest in (
        "thickness", "kerf", "min_web", "min_hole", "strain_limit", "gap", "tol", "ligament_width",
    )
) + (("set", "--set", None),)  # fmt: skip


def cmd_cut(args: argparse.Namespace) -> int:
    pattern = load_any(args.file)
    material, hinge = cut_material(
        pattern,
        args.material,
        args.hinge,
        settings=args.set or [],
        changes=dict(
            thickness_mm=args.thickness,
            kerf_mm=args.kerf,
            min_web_mm=args.min_web,
            min_hole_mm=args.min_hole,
            strain_limit=args.strain_limit,
            gap_mm=args.gap,
            tolerance_mm=args.tol,
        ),
    )
    stem = Path(args.file).stem
    out = Path(args.output) if args.output else Path("outputs") / stem
    options = CutOptions(
        material=material,
        hinge=hinge,
        state=args.state,
        sheet=parse_sheet(args.sheet),
        margin=args.margin,
        layout=args.layout,
        scale=args.scale,
        width=args.width,
        formats=_formats(args.formats),
        colors=args.colors,
        labels=not args.no_labels,
        label_height=args.label_height,
        reference_mm=args.reference,
        ligament_width=args.ligament_width,
        force=args.force,
        stem=stem,
        pattern_file=Path(args.file).name,
        notes=not args.no_notes,
        stroke_mm=args.stroke,
        exact=args.exact,
    )
    ask = asked(args, CUT_FLAGS, MATERIAL_FLAGS, args.material)
    with options_on_stdout():
        cut = cut_files(pattern, options, use_verifier=not args.no_verify, ask=ask)
    rb, result = cut.readback, cut.result
    stale = left_over(out, cut.files)
    written = atomic_write_many(out, cut.files)
    if stale:
        print(
            f"note: {out} also holds {', '.join(stale)} of an earlier run, not of this one",
            file=sys.stderr,
        )
    for w in result.warnings:
        print(f"warning: {w}", file=sys.stderr)
    if not rb.ok:
        print(
            "warning: written with --force although the verifier failed (see manifest.json)",
            file=sys.stderr,
        )
    man = result.manifest
    total = sum(s["cut_length_mm"] for s in man["sheets"])
    secs = sum(s["cut_time_s"] for s in man["sheets"])
    print(
        f"wrote {len(written)} files to {out}: {len(man['sheets'])} sheet(s), {man['hinge']} hinges, "
        f"{material.name}, cut {total / 1000:.2f} m (~{secs / 60:.1f} min); "
        f"{len(rb.checks)} read-back checks passed"
        + ("" if args.no_verify or not rb.ok else ", verifier passed"),
        file=sys.stderr,
    )
    return 0


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "cut", help="laser-cut files (DXF, SVG, PNG, manifest) for a pattern's closed state"
    )
    p.add_argument("file", help="pattern.json (or a design .obj)")
    _add_sheet_args(p)
    _add_material_args(p)
    _add_tolerance_args(p)
    p.add_argument(
        "--set", action="append", metavar="FIELD=VALUE", help="override any material field"
    )
    _add_drawing_args(p)
    p.add_argument(
        "--force", action="store_true", help="cut even if the pattern does not close in both states"
    )
    p.add_argument("--no-verify", action="store_true", help=argparse.SUPPRESS)
    p.add_argument(
        "-o", "--output", metavar="DIR", help="output folder (default outputs/<pattern stem>)"
    )
    p.set_defaults(func=cmd_cut)


def _add_sheet_args(p: argparse.ArgumentParser) -> None:
    """Material, hinge, state, sheet, layout, size and output formats."""
    p.add_argument(
        "--material",
        metavar="NAME",
        help=f"preset ({', '.join(available())}) or a material .json (default: the one the design "
        "was made for, else acrylic-3)",
    )
    p.add_argument("--hinge", choices=HINGE_KINDS, help="hinge kind (default: the material's)")
    p.add_argument(
        "--state", type=int, choices=[1, 2], default=1, help="closed state to cut (default 1)"
    )
    p.add_argument(
        "--sheet", default="600x400", metavar="WxH", help="sheet size in mm (default 600x400)"
    )
    p.add_argument(
        "--margin",
        type=nonnegative_number,
        default=5.0,
        metavar="MM",
        help="sheet margin (default 5)",
    )
    p.add_argument(
        "--layout",
        choices=LAYOUTS,
        help="in-place (tape, ligament), exploded or nested (separate; default exploded)",
    )
    g = p.add_mutually_exclusive_group()
    g.add_argument(
        "--scale",
        type=_scale_or_auto,
        metavar="K|auto",
        help="mm in the file per mm of the pattern (auto: the smallest the material accepts)",
    )
    g.add_argument(
        "--width",
        type=_scale_or_auto,
        metavar="MM|auto",
        help="width of the cut (closed) pattern in mm (auto: the smallest the material accepts)",
    )
    p.add_argument(
        "--formats", default=",".join(FORMATS), metavar="LIST", help="dxf,svg,png (default all)"
    )
    p.add_argument(
        "--colors", choices=sorted(COLORS), help="colour preset (default: the material's)"
    )


def _add_material_args(p: argparse.ArgumentParser) -> None:
    """Material fields given one by one (they override the preset's)."""
    p.add_argument(
        "--kerf", type=float, metavar="MM", help="full kerf (Boxes.py's burn is half of it)"
    )
    p.add_argument("--thickness", type=float, metavar="MM")
    p.add_argument("--min-web", type=float, metavar="MM")
    p.add_argument("--min-hole", type=float, metavar="MM")
    p.add_argument("--strain-limit", type=float, metavar="EPS")
    p.add_argument("--gap", type=float, metavar="MM", help="gap between ligament-sheet tiles")
    p.add_argument(
        "--ligament-width", type=positive_number, metavar="MM", help="force the ligament width"
    )


def _add_tolerance_args(p: argparse.ArgumentParser) -> None:
    """The verification tolerance of the pattern and of the read-back."""
    p.add_argument(
        "--tol-mm",
        "--tol",
        dest="tol",
        type=positive_number,
        metavar="MM",
        help="verification tolerance in mm for the pattern and the read-back (default: the material's); "
        "angle residuals count as their displacement at the tile size",
    )
    p.add_argument(
        "--exact",
        action="store_true",
        help="check the pattern at the relative tier for solver output (1e-9 of the tile edge, 1e-5 "
        "for optimiser output) instead of --tol-mm; the read-back stays at --tol-mm",
    )


def _add_drawing_args(p: argparse.ArgumentParser) -> None:
    """What the sheets carry besides the cuts: labels, the reference square, notes, the SVG stroke."""
    p.add_argument(
        "--label-height",
        type=positive_number,
        metavar="MM",
        help="tile ID height (default: the material's)",
    )
    p.add_argument(
        "--no-labels", action="store_true", help="no tile IDs, face letters or tape marks"
    )
    p.add_argument(
        "--reference",
        type=nonnegative_number,
        default=50.0,
        metavar="MM",
        help="side of the uncompensated reference square (0: none; default 50)",
    )
    p.add_argument(
        "--no-notes",
        action="store_true",
        help="leave out the NOTES layer (sheet frame, caption, reference-square size) that some laser "
        "software would cut",
    )
    p.add_argument(
        "--stroke",
        type=positive_number,
        default=STROKE_MM,
        metavar="MM",
        help=f"SVG stroke width (default {STROKE_MM:g}: visible in viewers; the colour tells the laser "
        "what to do; 0.01 for software that wants hairlines)",
    )
