"""``print_pattern``: a pattern's 3D-print files, verified, as :class:`PrintOutcome`.

The bodies, meshes and files are made in :mod:`fabkiri.fabricate.print.mesh`; this front door holds
the policy ``fabkiri print`` applies around them: the defaults the design was made for, the
printer's overrides, ``scale="auto"``, the fabrication gate at the printer's tolerance, the
refusal that names the scale at which a design would print, the mesh and printed-tile checks,
each style's own checks (pinned: the sweep along the deployment path; tiles-and-strips: the
layout verifier on the printed top faces), the optional laser files and STEP, and the read-back
of every written mesh. A failed check raises :class:`~fabkiri.errors.CheckFailed` (nothing is
returned, so nothing can be written); bad input raises :class:`~fabkiri.errors.InputError`.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field, replace
from typing import Any

from .. import limits
from ..errors import CheckFailed, FabricationError, InputError, Param
from ..fabricate.gate import claimed_states, closes_gate
from ..fabricate.print import mesh
from ..fabricate.print.job import print_style
from ..fabricate.tube.sheet import tube_cut_inputs
from ..pattern.fingerprint import fingerprint
from ..pattern.model import Pattern
from ..verify.printmanifest import PrintManifest
from .advice import Ask, Refused, print_alternatives
from .intent import design_intent
from .print_options import DEFAULT_STYLE, PrintOptions, minimum, printer_for, refuse_unread

AUTO = Param("scale", "auto")  # first part of the refusal of --scale auto (no scale prints it)


@dataclass(frozen=True, eq=False)
class PrintOutcome:
    """A verified print: the files to write (names relative to the output folder) and its figures.

    ``realised`` is the job as realised (its beds, plan and printer), ``mesh_report`` the mesh
    checks (with the pinned sweep, if any), ``plan`` how it prints on ``printer``, ``verifier`` the layout verifier's report on the
    printed top faces (tiles-and-strips only) and ``messages`` the warnings and notes, in order.
    """

    files: dict[str, Any]
    realised: Any
    mesh_report: Any
    scale: float
    printer: Any
    plan: str
    verifier: Any = None
    messages: list[str] = field(default_factory=list)

    @property
    def job(self):
        return self.realised.job

    def __repr__(self) -> str:  # the files are bytes and meshes: named, not printed
        return f"PrintOutcome(scale {self.scale:g}, files {sorted(self.files)})"

    def describe(self, cli: bool = True) -> str:
        """One line: style, scale, state, printer, tiles, hinges (top/bottom faces), beds, clearance, plan;
        the scale as the command line names it (``--scale 2``) or, ``cli`` false, as Python does."""
        job, report = self.job, self.mesh_report
        faces = int(job.plan.top.sum())
        clearance = (
            "n/a" if report.min_clearance_mm is None else f"{report.min_clearance_mm:.3f} mm"
        )
        return (
            f"{job.style} at {Param('scale', self.scale, 'g').words(cli)}, closed state {job.state}, "
            f"printer {self.printer.name}, "
            f"{len(job.plan.tiles)} tiles, {job.plan.n_hinges} hinges ({faces} top, "
            f"{job.plan.n_hinges - faces} bottom), {len(job.beds)} bed(s), min clearance {clearance}, "
            f"{self.plan}"
        )


def print_pattern(
    pattern: Pattern,
    options: PrintOptions = PrintOptions(),
    *,
    stem: str = "pattern",
    source: str = "pattern.json",
    notify: Callable[[str], None] | None = None,
    ask: Ask | None = None,
) -> PrintOutcome:
    """Build, check and serialise the print of ``pattern``; ``stem`` names the files, ``source`` is
    the pattern file named in the manifests; ``notify`` receives each warning or note as it arises.
    A fabricability refusal (plan checks, bed) raises :class:`~fabkiri.api.advice.Refused` naming the
    options that pass (``ask``: how the command was given, so that each is a line that runs)."""
    messages: list[str] = []

    def say(text: str) -> None:
        messages.append(text)
        if notify is not None:
            notify(text)

    state = int(options.state or design_intent(pattern, "state") or 1)
    options = replace(options, state=state)
    style = options.style or design_intent(pattern, "style") or DEFAULT_STYLE
    refuse_unread(style, options)
    printer = printer_for(options.printer or design_intent(pattern, "printer"), style, options)
    made_from = fingerprint(pattern)  # before scaling: the manifest names the input pattern
    pattern, seam_files, seam_entry = tube_cut_inputs(pattern, state, "print")  # a tube: flat sheet
    base = pattern  # at scale 1: the refusal advice scales it itself
    memo: dict = {}  # base's plan checks, shared with the refusal advice
    pattern, scale = _refusal_advice(
        lambda: _scaled(base, style, printer, options, memo), base, options, ask, memo
    )
    # the gate verifies the pattern at its own size, the printer's tolerance divided by the scale (as
    # `cut`): its stored target is in that size's mm, so the outline's shape is measured where it fits
    for w in closes_gate(
        base,
        printer.tolerance_mm,
        scale=scale,
        force=options.force,
        action="print",
        tolerance="printer",
        states=claimed_states(pattern, state),
    ).warnings:  # as `cut`, printer tolerance
        say(f"warning: {w}")
    job, plan = _refusal_advice(
        lambda: _build_job(pattern, style, state, printer, scale, memo if pattern is base else {}),
        base,
        replace(options, scale=scale),
        ask,
        memo,
    )
    _shared_faces_note(job, style, say)
    realised = mesh.realise_job(job)  # a pinned tile may be rebuilt with turned pivot polygons
    report = mesh.check_meshes(realised)
    has_tiles = print_style(realised.job.style).tiles is not None
    tiles = mesh.check_printed_tiles(realised) if has_tiles else None
    problems = list(report.problems)
    if tiles is not None and not tiles.ok:
        problems.append(
            f"printed tiles deviate {tiles.max_deviation_mm:.3g} mm from closed state {realised.job.state} "
            f"(tolerance {tiles.tolerance_mm:g} mm), overlap {tiles.max_overlap_mm2:.3g} mm²"
        )
    verifier = _style_checks(pattern, realised, report, problems, say)
    if problems:
        raise CheckFailed("; ".join(problems) + "; nothing written")
    files = _files(pattern, realised, report, tiles, verifier, options, stem, source)
    _stamp(files, made_from, seam_entry, seam_files)
    return PrintOutcome(
        files=files,
        realised=realised,
        mesh_report=report,
        scale=scale,
        printer=printer,
        plan=plan,
        verifier=verifier,
        messages=messages,
    )


def _shared_faces_note(job, style: str, say: Callable[[str], None]) -> None:
    if (
        job.plan.shared_faces and print_style(style).strip_hinges
    ):  # three strips at a point (kagome): two faces cannot keep them all apart (pins stack instead)
        say(
            f"note: {job.plan.shared_faces} pair(s) of coincident hinges share a face (more meet at a point "
            "than two faces separate); their strips keep the clearance as printed"
        )


def _stamp(files: dict, made_from: dict, seam_entry, seam_files: dict) -> None:
    """Put the input pattern's fingerprint and, for a tube, its seam (the pairs of corners to join
    across it, as `cut` lists them) into the print's manifest."""
    stamped = PrintManifest.from_json(files["manifest.json"])
    stamped.pattern_fingerprint = made_from
    if seam_entry:
        stamped.extra["seam"] = seam_entry
        stamped.files = sorted(set(stamped.files) | set(seam_files))
        files.update(seam_files)
    files["manifest.json"] = stamped.to_json()


