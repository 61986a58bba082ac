"""Front doors for tubes: design a tube's sheet, and write its states in 3D.

:func:`design_tube_pattern` solves (:mod:`fabkiri.design.tube.solve`), contracts both closed states,
verifies the sheet (planar checks and seam checks) and reports each state's tube. A design whose
equalities stop above the tolerance, or that fails a check, is still returned (and written) with
``design.valid = false``, its figures, and exit code 1.

:func:`tube_3d_files` rolls every state onto its tube: OBJ surfaces, thin-plate STL, one PNG of all
states, and optionally a deployment GIF in 3D; ``copies`` assembles ``k`` copies around.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

from .. import limits
from ..design.tube.periodic import TWO_PI, TubeTarget, parse_tube_target
from ..design.tube.solve import TubeRequest, TubeResult, design_tube
from ..errors import CheckFailed, InputError
from ..exchange.pattern_json import dumps
from ..mechanics.contract import contract
from ..mechanics.tube import tube_lines, tube_report
from ..pattern.kinds.periodic.sheet import seam_of
from ..pattern.model import Pattern
from ..verify.pattern_checks import verify_pattern
from ..verify.report import Report

CLOSE_TOL = 1e-9  # loop closure a closed state must meet to be stored, in tile sizes (as ``info``)
PLATE_OVERLAP = (
    1e-9  # largest intersection of two rolled plates, share of a plate (touching: ~1e-15)
)


@dataclass
class TubeOutcome:
    """A designed tube: the sheet (closed states stored when they close), its checks and its tube."""

    pattern: Pattern
    result: TubeResult
    verification: Report | None
    tube: dict | None
    problems: list[str] = field(default_factory=list)

    @property
    def valid(self) -> bool:
        return self.result.converged and not self.problems

    @property
    def exit_code(self) -> int:
        return 0 if self.valid else 1

    @property
    def max_equality_residual(self) -> float:
        """The largest equality residual the solver ended at (the tube report's ``equality_max``)."""
        return self.result.max_equality_residual

    def summary(self, path=None) -> list[str]:
        """The figures, the tube and the problems; with ``path``, the first line names the file written."""
        r = self.result.report
        lines = [
            ("" if path is None else f"wrote {path}: ")
            + f"{r['status']}: max equality residual {self.max_equality_residual:.2e} (tol {r['tol']:g}), "
            f"{r['continuation_steps']} continuation step(s), ends fitted to {r['fit_max_mm']:.3g} mm, "
            f"{r['cpu_s']:.2f} s CPU / {r['wall_s']:.2f} s wall"
        ]
        if self.tube:
            lines += tube_lines(self.tube)
        lines += [f"problem: {p}" for p in self.problems]
        return lines

    def text(self) -> str:
        return dumps(self.pattern)


def design_tube_pattern(
    tiles: tuple[int, int],
    spec: str,
    *,
    rigid: bool = False,
    tol: float = 1e-10,
    name: str = "",
    closed: str = "cylinder",
    i_know: bool = False,
) -> TubeOutcome:
    """Design, contract, verify and report a tube of ``tiles = (rows, cols around)`` for target ``spec``
    (``cylinder:CIRC,LENGTH`` or ``cone:R_BOTTOM,R_TOP,LENGTH``, mm). Refuses sizes past
    :data:`~fabkiri.limits.MAX_LENGTH_MM` and tile counts past the largest measured (unless ``i_know``)."""
    target = parse_tube_target(spec)
    for label, mm in tube_sizes(target).items():
        limits.check_length(mm, f"--tube {target.kind} {label}")
    limits.check_tiles(tiles[0], tiles[1], "design tube", i_know)
    req = TubeRequest(tiles[0], tiles[1], target, rigid=rigid, tol=tol, name=name, closed=closed)
    res = design_tube(req)
    pattern = res.pattern
    problems: list[str] = []
    if not res.converged:
        problems.append(
            f"the solver stopped at max equality residual {res.max_equality_residual:.3g} "
            f"(tol {tol:g}) after {res.report['continuation_steps']} continuation step(s)"
        )
        if (
            req.target.kind == "cone" and closed == "cylinder"
        ):  # the measured lock, not a tuning problem (docs/tubes.md)
            problems.append(
                "a deployed cone between two cylindrical closed states: reconfigurable tubes are "
                "locally rigid-deployable and keep the seam's rotation in every state (docs/tubes.md); "
                "--closed cone lets the closed states be cones too"
            )
    states = {}  # `closed` names the closed states' shape
    for s in (1, 2):
        c = contract(pattern, s)
        if c.max_closure <= CLOSE_TOL * pattern.tile_size:
            states[s] = c.corners
        else:
            problems.append(
                f"state {s} does not close: loop closure {c.max_closure / pattern.tile_size:.3g} "
                f"tile sizes at hole {c.worst_hole}"
            )
    pattern = pattern.with_contracted(states)
    verification = tube = None
    if len(states) == 2:
        verification = verify_pattern(pattern, rigid=res.report["rigid"])
        problems += [
            f"{c.name}: {c.value:.3g} {c.unit} (tol {c.tol:g})" for c in verification.failed()
        ]
        tube = tube_report(pattern)
    valid = res.converged and not problems
    design = {**(pattern.design or {}), "valid": valid, "tube": tube}
    pattern = replace(pattern, design=design)
    return TubeOutcome(pattern, res, verification, tube, problems)


def tube_sizes(target: TubeTarget) -> dict[str, float]:
    """The sizes the user gave (mm), by name: a cylinder's circumference and length, a cone's radii
    and length."""
    if target.kind == "cylinder":
        return {"circumference": TWO_PI * target.r_bottom, "length": target.length}
    return {"R_BOTTOM": target.r_bottom, "R_TOP": target.r_top, "length": target.length}


def tube_3d_files(
    pattern: Pattern,
    *,
    stem: str = "tube",
    copies: int = 1,
    thickness: float = 1.0,
    gif: bool = True,
) -> dict[str, bytes]:
    """OBJ and thin-plate STL of every state rolled onto its tube, a PNG of them, and a 3D deployment GIF.

    The pattern must be a tube that closes in both states with pure-translation seams; otherwise
    :class:`CheckFailed` names what fails and nothing is produced.
    """
    from ..fabricate.tube.rolled import (
        obj_bytes,
        plate_meshes,
        plate_overlap,
        state_frame,
        stl_bytes,
        surface_mesh,
    )
    from ..render.tube import deployment_gif_3d, states_png

    if seam_of(pattern) is None:
        raise InputError(
            "the pattern has no seam: it is a flat sheet, not a tube (make one with --tube)"
        )
    rep = verify_pattern(pattern, rigid=False)
    seam_fail = [c for c in rep.failed() if "seam" in c.name or "loop closure" in c.name]
    if seam_fail:
        raise CheckFailed(
            "not a closed tube: " + "; ".join(f"{c.name} {c.value:.3g} {c.unit}" for c in seam_fail)
        )
    limits.check_copies(len(pattern.tiles), copies)  # (a whole number >= 1: state_frame says)
    closed = {s: pattern.contracted.get(s, contract(pattern, s).corners) for s in (1, 2)}
    pattern = pattern.with_contracted(closed)
    files: dict[str, bytes] = {}
    for s in ("deployed", 1, 2):
        tiles, f = state_frame(pattern, s, copies)
        label = "deployed" if s == "deployed" else f"closed{s}"
        plates = plate_meshes(tiles, f, thickness)
        worst, pair = plate_overlap(plates)
        if (
            worst > PLATE_OVERLAP and pair is not None
        ):  # e.g. plates thicker than the tube is wide: nothing is written
            raise CheckFailed(
                f"{label}: plates {pair[0]} and {pair[1]} overlap in 3D by {worst:.3g} of a plate's "
                f"volume (tolerance {PLATE_OVERLAP:g}); try a thinner --thickness"
            )
        files[f"{stem}_{label}.obj"] = obj_bytes(surface_mesh(tiles, f))
        files[f"{stem}_{label}.stl"] = stl_bytes(plates)
    files[f"{stem}_states.png"] = states_png(pattern, copies)
    if gif and copies == 1:
        from ..mechanics.deploy import deployment_path

        files[f"{stem}_deploy.gif"] = deployment_gif_3d(pattern, deployment_path(pattern, 24))
    return files
