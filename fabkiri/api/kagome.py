"""``design_kagome``: the front door of kagome inverse design (``fabkiri design --lattice kagome``).

Policy: build the standard R x C kagome at the target's size, design it onto the target
(:mod:`fabkiri.design.kagome.fit`), contract both closed states, verify the pattern (both states,
overlaps, target shape) and judge the shape. The best iterate is always returned; ``valid`` and
``exit_code`` say whether it met the equality tolerance and every check.

Fabrication (``--material/--hinge``, ``--printer/--style``, ``--min-feature``, ``--min-hole``): resolved
into mm limits exactly as for quads (``fabricate/design_limits.resolve``), refused up front when the
tiles cannot fit the target (Pál's bound, as quads), solved under the kagome rows of
:mod:`fabkiri.design.kagome.fabrication`, and judged on those rows in mm: a candidate that misses a limit is
passed over, and a design that meets none is reported with its figures and exit 1. The limits become the
design's intent (``cut``/``print`` defaults), as for quads. Without these options, as for quads, no row
is added and the design reports its fabricability (every material's smallest cut scale).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING, Any, cast

import numpy as np

from .. import limits as size_limits
from ..design.core import conformance as conf
from ..design.kagome import aspect as KA
from ..design.kagome import fabrication as KF
from ..design.kagome import opening as KO
from ..design.kagome import trim as KT
from ..design.kagome.fit import design
from ..design.quad.fabrication import FabricationLimits, smallest_size
from ..design.targets.curve import Target
from ..design.targets.lookup import load_target
from ..errors import InputError, Param
from ..exchange.pattern_json import dumps
from ..fabricate import fabricability
from ..fileio import atomic_write
from ..mechanics.contract import with_contracted_states
from ..pattern.kinds.kagome.lattice import standard_kagome, trimmed_kagome
from ..pattern.model import Pattern
from ..pattern.thinness import pal_bound
from ..verify import verify_pattern
from . import kagome_lattices as KL
from .design_opening import check_floor
from .design_opening import judge as judge_opening
from .design_opening import summary_lines as opening_lines
from .design_report import KagomeReport
from .design_summary import wrote
from .designers import register_designer

if TYPE_CHECKING:
    from .design import PatternRequest

# options of the quad design that have no kagome counterpart yet
UNSUPPORTED = ("rigid", "holes", "contracted_target", "lattice_angle")


@dataclass(frozen=True)
class KagomeOutcome:
    """A kagome design, its report and its verdict."""

    pattern: Pattern
    report: (
        KagomeReport  # written into pattern.json as ``design.report`` (design-report.schema.json)
    )
    valid: bool
    tiles: tuple[int, int] = (0, 0)  # rows, cols

    @property
    def exit_code(self) -> int:
        return 0 if self.valid else 1

    def write(self, path, preview: bool = True) -> None:
        """Write the pattern (atomically); a kagome design has no preview yet."""
        atomic_write(path, dumps(self.pattern))

    @property
    def max_equality_residual(self) -> float:
        """The largest equality residual the solver ended at (the same name on every design outcome)."""
        return float(self.report["max_equality_residual"])

    def summary(self, path=None) -> list[str]:
        """The lines ``fabkiri design --lattice kagome`` prints about the design written to ``path`` (None:
        not written): the figures, then the fabrication limits and whether the design meets them (mm), then fabricability."""
        r, (rows, cols) = self.report, self.tiles
        cut = f" cut to {r['trimmed_tiles']} tiles" if r.get("trimmed_tiles") else ""
        out = [
            f"{wrote(path)}: kagome {rows}x{cols}{cut} {r['status']}, max equality residual "
            f"{self.max_equality_residual:.2e}, Hausdorff {100 * r['conformance']['hausdorff_rel']:.2f} % of "
            f"the size (shape {r['shape']['status']}), verify: "
            f"{'pass' if not r['verify_failed'] else 'FAIL ' + ', '.join(r['verify_failed'])}"
        ]
        fr = r.get("fabrication")
        if fr and "met" in fr:
            out.append(_fabrication_line(fr))
        out += opening_lines(r) + [
            f"fabkiri: design failed: {p}" for p in r.get("opening_problems", [])
        ]
        if r["shape"]["status"] == "missed" and not r.get("trimmed_tiles"):
            out.append(TRIM_HINT)
        if r.get("fabricability"):
            out += fabricability.summary_lines(r["fabricability"])
        return out


# a whole R x C block bends its corners onto a round or pointed outline, where the corner tiles reach the
# gap and quality floors; cut to the outline it has no such corners (docs/kagome.md, "A lattice cut to")
TRIM_HINT = (
    "hint: the whole R x C block must bend its corners onto the outline; --trim cuts it to the outline "
    "instead, which fits round and pointed outlines nearer"
)


def _fabrication_line(fr: dict) -> str:
    """One line: the limits' source, met or missed, the figures and each family's smallest slack."""
    fams = ", ".join(
        f"{k[len('fabrication_') :]} min {v['min']:.3g}{'' if 'angle' in k else ' mm'}"
        + (f" ({v['violated']}/{v['rows']} below)" if v["violated"] else "")
        for k, v in fr["families"].items()
    )
    return (
        f"fabrication ({fr['limits']['source']}): {'met' if fr['met'] else 'MISSED'}; thinnest tile "
        f"{fr['thinnest_tile_mm']:.3g} mm ({fr['thinnest_shrunk_tile_mm']:.3g} mm shrunk), smallest hinge "
        f"angle {fr['smallest_hinge_angle_deg']:.3g}°; rows: {fams}"
        + (
            ""
            if fr.get("without_limits_hausdorff_rel") is None
            else f"; designed from the {fr['route']} (without the limits: Hausdorff "
            f"{100 * fr['without_limits_hausdorff_rel']:.2f} %)"
        )
    )


def design_kagome(  # noqa: PLR0913 (the options of `fabkiri design --lattice kagome`)
    rows: int,
    cols: int,
    target: str,
    size: float | None = None,
    *,
    tol: float = 1e-10,
    shape_tol: str = conf.DEFAULT_SHAPE_TOL,
    name: str | None = None,
    symmetry: bool | str = True,
    fabrication: FabricationLimits | None = None,
    intent: dict | None = None,
    min_opening: float | None = None,
    trim: bool = False,
) -> KagomeOutcome:
    """Design a reconfigurable R x C kagome whose deployed outline follows ``target`` (mm).

    ``symmetry`` imposes every mirror the lattice and the target share (vertical for C odd, horizontal
    for R even; docs/kagome.md); False leaves the design free (about twice the fitting freedom); ``"x"``
    or ``"y"`` imposes that mirror alone (the lattice and the target must have it). ``fabrication``: mm
    limits the design keeps (:mod:`fabkiri.design.kagome.fabrication`), ``intent`` what ``cut``/``print`` then
    default to (``fabricate.design_limits.resolve`` gives both). ``trim``: the R x C block cut to the
    outline (:mod:`fabkiri.design.kagome.trim`) instead of the whole block."""
    if rows < 2 or cols < 2:  # a single row or column has no outline side to fit each way
        raise InputError(f"kagome inverse design needs at least 2x2 tiles, got {rows}x{cols}")
    tgt = load_target(target, size)
    shape = conf.parse_shape_tol(shape_tol)
    keep = KT.kept_tiles(rows, cols, tgt) if trim else None
    if fabrication is not None:
        _check_room(rows, cols, fabrication, tgt, None if keep is None else len(keep))
    std = _standard(rows, cols, keep, 1.0)
    tile = tgt.size / float(np.ptp(std.nodes, axis=0).max())  # the standard spans the target
    std = _standard(rows, cols, keep, tile)
    faces = _print_faces(std, fabrication)

    def fab_of(weight: float) -> list:
        return KF.families(std, fabrication, tile, faces=faces, weight=weight) + KO.families(
            std, min_opening, weight
        )

    check_floor(min_opening)
    accept = KO.accepting(_meets(fabrication, faces), min_opening)
    # a cut lattice that misses the shape tolerance (as a fraction of the size) is designed again damped
    damp = (keep is not None, shape[0] if shape[1] == "rel" else shape[0] / tgt.size)
    d, pattern, rejected, convex, free, route, paired = _solve(
        std, tgt, symmetry, fab_of, accept, damp
    )
    report = _report(d, pattern, tgt, shape, (rows, cols), tol, tile, rejected, convex)
    report["pair_rows"] = paired
    report["trimmed_tiles"] = None if keep is None else len(keep)
    if fabrication is not None:
        report["fabrication"] = KF.measure(pattern, fabrication, faces)
        # the price of the limits: the design without them (None: it met them already)
        report["fabrication"]["without_limits_hausdorff_rel"] = free
        report["fabrication"]["route"] = route
    size_limits.check_designed(pattern)  # a target too small for its tiles: refused, not written
    # every material's smallest cut scale (the print rows of this summary assume quad faces: left out)
    report["fabricability"] = fabricability.summary(pattern, prints=())
    too_closed = judge_opening(pattern, report, min_opening)  # the opening figures, the floor met
    report["opening_problems"] = too_closed
    options: dict[str, object] = {"fabrication": dict(intent)} if intent else {}
    options.update({"min_opening": min_opening} if min_opening else {})
    pattern = replace(
        pattern,
        name=name or pattern.name,
        design={
            **(pattern.design or {}),
            "report": report,
            "shape_tol": shape_tol,
            **({"options": options} if options else {}),
        },
    )
    rep = verify_pattern(pattern, shape_tol=shape_tol)
    report["verify_failed"] = [c.name for c in rep.failed()]
    valid = report["status"] == "converged" and not report["verify_failed"]
    valid = valid and bool(report.get("fabrication", {}).get("met", True)) and not too_closed
    pattern = replace(pattern, design={**(pattern.design or {}), "report": report, "valid": valid})
    return KagomeOutcome(pattern, cast(KagomeReport, report), valid, (rows, cols))


def _solve(std, tgt, symmetry, fab_of, accept, damp=(False, 0.0)):
    """``(design, pattern, rejected, convex, free, route, paired)``: the design without the fabrication
    rows (:func:`_free_design`); if
    none of its candidates closes and meets the limits, two designs with the rows and the nearer that
    meets them: a continuation from the free design's nearest closing candidate (``free``: its Hausdorff
    fraction; rows weighted ``KF.WEIGHT``), as the quad designer continues from its design without them,
    and one from the initial guess (rows weighted 1). Measured: 12x21 heart at 240 mm, acrylic-3: from the
    initial guess every candidate folds, the continuation meets them at 9.49 %; 6x11 at 120 mm: 7.28 %
    from the initial guess, 9.39 % by continuation. Then, if still no candidate closes, the same with
    convex holes, which rule tile crossings out. ``damp``: (a lattice cut to the outline, the shape
    tolerance as a fraction of the size), :func:`_free_design`."""
    limited = bool(fab_of(1.0))  # some limit gives rows
    d, pattern, rejected, paired = _free_design(std, tgt, symmetry, accept, limited, damp)
    start, free, route = None, None, "without rows" if limited else ""
    if pattern is None and limited:
        near, _ = _first_closing(d, _any)
        start = (near or with_contracted_states(d.pattern)).nodes
        free = conf.deployed(start, std.topology, tgt)["hausdorff_rel"]
        tries = {
            "continuation": design(std, tgt, symmetry=symmetry, fab=fab_of(KF.WEIGHT), start=start),
            "initial guess": design(std, tgt, symmetry=symmetry, fab=fab_of(1.0)),
        }
        route, d, pattern, rejected = _nearest(tries, accept)
    convex = pattern is None
    if convex:
        d = design(std, tgt, symmetry=symmetry, convex=True, fab=fab_of(KF.WEIGHT), start=start)
        pattern, rejected = _first_closing(d, accept)
    if pattern is None and limited:  # none meets the limits: the nearest that closes, reported
        pattern, rejected = _first_closing(d, _any)
    if pattern is None:  # still none: the solver's best, whose failures verify names
        pattern = with_contracted_states(d.pattern)
    return d, pattern, rejected, convex, free, route, paired


def _free_design(std, tgt, symmetry, accept, limited: bool, damp=(False, 0.0)):
    """``(design, pattern, rejected, paired)``: the design without fabrication rows and its nearest
    closing candidate. On a lattice cut to the outline (``damp[0]``) whose nearest closing candidate misses
    the shape tolerance (``damp[1]``, a fraction of the size) or where none closes, designs by other Lawson
    routes (:func:`_other_lawson_routes`), and the nearest. When nearer candidates were passed over (tiles
    crossing a hole or a row-end notch: the hinge-gap rows see only the two tiles at a hinge) or none
    closes, a second design with the rows that keep tiles sharing no hinge apart (``pairs``), and the
    nearer of the two (``paired``: the second). Measured (docs/kagome.md, "What limits the fit"): free 6x11 heart 4.54 ->
    4.30 %. With fabrication limits the routes below follow instead (candidates pass over for the limits
    too)."""
    # the solves of each mirror choice's designs: the other Lawson routes begin with the same ones
    shared: dict = {}
    d = design(std, tgt, symmetry=symmetry, solves=shared.setdefault(symmetry, {}))
    if damp[0] and not limited:
        d, pattern, rejected = _other_lawson_routes(std, tgt, symmetry, accept, damp[1], d, shared)
        symmetry = symmetry if d.symmetry else False  # the routes may have kept a free design
    else:
        pattern, rejected = _first_closing(d, accept)
    if limited or (pattern is not None and not rejected):
        return d, pattern, rejected, False
    dp = design(std, tgt, symmetry=symmetry, pairs=True)
    pp, rp = _first_closing(dp, accept)
    if pp is not None and (pattern is None or dp.candidates[rp][0] < d.candidates[rejected][0]):
        return dp, pp, rp, True
    return d, pattern, rejected, False


def _other_lawson_routes(std, tgt, symmetry, accept, enough: float, d, shared=None):
    """``(design, pattern, rejected)``: ``d``, its nearest closing candidate and how many nearer were
    passed over, or, while that misses ``enough`` (a fraction of the size) or none closes, the nearer of it
    and a design by the next route: without the mirror, when ``d`` took one the lattice and the target
    share (``symmetry`` True, not asked for by name), then damped, then from the best design so far
    (those two without the mirror once a design without it is the nearer). A mirror halves the family's
    freedom, and on the heart cut from a block with C odd it costs the fit (docs/kagome.md, "The mirror on
    a cut heart": 6x11 cut to 40 tiles 4.60 -> 1.81 %, 12x21 cut to 141 5.90 -> 2.63 %). The Lawson path
    on a cut lattice turns on the arithmetic's last bits; another route gives other candidates
    (docs/kagome.md, "Other Lawson routes on a cut lattice": 7x14 heart cut to 59 tiles 2.42 -> 0.92 %,
    with the tests' pinned kernels 3.27 -> 1.16 %). ``shared``: the solves made so far, by mirror choice
    (``fit.design``'s ``solves``)."""
    shared = {} if shared is None else shared
    pattern, rejected = _first_closing(d, accept)
    free = [("full", False)] if symmetry is True and d.symmetry else []
    for route, sym in [*free, ("damped", symmetry), ("from best", symmetry)]:
        if pattern is not None and d.candidates[rejected][0] <= enough:
            break
        sym = sym if d.symmetry else False
        dd = design(std, tgt, symmetry=sym, lawson_route=route, solves=shared.setdefault(sym, {}))
        pd, rd = _first_closing(dd, accept)
        if pd is not None and (pattern is None or dd.candidates[rd][0] < d.candidates[rejected][0]):
            d, pattern, rejected = dd, pd, rd
    return d, pattern, rejected


def _nearest(tries: dict, accept: Callable[[Pattern], bool]):
    """``(name, design, pattern, rejected)`` of the design whose first accepted candidate is nearest the
    target (the first design, with no pattern, when none has one)."""
    best = None
    for name, d in tries.items():
        pattern, k = _first_closing(d, accept)
        if pattern is not None and (best is None or d.candidates[k][0] < best[0]):
            best = (d.candidates[k][0], name, d, pattern, k)
    if best is None:
        name, d = next(iter(tries.items()))
        return name, d, None, len(d.candidates)
    return best[1:]


def _any(pattern: Pattern) -> bool:
    return True


def _report(d, pattern, tgt, shape, tiles, tol, tile, rejected, convex) -> dict[str, Any]:
    """The design report: solve figures, conformance and the shape verdict."""
    measured = conf.deployed(pattern.nodes, pattern.topology, tgt)
    rel = d.max_equality  # normalised units: already relative to the tile size
    return {
        "status": "converged" if d.converged and rel <= tol else "unconverged",
        "max_equality_residual": rel,
        "tol": tol,
        "iterations": d.iterations,
        "symmetry": list(d.symmetry),
        "min_gap_deg": d.min_gap_deg,
        "min_tile_quality": d.min_quality,
        "hausdorff_trace": list(d.hausdorff_trace),
        "candidates_rejected": rejected,
        "convex_holes": convex,
        "max_tip_distance_mm": d.max_tip_distance_mm,
        "tile_size_mm": tile,
        "conformance": measured,
        "shape": conf.judge(measured, shape, tiles),
    }


def _standard(rows: int, cols: int, keep, tile: float) -> Pattern:
    """The standard R x C kagome, or the tiles ``keep`` of it (a lattice cut to the outline)."""
    if keep is None:
        return standard_kagome(rows, cols, tile_size=tile)
    return trimmed_kagome(rows, cols, keep, tile_size=tile)


def _check_room(
    rows: int, cols: int, limits: FabricationLimits, target, kept: int | None = None
) -> None:
    """InputError when R x C triangles (``kept`` of them when the lattice is cut to the outline) wide
    enough for ``limits`` cannot fit inside the target (the quad designer's refusal: Pál's bound is the
    equilateral triangle's area, so it is tight here)."""
    n = rows * cols if kept is None else kept
    least = smallest_size(target.size, abs(target.area), n, limits)
    if least is not None:
        w = limits.required_width_mm()
        raise InputError(
            f"{rows}x{cols} triangles each at least {w:.3g} mm wide ({limits.source}) cannot fit a "
            f"{target.size:.4g} mm {target.name}: they cover at least {pal_bound(n, w):.4g} mm² (Pál) but "
            f"the target has {abs(target.area):.4g} mm²; the smallest size that could work is ",
            Param("size", least, ".4g"),
        )


def _print_faces(standard: Pattern, limits: FabricationLimits | None) -> np.ndarray | None:
    """The face ``print`` gives each hinge before it looks at the strips (``assign_faces``: from the
    closed states' coincident hinges, the same for every design of the lattice), for the strip rows."""
    if limits is None or limits.strip_clearance_mm <= 0:
        return None
    from ..fabricate.cut.hinges import assign_faces  # the print geometry, only when printing

    std = with_contracted_states(standard)
    return assign_faces(std, std.contracted).face


def _meets(limits: FabricationLimits | None, faces) -> Callable[[Pattern], bool]:
    """Whether a candidate (mm) meets ``limits`` on the rows themselves (always, without limits)."""
    if limits is None:
        return lambda p: True
    return lambda p: bool(KF.measure(p, limits, faces)["met"])


def _first_closing(d, accept: Callable[[Pattern], bool]) -> tuple[Pattern | None, int]:
    """The design's nearest candidate that ``accept``s and whose closed states pass every check but the
    shape (a Lawson step can fold a row's end tile onto its neighbour in a closed state, which only
    contraction shows), and how many nearer ones were rejected; None when none passes. The shape is left
    out of the checks (verified without its target): only the shape check reads it, and the candidate's
    Hausdorff distance is known."""
    for k, (_, nodes) in enumerate(d.candidates):
        pattern = replace(d.pattern, nodes=nodes)
        if not accept(pattern):
            continue
        pattern = with_contracted_states(pattern)
        design = {key: v for key, v in (pattern.design or {}).items() if key != "target"}
        if not [c for c in verify_pattern(replace(pattern, design=design)).failed()]:
            return pattern, k
    return None, len(d.candidates)


def check_options(**given) -> None:
    """:class:`InputError` naming the first quad-only option given for a kagome design."""
    for key in UNSUPPORTED:
        if given.get(key):
            raise InputError(f"--{key.replace('_', '-')} is not available for kagome designs yet")


def design_kagome_pattern(
    request: PatternRequest, notify: Callable[[str], None] | None = None
) -> KagomeOutcome:
    """The kagome front door for a :class:`~.design.PatternRequest` (``fabkiri design --lattice kagome``):
    refuses the quad-only options, resolves the fabrication limits as the quad designer does, then
    :func:`design_kagome` (the target defaults to a circle; without ``tiles`` the lattice is chosen from
    the outline and cut to it, and the next lattices of the outline's aspect are designed when it misses
    the shape (:mod:`.kagome_lattices`); with ``tiles`` it is the whole block unless ``trim``)."""
    check_options(**{k: getattr(request, k) for k in UNSUPPORTED})
    target = request.target or "circle"
    # a curve: the quad front door's loaded or turned outline (api/design_turn.py)
    if not isinstance(target, str):
        raise InputError("a kagome design takes its target by name or file")
    tgt = load_target(target, request.size)
    # a lattice chosen from the outline is cut to it: cut, the circle, ellipse and heart fit nearer than
    # the whole block at every count measured (docs/kagome.md, "A lattice cut to the outline")
    trim = request.trim or request.tiles is None
    rows, cols, aspect = choose_lattice(request.tiles, tgt, trim)
    if rows >= 2 and cols >= 2:  # (smaller: refused by design_kagome, in its own words)
        size_limits.check_tiles(rows, cols, "design kagome", request.i_know)
        if notify is not None and aspect["note"]:  # a lattice refused above gets no advice
            notify(aspect["note"])
    limits, intent = request.fabrication_limits(tgt)

    def design_on(lattice: tuple[int, int]) -> KagomeOutcome:
        return design_kagome(
            *lattice,
            target,
            request.size,
            tol=request.tol,
            shape_tol=request.shape_tol,
            name=request.name,
            symmetry=SYMMETRY[request.symmetry],
            fabrication=limits,
            intent=intent,
            min_opening=request.min_opening,
            trim=trim,
        )

    out = design_on((rows, cols))
    if request.tiles is None:  # a chosen lattice that misses: the next ones of the outline's aspect
        out, aspect = KL.next_lattices(out, design_on, tgt, aspect, notify, request.i_know)
    elif trim and notify is not None and (hint := KL.next_lattice_hint(out, rows, cols, tgt)):
        notify(hint)  # a lattice the user names is kept
    out.report["aspect"] = aspect
    return out


def choose_lattice(
    tiles: tuple[int, int] | None, target: Target, trim: bool = False
) -> tuple[int, int, dict]:
    """``(rows, cols, aspect report)``: the lattice asked for, or, when none is (``tiles`` None), the one
    whose aspect suits the target (``design.kagome.aspect.suggest``; with ``trim`` the block whose cut to the
    outline keeps about as many tiles, ``design.kagome.trim.block_for``). The report's ``note`` is the one line
    to tell the user: the lattice chosen, or a warning when the asked one does not suit the target's
    aspect and a lattice of about as many tiles does (None otherwise)."""
    if tiles is None:
        fit = KA.suggest(target)
        if trim:
            fit = KA.aspect_fit(*KT.block_for(target, KA.DEFAULT_TILES), target)
        note: str | None = (
            f"kagome {fit.tiles[0]}x{fit.tiles[1]}{' (cut to the outline)' if trim else ''} chosen from "
            f"the outline: {fit.lattice:.2f} wide for 1 high, {target.name!r} {fit.target:.2f} (--tiles "
            "RxC to choose)"
        )
    else:
        rows, cols = tiles
        fit, note = KA.aspect_fit(rows, cols, target), KA.advice(rows, cols, target)
    chosen = tiles is None
    report = {"lattice": fit.lattice, "target": fit.target, "miss": fit.miss, "chosen": chosen}
    return fit.tiles[0], fit.tiles[1], {**report, "note": note}


# --symmetry: absent imposes every mirror the lattice and target share; none leaves the design free
SYMMETRY: dict[str | None, bool | str] = {None: True, "none": False, "x": "x", "y": "y"}


register_designer("kagome", design_kagome_pattern)
