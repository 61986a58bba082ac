"""The design front door: :func:`design_pattern` turns a :class:`PatternRequest` into a :class:`DesignOutcome`.

The solve lives in :mod:`fabkiri.design`; this module holds the policy around
it: which initial guesses to try and when to retry, contraction into both
closed states (:mod:`fabkiri.mechanics`), loop closure and tile overlaps
(:mod:`fabkiri.verify`), closed-outline fits, the conformance verdict against
the shape tolerance and the fabricability summary. A design that misses its
tolerance is still returned (its best iterate, marked
``design.report.status = "unconverged"`` and ``design.valid = false``);
:attr:`DesignOutcome.success` says whether it passed everything.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

from .. import limits
from ..design import conformance as conf
from ..design.fabrication import smallest_size
from ..design.offset_outline import preferred_holes
from ..design.refine import refine_minimax
from ..design.solve import VIA_RIGID_INIT, DesignRequest, design, via_rigid_applies
from ..design.targets import Target, load_target
from ..errors import InputError, SolveError
from ..fabricate import design_limits, fabricability
from ..fileio import atomic_write
from ..mechanics.contract import contract
from ..pattern.fabricability import pal_bound
from ..pattern.io import dumps
from ..pattern.model import Pattern
from ..pattern.tessellation import DEFAULT_KIND
from .closed_states import closed_outline_fit, overlapping_tiles, parse_contracted  # noqa: F401 (re-exported)
from .design_summary import summary_lines
from .designers import register_designer

CLOSURE_TOL = 1e-9  # loop closure relative to the mean tile edge
AUTO_INITS = ("conformal", "rescaled", "standard")  # tried in turn when --init is not given
# from 32x32 tiles a rigid design starts coarse to fine (the coarse closed-state grid resampled inside the
# rigid family): from the standard pattern the rigid family's LM stalls against the inequalities (128x128
# circle: 11 % of the size off, coarse 0.23 %; 64x64 heart 21.6 mm in 204 s, coarse 0.098 mm in 12 s; 64x64
# ellipse 7.3 mm, coarse 0.019 mm in 30 s). Below 32x32 it was mixed (16x16: heart better, ellipse, star,
# rectangle and a points file worse), so the usual order stays there.
BIG_RIGID_INITS = ("coarse", "rescaled")
BIG_TILES = 32 * 32
# a valid design whose least-squares fit misses by more than this fraction of the target size is retried
# from the next guess and the closest valid fit kept (ellipse 16x16: rescaled 1.86 %, standard 0.08 %)
RETRY_FIT_ABOVE = 5e-3


@dataclass
class PatternRequest:
    """Everything ``fabkiri design`` can be told (the same names as its options)."""

    tiles: tuple[int, int]  # rows, cols
    target: str | None = None  # a name from templates/targets or a .csv/.json/.svg file
    size: float | None = None  # the target's larger dimension in mm (named targets default to 100)
    rigid: bool = False
    symmetry: str | None = None  # "x" or "y"
    holes: str | None = None  # None: rhombus, but parallelogram where offset_outline.preferred_holes says
    contracted_target: tuple[str, ...] = ()  # "STATE:NAME|FILE", "STATE:rect" or "STATE:rect=RATIO"
    init: str | None = None  # None: the retry order of AUTO_INITS / BIG_RIGID_INITS
    solver: str = "auto"
    fit: str = "outline"
    tol: float = 1e-10
    shape_tol: str = conf.DEFAULT_SHAPE_TOL
    material: str | None = None
    hinge: str | None = None
    printer: str | None = None
    style: str | None = None
    min_feature: float | None = None
    min_hole: float | None = None
    name: str | None = None
    seed: int | None = None  # jitters the full solver's initial nodes (the rigid family ignores it)
    i_know: bool = False
    verbose: bool = False  # solver progress on stderr even for small solves
    quiet: bool = False  # no solver progress even for big solves (a sweep's workers)
    kind: str = DEFAULT_KIND  # the tessellation kind: which front door designs it (api/designers.py)


@dataclass
class DesignOutcome:
    """The design and its figures, like scipy's ``OptimizeResult``: the best attempt, judged.

    ``pattern`` carries both closed states and ``pattern.design["report"]`` (the
    same dict as ``report``); ``messages`` are the retry notes in the order they arose.
    """

    pattern: Pattern
    report: dict
    valid: bool  # converged, closes, no overlaps
    shape_met: bool  # every outline within the shape tolerance
    problems: list[str] = field(default_factory=list)
    messages: list[str] = field(default_factory=list)

    @property
    def success(self) -> bool:
        return self.valid and self.shape_met

    @property
    def exit_code(self) -> int:
        return 0 if self.success else 1

    @property
    def status(self) -> str:
        """``ok``, ``unconverged`` (a check failed) or ``shape missed``."""
        return "ok" if self.success else ("unconverged" if not self.valid else "shape missed")

    def files(self, output, preview: bool = True) -> dict[Path, bytes | str]:
        """``pattern.json`` text and the preview PNG beside it (its name goes in the report first)."""
        png = _preview(self.pattern, self.report, output) if preview else None
        out: dict[Path, bytes | str] = {Path(output): dumps(self.pattern)}
        if png is not None:
            out[png[0]] = png[1]
        return out

    def write(self, output, preview: bool = True) -> None:
        """Write the pattern (atomically) and its preview, as ``fabkiri design`` does."""
        png = _preview(self.pattern, self.report, output) if preview else None
        atomic_write(output, dumps(self.pattern))
        if png is not None:
            png[0].write_bytes(png[1])

    def summary(self, output) -> list[str]:
        """The lines ``fabkiri design`` prints about the design written to ``output``."""
        return summary_lines(output, self.report)


def design_pattern(request: PatternRequest, notify: Callable[[str], None] | None = None) -> DesignOutcome:
    """Design, contract, check and judge a pattern; ``notify`` receives each retry note as it arises.

    Raises :class:`InputError` for a request no design can meet and :class:`SolveError`
    when no initial guess could be built; a design that misses a check is returned, not raised.
    """
    messages: list[str] = []

    def say(text: str) -> None:
        messages.append(text)
        if notify is not None:
            notify(text)

    request, req, target, contracted = _solver_request(request)
    shape_tol = conf.parse_shape_tol(request.shape_tol)
    req.second_opinion_above = _tol_rel(shape_tol, target)
    best, attempts = _attempts(request, req, target, contracted, shape_tol, say)
    if _continuation_applies(req, best, contracted):
        say("fabkiri: the fabrication-aware design misses the shape; trying a continuation from the design "
            "without the fabrication rows")
        cont = _continuation(request, req, target, shape_tol, attempts)
        if cont is not None and _rank(cont) < _rank(best):
            best = cont
    return _outcome(best, attempts, messages)


def _solver_request(request: PatternRequest) -> tuple[PatternRequest, DesignRequest, Target | None, dict]:
    """``(request with its holes resolved, solver request, target, closed-state specs)``, or InputError."""
    rows, cols = request.tiles
    if rows < 2 or cols < 2:
        raise InputError(f"inverse design needs at least 2x2 tiles, got {rows}x{cols}")
    target = load_target(request.target, request.size) if request.target else None
    contracted: dict[int, object] = {}
    for text in request.contracted_target or []:
        s, spec = parse_contracted(text, request.size)
        if s in contracted:
            raise InputError(f"--contracted-target given twice for state {s}")
        contracted[s] = spec
    if target is None and not contracted:
        raise InputError("give --target, or --contracted-target STATE:NAME for a closed-state outline")
    fab_limits, intent = design_limits.resolve(request.material, request.hinge, request.printer, request.style,
                                               request.min_feature, request.min_hole, target)
    if fab_limits is not None and target is not None:  # a request no design can meet: say so before solving
        least = smallest_size(target.size, abs(target.area), rows * cols, fab_limits)
        if least is not None:
            raise InputError(
                f"{rows}x{cols} tiles each at least {fab_limits.required_width_mm():.3g} mm wide ({fab_limits.source}) "
                f"cannot fit a {target.size:.4g} mm {target.name}: they cover at least "
                f"{pal_bound(rows * cols, fab_limits.required_width_mm()):.4g} mm² (Pál) but the target has "
                f"{abs(target.area):.4g} mm²; the smallest size that could work is --size {least:.4g}")
    holes = request.holes if request.holes is not None else preferred_holes(rows, cols, request.rigid,
                                                                            request.symmetry, target, contracted)
    request = replace(request, holes=holes)  # without --init, _attempts sets each guess in req.init
    req = DesignRequest(rows=rows, cols=cols, target=target, rigid=request.rigid, symmetry=request.symmetry,
                        holes=holes, contracted=contracted, init=request.init or DesignRequest.init, tol=request.tol,
                        solver=request.solver, outline=request.fit == "outline", fabrication=fab_limits,
                        fabrication_intent=intent, seed=request.seed, rigid_first=not request.init,
                        name=request.name or "")
    if not req.name:
        parts = [target.name if target else "", *[f"{s}:{v.name if isinstance(v, Target) else 'rect'}"
                                                 for s, v in contracted.items()]]
        req.name = f"{' '.join(p for p in parts if p)} {rows}x{cols}{' rigid' if request.rigid else ''}"
    req.validate()
    family = via_rigid_applies(req) or (request.rigid and request.solver != "full" and request.holes == "rhombus"
                                        and not request.symmetry and not contracted)  # the rigid family's figures
    limits.check_tiles(rows, cols, "design rigid" if family else "design full", request.i_know)
    return request, req, target, contracted


def _inits(request: PatternRequest, req: DesignRequest, target: Target | None) -> list[str]:
    """The initial guesses to try in turn: without an explicit --init, a design that fails a check is retried."""
    if request.init:
        return [request.init]
    if request.rigid and req.rows * req.cols >= BIG_TILES:
        return list(BIG_RIGID_INITS)
    if target is None:  # closed-state targets only: every guess is the standard pattern, retries repeat it
        return [AUTO_INITS[0]]
    if via_rigid_applies(req):  # answered by the rigid family, coarse to fine, whatever the guess
        return ["coarse"]
    # last, when every guess misses: the rigid family (its members satisfy every non-rigid equality)
    return list(AUTO_INITS) + [VIA_RIGID_INIT] * via_rigid_applies(replace(req, init=VIA_RIGID_INIT))


def _attempts(request: PatternRequest, req: DesignRequest, target: Target | None, contracted: dict,
              shape_tol: tuple, say: Callable[[str], None]) -> tuple[tuple, list[dict]]:
    """The best outcome (``_rank``) over the guesses of :func:`_inits`, and each attempt's figures."""
    inits = _inits(request, req, target)
    best, attempts = None, list[dict]()
    for init in inits:
        if init == VIA_RIGID_INIT and best is not None and best[3] and _shape_met(best[1]):
            break  # the rigid family is the last resort for a miss, not a second opinion
        req.init = init
        try:
            result = design(req, progress=(req.rows * req.cols >= 256 or request.verbose) and not request.quiet)
        except SolveError as exc:
            if len(inits) == 1:
                raise
            say(f"fabkiri: no {init} initial guess ({exc}); trying the next one")
            attempts.append({"init": init, "status": "skipped", "problems": [str(exc)], "time_s": 0.0})
            continue
        req.rigid_first = False  # tried once: later guesses go to the full solver
        outcome = _check(result, contracted, request, target, shape_tol)
        miss, shape_met = _fit_miss(outcome[1]), _shape_met(outcome[1])
        attempts.append({"init": init, "status": outcome[1]["status"], "problems": outcome[2],
                         "time_s": outcome[1]["time_s"], "fit_max_rel_size": miss,
                         "hausdorff_max_rel": _hausdorff(outcome[1]), "shape": "met" if shape_met else "missed"})
        best = outcome if best is None or _rank(outcome) < _rank(best) else best
        if outcome[3] and shape_met and (miss <= RETRY_FIT_ABOVE or outcome[1].get("rigid_first")):
            break  # a rigid member's tips sit off the curve between seeds: the outline (shape_met) judges it
        if outcome[3] and init != inits[-1]:
            why = (f"misses the target by {miss:.2%} of its size" if miss > RETRY_FIT_ABOVE else
                   f"misses the shape tolerance (Hausdorff {_hausdorff(outcome[1]):.2%} of the size)")
            say(f"fabkiri: design from the {init} guess {why}; trying the next guess too")
        elif len(inits) > 1 and init != inits[-1]:
            say(f"fabkiri: design from the {init} guess failed ({outcome[2][0]}); retrying")
    if best is None:
        raise SolveError("no initial guess could be built: " + "; ".join(a["problems"][0] for a in attempts))
    return best, attempts


