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
from typing import cast

from .. import limits
from ..design.core import conformance as conf
from ..design.quad.fabrication import FabricationLimits
from ..design.quad.rigid.offset_outline import preferred_holes
from ..design.quad.solve import VIA_RIGID_INIT, DesignRequest, design, via_rigid_applies
from ..design.targets.lookup import Target
from ..errors import FabkiriError, InputError, Param, SolveError
from ..exchange.pattern_json import dumps
from ..fabricate import design_limits, fabricability
from ..fileio import publish
from ..pattern.kinds.tessellation import DEFAULT_KIND
from ..pattern.model import Pattern
from .closed_states import closed_outline_fit, overlapping_tiles, parse_contracted  # noqa: F401 (re-exported)
from .design_judge import CLOSURE_TOL, _check, _fit_miss, _hausdorff, _rank, _shape_met  # noqa: F401 (re-exported)
from .design_minimax import applies as minimax_applies
from .design_minimax import minimax_finish
from .design_mirror import keep_closer, mirror_axis
from .design_opening import check_floor, refine_to_floor
from .design_opening import judge as judge_opening
from .design_report import DesignAttempt, DesignReport
from .design_search import (
    RETRY_FIT_ABOVE,
    attempt_record,
    last_note,
    poor_for_size,
    replaces,
    retry_note,
    strip_why,
    with_why,
)
from .design_strip import LAST_INIT, LAST_TRIES, last_request, strip_design, strip_note
from .design_summary import _preview, preview_path, summary_lines  # noqa: F401 (preview_path re-exported)
from .design_turn import loaded_or_turned, request_target
from .designers import TakesTiles, register_designer
from .print_tiles import check_micrometre, check_room, check_tiles
from .shape_limits import annotate as annotate_misses

AUTO_INITS = ("conformal", "rescaled", "standard")  # tried in turn when --init is not given
# from 32x32 tiles a rigid design starts coarse to fine (the coarse closed-state grid resampled inside the
# rigid family): from the standard pattern the rigid family's LM stalls against the inequalities (128x128
# circle: 11 % of the size off, coarse 0.23 %; 64x64 heart 21.6 mm, coarse 0.098 mm and much faster; 64x64
# ellipse 7.3 mm, coarse 0.019 mm). Below 32x32 it was mixed (16x16: heart better, ellipse, star,
# rectangle and a points file worse), so the usual order stays there.
BIG_RIGID_INITS = ("coarse", "rescaled")
BIG_TILES = 32 * 32


@dataclass
class PatternRequest(TakesTiles):  # tiles: "8x8" is taken too, as the CLI's --tiles
    """Everything ``fabkiri design`` can be told (the same names as its options)."""

    tiles: tuple[int, int] | None  # rows, cols (None: kagome chooses them from the outline)
    trim: bool = False  # kagome: the R x C block cut to the outline (design/kagome/trim.py)
    # a name from templates/targets, a .csv/.json/.svg file, or the curve itself
    target: str | Target | None = None
    size: float | None = None  # the target's larger dimension in mm (named targets default to 100)
    rigid: bool = False
    symmetry: str | None = None  # "x" or "y"
    # None: rhombus, but parallelogram where offset_outline.preferred_holes says
    holes: str | None = None
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
    min_opening: float | None = None  # floor on the deployed hole fraction (opening_rows)
    # the target's split parameters BL, BR, TR, TL (None: its own; make's design/quad/corner_split.py)
    corners: tuple[float, float, float, float] | None = None
    name: str | None = None
    seed: int | None = None  # jitters the full solver's initial nodes (the rigid family ignores it)
    i_know: bool = False
    verbose: bool = False  # solver progress on stderr even for small solves
    quiet: bool = False  # no solver progress even for big solves (a sweep's workers)
    # the tessellation kind: which front door designs it (api/designers.py)
    kind: str = DEFAULT_KIND
    # degrees the lattice is laid at, counter-clockwise (None: on the outline's mirror axis, api/design_turn.py)
    lattice_angle: float | None = None

    def fabrication_limits(self, target: Target | None) -> tuple[FabricationLimits | None, dict]:
        """The mm limits of ``--material/--hinge/--printer/--style/--min-feature/--min-hole`` for
        ``target`` and the intent ``cut``/``print`` default to (``fabricate.design_limits.resolve``)."""
        return design_limits.resolve(
            self.material,
            self.hinge,
            self.printer,
            self.style,
            self.min_feature,
            self.min_hole,
            target,
        )