def _refusal_advice(
    step: Callable[[], Any], pattern: Pattern, o: PrintOptions, ask: Ask | None, memo: dict
):
    """``step()``; a fabricability refusal (a FabricationError, or ``--scale auto`` finding no scale) is
    raised again as :class:`Refused` with the checked options, exit 1 whatever the flags. ``pattern``
    is the pattern at scale 1, ``o.scale`` the scale asked for, ``memo`` its plan checks' answers."""
    try:
        return step()
    except (FabricationError, CheckFailed) as exc:
        if isinstance(exc, Refused) or (isinstance(exc, CheckFailed) and exc.parts[:1] != (AUTO,)):
            raise
        scale = None if o.scale == "auto" else float(o.scale)
        alternatives = print_alternatives(pattern, o, scale, ask=ask or Ask(), memo=memo)
        raise Refused(exc, alternatives) from None


def _scaled(
    pattern: Pattern, style: str, printer, o: PrintOptions, memo: dict
) -> tuple[Pattern, float]:
    """The pattern at the print's scale, and the scale (``"auto"``: the smallest the plan checks accept)."""
    given = o.scale
    if given == "auto":
        assert o.state is not None, "print_pattern resolves the state first"
        need = minimum(pattern, style, printer, o.state, memo)
        if not need.possible or need.min_scale is None:
            raise CheckFailed(
                AUTO, f": {style} on {printer.name}: ", *need.advice_parts(printer.name)
            )
        scale = need.min_scale
    elif isinstance(
        given, str
    ):  # a library caller's text: one line, not a TypeError deep in check_scale
        raise InputError(
            Param("scale"), f" must be a number (mm printed per mm) or auto, got {given!r}"
        )
    else:
        scale = given
    limits.check_scale(pattern.nodes, pattern.tiles, scale, Param("scale"))
    if scale != 1.0:  # mm printed per mm of the pattern
        pattern = replace(
            pattern,
            nodes=pattern.nodes * scale,
            contracted={k: v * scale for k, v in pattern.contracted.items()},
        )
    return pattern, scale