def _outcome(best, attempts: list[dict], messages: list[str]) -> DesignOutcome:
    """The judged outcome: the best design with its attempts, validity, shape verdict and fabricability."""
    pattern, report, problems, valid, contracted_states = best
    report.update(attempts=attempts, time_s_total=float(sum(a["time_s"] for a in attempts)))
    shape_met = _shape_met(report)
    meta = {**(pattern.design or {}), "report": report, "valid": bool(valid),
            "shape": "met" if shape_met else "missed"}
    pattern = Pattern(nodes=pattern.nodes, tiles=pattern.tiles, contracted=contracted_states, parity=0,
                      name=pattern.name, lattice=pattern.lattice, design=meta)
    report["fabricability"] = fabricability.summary(pattern)  # every material and printer preset
    return DesignOutcome(pattern=pattern, report=report, valid=bool(valid), shape_met=shape_met,
                         problems=list(problems), messages=messages)


def _tol_rel(shape_tol: tuple, target: Target | None) -> float:
    """``--shape-tol`` as a share of the deployed target's size (the solver skips its second opinion within it)."""
    value, unit = shape_tol
    return value / target.size if unit == "mm" and target is not None else value


# Continuation in the fabrication limits (issue 14): the rows held from the first step wall the fit in (16x16
# heart at 200 mm, acrylic-3: 5-19 of 1024 width rows active, Hausdorff 16 % against 1.75 % without them).
# From the design without them, the limits are raised in steps, each step warm-started from the last. A rigid
# request takes one step (measured, heart: straight to the limits 2.88 %, in four steps 3.13 %).
CONTINUATION = (0.25, 0.5, 0.75, 1.0)
CONTINUATION_MARGIN = 0.02  # the rows' penalty margin in a step (tile edges; FabricationLimits.margin)