@dataclass
class DesignOutcome:
    """The design and its figures, like scipy's ``OptimizeResult``: the best attempt, judged.

    ``pattern`` carries both closed states and ``pattern.design["report"]`` (the
    same dict as ``report``); ``messages`` are the retry notes in the order they arose.
    """

    pattern: Pattern
    report: DesignReport  # pattern.json's ``design.report`` (design-report.schema.json)
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
        """Write the pattern and its preview, all or nothing, as ``fabkiri design`` does."""
        publish(self.files(output, preview), Path(output).parent)

    @property
    def max_equality_residual(self) -> float:
        """The largest equality residual the solver ended at (the same name on every design outcome)."""
        return float(self.report["max_equality_residual"])

    def summary(self, path=None) -> list[str]:
        """The lines ``fabkiri design`` prints about the design written to ``path`` (None: not written)."""
        return summary_lines(path, self.report)


def design_pattern(
    request: PatternRequest, notify: Callable[[str], None] | None = None
) -> DesignOutcome:
    """Design, contract, check and judge a pattern; ``notify`` receives each retry note as it arises.

    Raises :class:`InputError` for a request no design can meet and :class:`SolveError`
    when no initial guess could be built; a design that misses a check is returned, not raised.
    """
    messages: list[str] = []

    def say(text: str) -> None:
        messages.append(text)
        if notify is not None:
            notify(text)

    request, turned = loaded_or_turned(request, design_pattern, notify)
    if turned is not None:
        return turned
    asked = request.symmetry is not None  # "none" too: an explicit free request is never mirrored
    # the CLI's explicit "free"; a quad design is free without a symmetry
    if request.symmetry == "none":
        request = replace(request, symmetry=None)
    request, req, target, contracted = _solver_request(request)
    if not asked and (axis := mirror_axis(request, req)):  # both designs, the closer kept
        return keep_closer(request, axis, design_pattern, notify)
    shape_tol = conf.parse_shape_tol(request.shape_tol)
    req.second_opinion_above = _tol_rel(shape_tol, target)
    first: list[dict] = []
    best, cont, tried = None, None, _continuation_first(request, req, contracted)
    if tried:  # the rows from the start wall the fit in
        # the continuation's module loads where it runs: a design without fabrication limits never does
        from .continuation import LIMITS_COST_TILES, continuation, limits_note

        cont = continuation(request, req, target, shape_tol, first, design_pattern)
        if cont is not None and _good(cont):
            return _outcome(cont, first, messages, target)
        note = limits_note(cont) if cont and req.rows * req.cols >= LIMITS_COST_TILES else ""
        # where the limits cost the shape, the guesses (the full limits from the start) fare no better: 16x16
        # heart at 200 mm, prusa-mk4: continuation 22.1 %, then rescaled 22.7 %, standard 40.2 %, rigid 22.7 %,
        # all unconverged, in about 40 % of the design's time
        best = cont if note else None
        say(
            f"fabkiri: the continuation in the fabrication limits misses{note}; "
            + ("not retried from the initial guesses" if note else "trying the initial guesses")
        )
    attempts = first
    if best is None:
        best, attempts = _attempts(request, req, target, contracted, shape_tol, say)
        attempts = first + attempts
    req = strip_design(req, best)  # a strip's (or its continuation's) finishes on its lattice
    judge = _judge(contracted, request, target, shape_tol)
    if minimax_applies(req, contracted, best):  # the largest miss, after the least-squares fit
        best = minimax_finish(req, best, judge, attempts, say, shape_tol) or best
    if not tried and _continuation_applies(req, best, contracted):
        say(
            "fabkiri: the fabrication-aware design misses the shape; trying a continuation from the design "
            "without the fabrication rows"
        )
        from .continuation import continuation

        cont = continuation(request, req, target, shape_tol, attempts, design_pattern)
    if cont is not None and _rank(cont) < _rank(best):
        best = cont
    best = refine_to_floor(req, best, judge, attempts, say) or best  # a floor that cost the shape
    return _outcome(best, attempts, messages, target)


