"""``fabkiri print``: 3D-printable hinges and tiles (STL, 3MF, optional STEP)."""

from __future__ import annotations

import argparse
import sys
import time
from dataclasses import replace
from pathlib import Path

from .. import limits
from ..errors import CheckFailed, FabricationError, InputError
from ..fabricate import fabricability as fb
from ..fabricate import mesh
from ..fabricate.gate import claimed_states, closes_gate
from ..fabricate.printers import available_printers, load_printer
from ..fileio import atomic_write_many
from .pattern_cmds import _positive, load_any


def _scale_auto(text: str):
    return "auto" if text.strip().lower() == "auto" else _positive(text)


def cmd_print(args: argparse.Namespace) -> int:
    t0 = time.perf_counter()
    pattern = load_any(args.file)
    from .cut_cmd import intent

    args.printer = args.printer or intent(pattern, "printer")
    args.style = args.style or intent(pattern, "style") or "tiles-and-strips"
    pinned = args.style == "pinned"  # pinned tiles have their own (thicker) preset thickness
    printer = load_printer(args.printer).with_overrides(
        tile_thickness_mm=None if pinned else args.tile_thickness,
        pin_tile_thickness_mm=args.tile_thickness if pinned else None,
        strip_thickness_mm=args.strip_thickness,
        strip_width_mm=args.strip_width, strip_reach_mm=args.strip_reach, gap_mm=args.gap,
        radial_clearance_mm=args.radial_clearance, axial_clearance_mm=args.axial_clearance,
    )
    if args.scale == "auto":  # the smallest scale the plan checks accept
        need = fb.print_minimum(pattern, args.style, printer, int(args.state))
        if not need.possible:
            raise CheckFailed(f"--scale auto: {args.style} on {printer.name}: {need.advice(printer.name)}")
        args.scale = need.min_scale
    limits.check_scale(pattern.nodes, pattern.tiles, args.scale, "--scale")
    if args.scale != 1.0:  # mm printed per mm of the pattern
        pattern = replace(pattern, nodes=pattern.nodes * args.scale,
                          contracted={k: v * args.scale for k, v in pattern.contracted.items()})
    for w in closes_gate(pattern, printer.tolerance_mm, force=args.force, action="print", tolerance="printer",
                         states=claimed_states(pattern, int(args.state))).warnings:  # as `cut`, printer tolerance
        print(f"warning: {w}", file=sys.stderr)
    job, plan = _build_job(pattern, args, printer)
    realised = mesh.realise_job(job)
    job = realised.job  # the bodies as realised (a pinned tile may have been rebuilt with turned pivot polygons)
    report = mesh.check_meshes(realised)
    tiles = None if job.style == "strips" else mesh.check_printed_tiles(realised)
    problems = list(report.problems)
    if tiles is not None and not tiles.ok:
        problems.append(
            f"printed tiles deviate {tiles.max_deviation_mm:.3g} mm from closed state {job.state} "
            f"(tolerance {tiles.tolerance_mm:g} mm), overlap {tiles.max_overlap_mm2:.3g} mm²"
        )
    verifier = _style_checks(pattern, realised, report, problems)
    if problems:
        raise CheckFailed("; ".join(problems) + "; nothing written")
    stem = Path(args.file).stem
    laser = {}
    if args.marks:
        laser = _laser_files(pattern, job, args, stem)
    files = mesh.job_files(realised, stem)
    if args.step:
        from ..fabricate import cad  # lazy: OpenCascade is heavy

        for k, bed in enumerate(job.beds, 1):  # one STEP per bed, like the meshes
            files[f"{stem}.step" if len(job.beds) == 1 else f"{stem}-bed{k}.step"] = cad.step_bytes(bed)
    read_back = mesh.read_back_files(files)  # watertight as written, not as held in memory
    bad = [f"{n} ({v['edges_not_shared_by_two_faces']} edges not shared by two faces)"
           for n, v in read_back.items() if not v["ok"]]
    if bad:
        raise CheckFailed("written meshes are not closed 2-manifolds when read back: " + ", ".join(bad)
                          + "; nothing written")
    files["manifest.json"] = mesh.manifest(realised, report, tiles, Path(args.file).name,
                                           list(files) + ["manifest.json"], verifier, read_back)
    from ..fabricate.assembly import add_to_print

    files["manifest.json"], extra = add_to_print(files["manifest.json"], pattern, realised, stem)
    files.update(extra)
    files.update(laser)
    atomic_write_many(args.output, files)
    faces = int(job.plan.top.sum())
    print(f"wrote {len(files)} files to {args.output}: {job.style} at --scale {args.scale:g}, closed state {job.state}, printer "
          f"{printer.name}, {len(job.plan.tiles)} tiles, {job.plan.n_hinges} hinges ({faces} top, "
          f"{job.plan.n_hinges - faces} bottom), {len(job.beds)} bed(s), min clearance "
          f"{'n/a' if report.min_clearance_mm is None else f'{report.min_clearance_mm:.3f} mm'}, {plan}, "
          f"{time.perf_counter() - t0:.1f} s", file=sys.stderr)
    return 0