def _continuation_applies(req: DesignRequest, best, contracted: dict) -> bool:
    """A fabrication-aware deployed-target design below BIG_TILES that is invalid, misses the shape or (for a
    printer) does not fit the bed (8x8 ellipse at 200 mm for prusa-mk4: 116 x 261 mm; its continuation fits)."""
    return (req.fabrication is not None and req.target is not None and not contracted
            and req.rows * req.cols < BIG_TILES
            and not (best[3] and _shape_met(best[1]) and best[1]["checks"].get("fits_bed", True)))


def _continuation(request: PatternRequest, req: DesignRequest, target: Target | None, shape_tol: tuple,
                  attempts: list):
    """The design without fabrication rows, then the rows raised in steps (``CONTINUATION``) from it, each warm
    started from the last; a last step that does not converge is tried in the rigid family (where it may) from
    the last converged step. Returns the ``_check`` outcome, or None when the design without the rows fails."""
    free = design_pattern(replace(request, material=None, hinge=None, printer=None, style=None, min_feature=None,
                                  min_hole=None, quiet=True))
    if not free.valid:
        return None
    X = last_ok = free.pattern.nodes
    spent = free.report.get("time_s_total", 0.0)  # wall s, as the attempts
    fab, printer = req.fabrication, request.printer
    assert fab is not None, "_continuation_applies admits only fabrication-aware requests"
    if printer:  # the strip rows follow the closed state that fits the bed (2:1 ellipse: state 2)
        fab = replace(fab, print_state=design_limits.bed_state(free.pattern.contracted, printer))
        req = replace(req, fabrication=fab, fabrication_intent={**req.fabrication_intent, "state": fab.print_state})
    # a non-rigid request below 32x32 steps in the rigid family when it may (a member meets every non-rigid
    # equality): with the full solver the steps from 7/8 of the limits on stalled against closed holes
    # (hundreds of non-overlap rows at zero; heart 16x16: equality 1e-5 to 6e-5, unconverged, 2.2-3.3 %)
    init = VIA_RIGID_INIT if via_rigid_applies(replace(req, init=VIA_RIGID_INIT)) else req.init
    for f in (1.0,) if req.rigid else CONTINUATION:
        step = replace(req, fabrication=fab.scaled(f, CONTINUATION_MARGIN), start=X, init=init)
        result = design(step)
        spent += result.report["time_s"]
        X = result.pattern.nodes
        if result.converged:
            last_ok = X
    outcome = _check(result, {}, request, target, shape_tol)
    how = "continuation"
    if not outcome[3] and via_rigid_applies(replace(req, init=VIA_RIGID_INIT)):
        rigid = _check(design(replace(step, init=VIA_RIGID_INIT, start=last_ok)), {}, request, target, shape_tol)
        spent += rigid[1]["time_s"]
        if _rank(rigid) < _rank(outcome):
            outcome, how = rigid, "continuation, rigid family last"
    trace: list[float] = []
    if not (outcome[3] and _shape_met(outcome[1])):  # the fit was least squares, the tolerance is a maximum;
        # from an unconverged continuation too (only converged steps are kept: 16x16 heart, prusa-mk4, 2.53 %)
        bed = None if not printer else (  # keep only steps whose printed closed state fits the bed
            lambda r: design_limits.fits_bed(contract(r.pattern, fab.print_state).corners, printer))
        refined, trace, secs = refine_minimax(replace(step, init=VIA_RIGID_INIT if "rigid family" in how else init),
                                              outcome[0].nodes, accept=bed)
        spent += secs
        if refined is not None and _rank(cand := _check(refined, {}, request, target, shape_tol)) < _rank(outcome):
            outcome, how = cand, how + ", minimax refinement"
    outcome[1]["continuation"] = {"steps": list((1.0,) if req.rigid else CONTINUATION), "how": how,
                                  "free_hausdorff_rel": _hausdorff(free.report), "margin": CONTINUATION_MARGIN,
                                  "refinement_hausdorff_rel": trace}
    attempts.append({"init": how, "status": outcome[1]["status"], "problems": outcome[2], "time_s": spent,
                     "fit_max_rel_size": _fit_miss(outcome[1]), "hausdorff_max_rel": _hausdorff(outcome[1]),
                     "shape": "met" if _shape_met(outcome[1]) else "missed"})
    return outcome