def _judge(contracted: dict, request: PatternRequest, target: Target | None, shape_tol: tuple):
    """``_check`` of a solver result against this request (a refinement's candidates)."""
    return lambda result: _check(result, contracted, request, target, shape_tol)


def check_size(request: PatternRequest) -> None:
    """The size bound :func:`design_pattern` applies to ``request``, without solving: raises
    :class:`InputError` past it; other problems of the request are left to the design itself."""
    try:
        request, req, _, contracted = _solver_request(request, sized=False)
    except FabkiriError:
        return
    _check_size(request, req, contracted)


def _solver_request(
    request: PatternRequest, sized: bool = True
) -> tuple[PatternRequest, DesignRequest, Target | None, dict]:
    """``(request with its holes resolved, solver request, target, closed-state specs)``, or InputError
    (with ``sized``, also past the size bound)."""
    if request.tiles is None:
        tiles = Param("tiles", shown="(rows, cols)", cli_value="ROWSxCOLS")
        raise InputError(
            "quad designs need ", tiles, " (a kagome design chooses it from the outline)"
        )
    if request.trim:
        raise InputError(
            Param("trim", True),
            " cuts kagome lattices to the outline; quad designs have no cut lattice",
        )
    rows, cols = request.tiles
    if rows < 2 or cols < 2:
        raise InputError(f"inverse design needs at least 2x2 tiles, got {rows}x{cols}")
    target = request_target(request)
    contracted: dict[int, object] = {}
    for text in request.contracted_target or []:
        s, spec = parse_contracted(text, request.size)
        if s in contracted:
            raise InputError(Param("contracted_target"), f" given twice for state {s}")
        contracted[s] = spec
    if target is None and not contracted:
        outline = Param("contracted_target", shown='"STATE:NAME"', cli_value="STATE:NAME")
        raise InputError("give ", Param("target"), ", or ", outline, " for a closed-state outline")
    check_micrometre(rows, cols, target)  # tiles under a micrometre: no solve
    fab_limits, intent = request.fabrication_limits(target)
    check_floor(request.min_opening)
    if (
        fab_limits is not None and target is not None
    ):  # a request no design can meet: say so before solving
        check_room(rows, cols, fab_limits, target)
        if request.corners is None:  # too narrow to print (not estimated for a lattice on corners)
            check_tiles(rows, cols, target, request.printer, intent.get("style"))
    holes = (
        request.holes
        if request.holes is not None
        else preferred_holes(rows, cols, request.rigid, request.symmetry, target, contracted)
    )
    request = replace(request, holes=holes)  # without --init, _attempts sets each guess in req.init
    req = DesignRequest(
        rows=rows,
        cols=cols,
        target=target,
        rigid=request.rigid,
        symmetry=request.symmetry,
        holes=holes,
        contracted=contracted,
        init=request.init or DesignRequest.init,
        tol=request.tol,
        solver=request.solver,
        outline=request.fit == "outline",
        fabrication=fab_limits,
        fabrication_intent=intent,
        seed=request.seed,
        min_opening=request.min_opening,
        rigid_first=not request.init,
        name=request.name or "",
    )
    if not req.name:
        parts = [
            target.name if target else "",
            *[f"{s}:{v.name if isinstance(v, Target) else 'rect'}" for s, v in contracted.items()],
        ]
        req.name = (
            f"{' '.join(p for p in parts if p)} {rows}x{cols}{' rigid' if request.rigid else ''}"
        )
    req.validate()
    if sized:
        _check_size(request, req, contracted)
    return request, req, target, contracted