def _build_job(pattern, args: argparse.Namespace, printer):
    """The print job and its plan; a refusal says at which scale it would print, if any."""
    try:
        job = mesh.build_job(pattern, args.style, int(args.state), printer, advise_scale=args.scale)
        plan = mesh.print_plan(job)  # refuses a print the printer cannot make
    except FabricationError as exc:  # say at which scale it would print, if any
        if args.style == "pinned":  # build_job named the scales that print pinned on this bed
            raise
        need = fb.print_minimum(pattern, args.style, printer, int(args.state))
        if need.min_scale is None or need.min_scale <= 1.0:
            raise
        k = args.scale
        at = need.advice(printer.name).replace(f"≥ {need.min_scale:g}", f"≥ {fb.ceil_sig(need.min_scale * k):g}")
        at = at.replace(f"--scale {need.max_scale:g}", f"--scale {fb.floor_sig(need.max_scale * k):g}") \
            if need.max_scale is not None else at
        raise type(exc)(f"{exc} (at --scale {k:g}); {at}") from None
    return job, plan


def _style_checks(pattern, realised, report, problems: list[str]):
    """The checks one print style adds (pinned: the sweep along the deployment
    path; tiles-and-strips: the layout verifier), appending to ``problems``;
    returns the verifier's report, if run."""
    job = realised.job
    verifier = None
    if job.style == "pinned":  # the printed tiles moved along the rigid deployment path
        sweep = mesh.sweep_pinned(pattern, realised)
        report.sweep = sweep.to_dict()
        if not sweep.ok:
            problems.append(f"pinned tiles collide while reconfiguring: {sweep.max_overlap_mm2:.3g} mm² overlap "
                            f"({sweep.worst})")
    if job.style == "tiles-and-strips":  # the layout verifier on the printed top faces
        verifier = mesh.verify_printed_tiles(pattern, realised)
        # (c) reassembles the other closed state: moot for a pattern that closes one way only
        moot = [] if job.plan.other_state_closes else [c.name for c in verifier.failed() if "(c)" in c.name]
        if moot:
            verifier.meta["not_applicable"] = moot
            print(f"note: closed state {3 - job.state} does not close; the verifier's reassembly checks are moot",
                  file=sys.stderr)
        problems += [f"verifier: {c.name} measured {c.value:.3g} {c.unit} (tolerance {c.tol:g})"
                     for c in verifier.failed() if c.name not in moot]
    return verifier


def _laser_files(pattern, job, args, stem: str) -> dict[str, bytes]:
    """Laser files of the tiles with the pads engraved (``laser/``), verified like ``fabkiri cut``."""
    from ..fabricate.marks import marked_cut
    from ..fabricate.materials import load_material
    from ..fabricate.readback import verify_result

    if job.style != "strips":
        raise InputError("--marks engraves strip pads on laser-cut tiles: it needs --style strips")
    res, n = marked_cut(pattern, job.state, job.strips, job.plan.corners, load_material(args.material), stem,
                        Path(args.file).name)
    rb = verify_result(pattern, res)
    res.manifest["verification"] = rb.to_dict()
    if not rb.ok:
        raise CheckFailed("laser files with pad marks failed their read-back checks: "
                          + "; ".join(f"{c.name} ({c.detail})" for c in rb.failed()[:4]) + "; nothing written")
    out = {f"laser/{k}": v for k, v in res.files.items()}
    out["laser/manifest.json"] = res.manifest_bytes()
    return out


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("print", help="3D-printable hinges/tiles of a closed state (STL, 3MF, STEP)")
    p.add_argument("file", help="pattern.json (or design .obj)")
    p.add_argument("--style", choices=mesh.STYLES,
                   help="strips: one flexible strip per hinge for laser-cut tiles; tiles-and-strips: rigid tiles "
                        "joined by flexible strips (two materials: recessed with two extruders, stacked with colour "
                        "changes on one; the default unless the design was made for another); pinned: "
                        "print-in-place pin hinges")
    p.add_argument("--state", choices=["1", "2"], default="1", help="closed state printed (default 1)")
    p.add_argument("--printer", metavar="NAME|FILE.json",
                   help=f"printer preset (default prusa-mk4; presets: {', '.join(available_printers())})")
    p.add_argument("--scale", type=_scale_auto, default=1.0, metavar="K|auto",
                   help="print the pattern K times its size (default 1; auto: the smallest the plan checks accept)")
    p.add_argument("--step", action="store_true", help="also write STEP (needs the 'cad' extra: build123d)")
    for flag, what in [("tile-thickness", "tile thickness"), ("strip-thickness", "strip thickness"),
                       ("strip-width", "strip width along the seam"), ("strip-reach", "strip reach into each tile"),
                       ("gap", "gap between printed tiles"), ("radial-clearance", "in-plane print clearance"),
                       ("axial-clearance", "clearance between stacked parts")]:
        p.add_argument(f"--{flag}", type=_positive, metavar="MM", help=f"override the preset's {what}")
    p.add_argument("--marks", action="store_true",
                   help="strips style: also write the laser files of the tiles (laser/, as 'fabkiri cut --hinge "
                        "tape') with every pad outline engraved where its strip is glued")
    p.add_argument("--material", default="acrylic-3", metavar="NAME|FILE.json",
                   help="laser material for --marks (default acrylic-3)")
    p.add_argument("--force", action="store_true",
                   help="print even if the pattern does not close in both states (as 'fabkiri cut --force')")
    p.add_argument("-o", "--output", required=True, metavar="DIR", help="output folder (created if missing)")
    p.set_defaults(func=cmd_print)