def _shape_met(report: dict) -> bool:
    return all(j["status"] == "met" for j in (report.get("shape") or {}).values())


def _hausdorff(report: dict) -> float:
    """Worst Hausdorff distance of any outline relative to its target's size."""
    return max((c["hausdorff_rel"] for c in (report.get("conformance") or {}).values()), default=0.0)


def preview_path(output) -> Path:
    """Where the design preview goes: ``NAME.png`` beside ``NAME.json``."""
    p = Path(output)
    return p.with_name((p.stem if p.suffix.lower() == ".json" else p.name) + ".png")


def _preview(pattern: Pattern, report: dict, output) -> tuple[Path, bytes]:
    """The preview's path and bytes (rendered before anything is written); its name goes in the report."""
    from ..render.conformance import conformance_png

    path = preview_path(output)
    report["preview"] = path.name
    return path, conformance_png(pattern, report.get("conformance") or {}, report.get("shape") or {})


def _fit_miss(report: dict) -> float:
    """Worst fit of the tips (deployed or closed-state outline) to any target relative to its size (the soft
    outline rows never reach zero: ``_hausdorff`` judges the whole outline)."""
    return max((float(f.get("max_rel_size", 0.0)) for f in (report.get("fit") or {}).values() if not f.get("soft")),
               default=0.0)