def _check_size(request: PatternRequest, req: DesignRequest, contracted: dict) -> None:
    """The tile count within what the solver that will run was measured at (:mod:`fabkiri.limits`)."""
    family = via_rigid_applies(req) or (
        request.rigid and request.solver != "full" and request.holes == "rhombus" and not contracted
    )  # the rigid family's figures (a symmetric design solves over half its seeds: no dearer)
    limits.check_tiles(
        req.rows, req.cols, "design rigid" if family else "design full", request.i_know
    )


def _inits(request: PatternRequest, req: DesignRequest, target: Target | None) -> list[str]:
    """The initial guesses to try in turn: without an explicit --init, a design that fails a check is retried."""
    if request.init:
        return [request.init]
    if request.rigid and req.rows * req.cols >= BIG_TILES:
        return list(BIG_RIGID_INITS)
    if target is None:  # closed-state targets only: every guess is the standard pattern
        return [AUTO_INITS[0]]
    if via_rigid_applies(req):  # answered by the rigid family, coarse to fine, whatever the guess
        return ["coarse"]
    # last, when every guess misses: the rigid family (its members satisfy every non-rigid equality)
    return list(AUTO_INITS) + [VIA_RIGID_INIT] * via_rigid_applies(
        replace(req, init=VIA_RIGID_INIT)
    )


def _attempts(
    request: PatternRequest,
    req: DesignRequest,
    target: Target | None,
    contracted: dict,
    shape_tol: tuple,
    say: Callable[[str], None],
) -> tuple[DesignAttempt, list[dict]]:
    """The best outcome (``_rank``) over the guesses of :func:`_inits`, and each attempt's figures."""
    inits = _inits(request, req, target)
    last_ok = not (request.init or request.corners)
    best, attempts = None, list[dict]()
    passed = None  # a design that passed but is poor for its size (design_search.py): only last attempts after it
    # after the guesses, the pocket attempts below BIG_TILES then the bent strips (design_strip.py)
    for init in inits + [LAST_INIT] * (LAST_TRIES * last_ok):
        last = init in (VIA_RIGID_INIT, LAST_INIT)  # last resorts for a miss, not second opinions
        if last and best is not None and best.valid and _shape_met(best.report):
            if not poor_for_size(req, best):
                break
            passed = passed or best  # a pass past RETRY_FIT_ABOVE's retries
        if passed is not None and init != LAST_INIT:
            continue  # the guesses left and the rigid family's answer skipped
        sub = req
        if init == LAST_INIT:
            if (found := last_request(req, attempts, req.rows * req.cols < BIG_TILES)) is None:
                break  # no pocket split or bent strip (left) for this outline
            init, sub, what = found
            say(last_note(req, passed, attempts, what))
        req.init = init if sub is req else req.init
        try:
            result = design(
                sub, progress=(req.rows * req.cols >= 256 or request.verbose) and not request.quiet
            )
        except SolveError as exc:
            if len(inits) == 1:
                raise
            say(f"fabkiri: no {init} initial guess ({exc}); trying the next one")
            attempts.append(
                {"init": init, "status": "skipped", "problems": [str(exc)], "time_s": 0.0}
            )
            continue
        req.rigid_first = False  # tried once: later guesses go to the full solver
        outcome = _check(result, contracted, request, target, shape_tol)
        # the lattice a strip attempt used, and why
        outcome.report.update(with_why(strip_note(init, sub, req), strip_why(req, passed)))
        miss, shape_met = _fit_miss(outcome.report), _shape_met(outcome.report)
        attempts.append(attempt_record(init, outcome, (sub.rows, sub.cols), (req.rows, req.cols)))
        best = outcome if replaces(outcome, best, passed) else best
        if (
            outcome.valid
            and shape_met
            and (miss <= RETRY_FIT_ABOVE or outcome.report.get("rigid_first"))
        ):  # a rigid member's tips sit off the curve between seeds: the outline (shape_met) judges it
            if last or not last_ok or not poor_for_size(req, outcome):
                break
            passed = outcome
            continue
        retry_note(init, inits, outcome, say)
    if best is None:
        raise SolveError(
            "no initial guess could be built: " + "; ".join(a["problems"][0] for a in attempts)
        )
    return best, attempts