def _build_job(pattern: Pattern, style: str, state: int, printer, scale: float, memo: dict):
    """The print job and its plan; a refusal says at which scale it would print, if any (``memo``:
    ``pattern``'s plan checks' answers)."""
    try:
        job = mesh.build_job(pattern, style, int(state), printer, advise_scale=scale)
        plan = mesh.print_plan(job)  # refuses a print the printer cannot make
    except FabricationError as exc:  # say at which scale it would print, if any
        if (
            print_style(style).advise is not None
        ):  # build_job named the scales that print on this bed
            raise
        need = minimum(pattern, style, printer, state, memo)
        if need.min_scale is None or need.min_scale <= 1.0:
            raise
        # the scales it names are of this pattern, which is at `scale` already
        at = need.advice_parts(printer.name, scale)
        raise type(exc)(exc, " (at ", Param("scale", scale, "g"), "); ", *at) from None
    return job, plan


def _style_checks(
    pattern: Pattern, realised, report, problems: list[str], say: Callable[[str], None]
):
    """The checks the print style adds (``PrintStyle.checks``), appending to ``problems`` and saying
    its notes; returns the layout verifier's report, if the style ran it."""
    checks = print_style(realised.job.style).checks
    if checks is None:
        return None
    found = checks(pattern, realised, report)
    for note in found.notes:
        say(note)
    problems += found.problems
    return found.verifier


def _files(
    pattern: Pattern, realised, report, tiles, verifier, o: PrintOptions, stem: str, source: str
) -> dict[str, Any]:
    """Every file of the print: meshes (and 3MF), STEP, laser files, assembly map and the manifest,
    after the written meshes were read back as closed 2-manifolds."""
    job = realised.job
    laser = _laser_files(pattern, job, o.material, stem, source) if o.marks else {}
    files = mesh.job_files(realised, stem)
    if o.step:
        from ..fabricate.print import step as cad  # lazy: OpenCascade is heavy

        for k, bed in enumerate(job.beds, 1):  # one STEP per bed, like the meshes
            files[f"{stem}.step" if len(job.beds) == 1 else f"{stem}-bed{k}.step"] = cad.step_bytes(
                bed
            )
    read_back = mesh.read_back_files(files)  # watertight as written, not as held in memory
    bad = [
        f"{n} ({v['edges_not_shared_by_two_faces']} edges not shared by two faces)"
        for n, v in read_back.items()
        if not v["ok"]
    ]
    if bad:
        raise CheckFailed(
            "written meshes are not closed 2-manifolds when read back: "
            + ", ".join(bad)
            + "; nothing written"
        )
    manifest = mesh.manifest(
        realised, report, tiles, source, list(files) + ["manifest.json"], verifier, read_back
    )
    from ..fabricate.assembly import add_to_print

    manifest, extra = add_to_print(manifest, pattern, realised, stem)
    return {
        **files,
        "manifest.json": manifest,
        **extra,
        **laser,
    }  # in this order, as the CLI writes them


def _laser_files(pattern: Pattern, job, material: str, stem: str, source: str) -> dict[str, bytes]:
    """Laser files of the tiles with the pads engraved (``laser/``), verified like ``fabkiri cut``."""
    from ..fabricate.cut.materials import load_material
    from ..fabricate.cut.readback import verify_result
    from ..fabricate.print.marks import marked_cut

    res, n = marked_cut(
        pattern, job.state, job.strips, job.plan.corners, load_material(material), stem, source
    )
    rb = verify_result(pattern, res)
    res.manifest["verification"] = rb.to_dict()
    if not rb.ok:
        raise CheckFailed(
            "laser files with pad marks failed their read-back checks: "
            + "; ".join(f"{c.name} ({c.detail})" for c in rb.failed()[:4])
            + "; nothing written"
        )
    out = {f"laser/{k}": v for k, v in res.files.items()}
    out["laser/manifest.json"] = res.manifest_bytes()
    return out