def _rank(outcome) -> tuple:
    """Order of preference among attempts: valid first, then (for a printer) closed state 1 within its bed, then
    fewer problems, then the shape tolerance met, then the smaller Hausdorff distance, then the closer fit of
    the tips (the heart 8x8 for prusa-mk4: the refined design, 3.27 %, was 227 mm tall on the 210 mm bed)."""
    return (not outcome[3], not outcome[1].get("checks", {}).get("fits_bed", True), len(outcome[2]),
            not _shape_met(outcome[1]), _hausdorff(outcome[1]), _fit_miss(outcome[1]))


def _check(result, contracted, request: PatternRequest, target: Target | None, shape_tol: tuple):
    """Contract, check closure, overlaps and outlines; returns (pattern, report, problems, valid, states)."""
    pattern = result.pattern
    report = dict(result.report)
    size = pattern.tile_size
    checks: dict[str, object] = {}
    contracted_states = {}
    problems = []
    for s in (1, 2):
        c = contract(pattern, s)
        contracted_states[s] = c.corners
        rel = c.max_closure / size
        checks[f"closure_{s}_rel"] = rel
        if not rel <= CLOSURE_TOL:
            problems.append(f"state {s} does not close (loop closure {rel:.2e} tile sizes)")
    for label, corners in [("deployed", pattern.corners()), *[(f"state {s}", contracted_states[s]) for s in (1, 2)]]:
        ov = overlapping_tiles(corners, CLOSURE_TOL * size)
        checks[f"overlaps_{label.replace(' ', '_')}"] = len(ov)
        if ov:
            where = "the deployed state" if label == "deployed" else label
            problems.append(f"{len(ov)} overlapping tile pairs in {where} (first {ov[0]})")
    if request.printer:  # in the state `print` makes: a design that does not fit the bed ranks below one that does
        state = (((pattern.design or {}).get("options") or {}).get("fabrication") or {}).get("state", 1)
        checks["fits_bed"] = design_limits.fits_bed(contracted_states[state], request.printer)
    if request.rigid or request.holes == "parallelogram":
        from ..pattern.residuals import hinge_sums

        checks["hinge_sum_max_rad"] = float(np.abs(hinge_sums(pattern)).max())
    closed_fit = {}
    for s, spec in contracted.items():
        if isinstance(spec, Target):
            closed_fit[str(s)] = closed_outline_fit(pattern, contracted_states[s], result.closed_grids[s],
                                                    result.closed_targets[s], s)
    if closed_fit:
        report["closed_outline_fit"] = closed_fit
    report["conformance"], report["shape"] = _conformance(pattern, result, contracted_states, target,
                                                              shape_tol)
    report["checks"] = checks
    valid = result.converged and not problems
    if not result.converged:
        problems.insert(0, f"solver did not reach the tolerance (max equality residual "
                           f"{report['max_equality_residual']:.2e} > {request.tol:g})")
    if problems:
        report["status"] = "unconverged"
        report["problems"] = problems
    return pattern, report, problems, valid, contracted_states


def _conformance(pattern: Pattern, result, contracted_states: dict, target: Target | None,
                 shape_tol: tuple) -> tuple[dict, dict]:
    """Conformance of the deployed tips and of each closed-state outline with a target curve, and each
    judged against ``--shape-tol``."""
    measured = {}
    tiles = (pattern.lattice["rows"], pattern.lattice["cols"]) if pattern.lattice else None
    if target is not None:
        measured["deployed"] = conf.deployed(pattern.nodes, pattern.topology, target)
    for s, tgt in sorted(result.closed_targets.items()):
        measured[f"state_{s}"] = conf.closed(contracted_states[s], tgt)
    return measured, {k: conf.judge(c, shape_tol, tiles) for k, c in measured.items()}


register_designer(DEFAULT_KIND, design_pattern)