def _outcome(
    best: DesignAttempt, attempts: list[dict], messages: list[str], target: Target | None = None
) -> DesignOutcome:
    """The judged outcome: the best design with its attempts, validity, shape verdict and fabricability."""
    pattern, report, problems, valid = best.pattern, best.report, best.problems, best.valid
    report.update(attempts=attempts, time_s_total=float(sum(a["time_s"] for a in attempts)))
    annotate_misses(report, attempts, target, pattern)  # no advice already tried (shape_limits.py)
    shape_met = _shape_met(report)
    meta = {
        **(pattern.design or {}),
        "report": report,
        "valid": bool(valid),
        "shape": "met" if shape_met else "missed",
    }
    pattern = Pattern(
        nodes=pattern.nodes,
        tiles=pattern.tiles,
        contracted=best.states,
        parity=0,
        name=pattern.name,
        lattice=pattern.lattice,
        design=meta,
    )
    limits.check_designed(pattern)  # a target too small for its tiles: refused, not written
    report["fabricability"] = fabricability.summary(pattern)  # every material and printer preset
    floor = ((pattern.design or {}).get("options") or {}).get("min_opening")
    too_closed = judge_opening(pattern, report, floor)  # the floor read back on the final design
    problems, valid = [*problems, *too_closed], valid and not too_closed
    report["problems"] = [*report.get("problems", []), *too_closed]
    return DesignOutcome(
        pattern=pattern,
        report=cast(DesignReport, report),
        valid=bool(valid),
        shape_met=shape_met,
        problems=list(problems),
        messages=messages,
    )


def _tol_rel(shape_tol: tuple, target: Target | None) -> float:
    """``--shape-tol`` as a share of the deployed target's size (the solver skips its second opinion within it)."""
    value, unit = shape_tol
    return value / target.size if unit == "mm" and target is not None else value


def _good(outcome: DesignAttempt) -> bool:
    """Valid, within the shape tolerance and (for a printer) within its bed."""
    r = outcome.report
    return bool(outcome.valid and _shape_met(r) and r["checks"].get("fits_bed", True))


def _continuation_first(request: PatternRequest, req: DesignRequest, contracted: dict) -> bool:
    """Whether the continuation comes before the guesses: a fabrication-aware deployed-target design below
    BIG_TILES with no --init (16x16 heart at 200 mm, acrylic-3: every guess with the rows walled in, 16 %, after
    half the design's time; the continuation met the shape)."""
    return not request.init and _continuation_applies(req, None, contracted)


def _continuation_applies(req: DesignRequest, best, contracted: dict) -> bool:
    """Whether to try the continuation in the fabrication limits (:mod:`.continuation`): a fabrication-aware deployed-target design below BIG_TILES that is invalid, misses the shape or (for a
    printer) does not fit the bed (8x8 ellipse at 200 mm for prusa-mk4: 116 x 261 mm; its continuation fits)."""
    return (
        req.fabrication is not None
        and req.target is not None
        and not contracted
        and req.rows * req.cols < BIG_TILES
        and not (best is not None and _good(best))
    )


register_designer(DEFAULT_KIND, design_pattern)
