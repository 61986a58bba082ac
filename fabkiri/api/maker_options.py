"""What ``make`` names when its design misses the shape and neither its retries nor a larger size make it.

The options are the other ways ``make`` could be asked to make this outline at this size: other tile
counts of the same process, the other styles (hinge kinds) of the same printer (material), the other
printers (materials), and the other process (cutting for a print, printing for a cut). Each is an
:class:`Option`: the process, the tiles and how much room the tiles leave the process's thinnest
feature (``slack``: the estimated tile width over that feature). :func:`ranked` orders them without
designing anything: an option no looser than a design that already missed (no more tiles and no more
slack, :func:`dominated`) is dropped; when the missed design had no fabrication row active its miss
came from the tile count alone, so only options whose count is likely to close it are kept
(:func:`predicted_miss`); the rest go the user's own process first, then by slack (the design's
fabrication rows bind least where the slack is largest: likelier to meet, and cheaper).

:func:`search` then runs them as ``make`` would (design, cut or print, deploy, on a scratch result,
nothing written), most likely first, at most :data:`MAX_RUNS` designs and no new one once they cost
:data:`BUDGET` times the first design, and names the first that passes every step as its exact
``fabkiri make`` line (a count of the user's own process, with tiles ``make`` chose, is adopted as the
design instead: that is what the user asked for).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace
from typing import Any

from ..design.quad.fabrication import smallest_size
from ..design.targets.lookup import load_target
from ..errors import FabkiriError
from ..fabricate import design_limits
from ..fabricate.cut.materials import HINGE_KINDS, available
from ..fabricate.fabricability import PRINT_STYLES
from ..fabricate.print.printers import available_printers
from .maker_tiles import (
    RETRY_COMFORT,
    STANDARD_TILES,
    TilesChoice,
    choose_tiles,
    min_feature_mm,
    tile_width_mm,
)
from .print_tiles import least_tile_mm

Progress = Callable[[str], None]
COUNTS = tuple(sorted({*STANDARD_TILES, 10}))  # N x N counts an option may name with --tiles
MAX_RUNS = 2  # designs run for options after the retries and the larger size (each a whole design)
BUDGET = 3.0  # no new option's design once they cost this many times the first design's CPU s
# group, process, material, hinge, printer, style
Setting = tuple[int, str, str | None, str | None, str | None, str | None]
GROUPS = (
    "this process, another tile count",
    "this preset, another style or hinge kind",
    "this process, another preset",
    "the other process",
)


@dataclass(frozen=True)
class Tried:
    """A design that missed: its tile count, its slack and its miss (Hausdorff over the tolerance)."""

    n_tiles: int
    slack: float
    miss: float
    rows_active: bool = True


@dataclass(frozen=True)
class Option:
    """One way to make the outline at this size: ``process`` ``cut`` (``material``, ``hinge``) or
    ``print`` (``printer``, ``style``), on ``tiles`` (``auto``: ``make``'s own choice there, named
    without ``--tiles``); ``group`` indexes :data:`GROUPS`; ``slack`` the estimated tile width over
    the process's thinnest feature."""

    process: str
    material: str | None
    hinge: str | None
    printer: str | None
    style: str | None
    tiles: TilesChoice
    auto: bool
    group: int
    slack: float

    @property
    def n_tiles(self) -> int:
        return self.tiles.tiles[0] * self.tiles.tiles[1]

    @property
    def name(self) -> str:
        how = (
            f"{self.material} {self.hinge}"
            if self.process == "cut"
            else f"{self.printer} {self.style}"
        )
        return f"{how} at {'x'.join(map(str, self.tiles.tiles))}"


def dominated(option: Option, tried: Sequence[Tried]) -> bool:
    """Whether a design that missed had at least the option's tiles and at least its slack: the option
    asks for no more of the design than one that already failed."""
    return any(t.n_tiles >= option.n_tiles and t.slack >= option.slack * (1 - 1e-9) for t in tried)


def predicted_miss(option: Option, first: Tried) -> float:
    """The miss expected at the option's count when the count alone binds: Hausdorff ~ one tile's
    width, which falls as one over the tiles per side."""
    return first.miss * math.sqrt(first.n_tiles / option.n_tiles)


def ranked(options: Sequence[Option], tried: Sequence[Tried]) -> list[Option]:
    """The options worth a design, likeliest first (the rules of the module docstring); one per
    preset and group (its most slack), so a refusal does not try near-identical designs in turn.
    ``tried``: the misses, the run's own first (none: a design that met, refused by cut or print)."""
    keep = [o for o in options if not dominated(o, tried)]
    if tried and not tried[0].rows_active:  # the count alone missed: counts likely to close it
        keep = [o for o in keep if predicted_miss(o, tried[0]) <= 1.0]
    keep.sort(key=lambda o: (o.group, -o.slack, o.n_tiles))
    seen: set[tuple[int, str | None, bool]] = set()
    out = []
    for o in keep:
        key = (o.group, o.material or o.printer, o.group == 0 and o.auto)
        if o.group != 0 and key in seen:
            continue
        seen.add(key)
        out.append(o)
    return out


def _settings(plan) -> list[Setting]:
    """Every (group, process, material, hinge, printer, style) make could be asked for, the plan's
    own first: group 0 the plan's, 1 its preset's other styles or hinge kinds, 2 the process's other
    presets, 3 the other process."""
    own_cut = plan.process == "cut"
    cuts = [(m, h) for m in (plan.material, *available()) if m for h in HINGE_KINDS]
    prints = [(p, s) for p in (plan.printer, *available_printers()) if p for s in PRINT_STYLES]
    out: list[Setting] = []
    for m, h in dict.fromkeys(cuts):
        group = (0 if h == plan.hinge else 1) if m == plan.material else (2 if own_cut else 3)
        out.append((group, "cut", m, h, None, None))
    for p, s in dict.fromkeys(prints):
        group = (0 if s == plan.style else 1) if p == plan.printer else (3 if own_cut else 2)
        out.append((group, "print", None, None, p, s))
    return out


def options(plan) -> list[Option]:
    """Every option at the plan's size, unranked: for each setting of :func:`_settings`, the count
    make would choose there and the larger counts of :data:`COUNTS` whose tiles stay
    :data:`~.maker_tiles.RETRY_COMFORT` times the feature and pass the design's room check."""
    target = load_target(plan.target, plan.size)
    out = []
    for group, process, material, hinge, printer, style in _settings(plan):
        try:
            fab, _ = design_limits.resolve(material, hinge, printer, style, None, None, target)
        except FabkiriError:  # a hinge kind the material cannot have, a style the printer lacks
            continue
        assert fab is not None
        feature = min_feature_mm(fab)
        least = least_tile_mm(printer, str(style)) if printer else 0.0
        auto = choose_tiles(target, fab, fab.source, least)
        counts = [auto.tiles] + [(n, n) for n in COUNTS if n * n > auto.tiles[0] * auto.tiles[1]]
        for tiles in dict.fromkeys(counts):
            n = tiles[0] * tiles[1]
            w = tile_width_mm(target, n)
            is_auto = tiles == auto.tiles
            if (not is_auto and w < RETRY_COMFORT * feature) or w < least:
                continue  # a count make would refuse up front (print_tiles) is no option either
            if smallest_size(target.size, abs(target.area), n, fab) is not None:
                continue
            why = f"tiles about {w:.3g} mm wide, {w / feature:.2g}x the {feature:.3g} mm {fab.source} needs"
            choice = auto if is_auto else TilesChoice(tiles, why, w, feature)
            out.append(
                Option(
                    process, material, hinge, printer, style, choice, is_auto, group, w / feature
                )
            )
    return out


def tried_of(plan, attempts: Sequence[Any]) -> list[Tried]:
    """The designs of the plan's process that missed (``maker_design._Attempt`` s, each at its own
    size), as :class:`Tried`; the slack measured as :func:`options` measures it."""
    out = []
    for a in attempts:
        if (
            a.miss is None or a.miss <= 1
        ):  # met the shape (a step after it failed): no miss to rule by
            continue
        target = load_target(plan.target, a.size or plan.size)
        fab, _ = design_limits.resolve(
            plan.material, plan.hinge, plan.printer, plan.style, None, None, target
        )
        assert fab is not None
        n = a.tiles.tiles[0] * a.tiles.tiles[1]
        slack = tile_width_mm(target, n) / min_feature_mm(fab)
        out.append(Tried(n, slack, a.miss, bool(a.figures.get("rows_active", True))))
    return out


def plan_of(plan, option: Option):
    """The make plan of ``option`` (the same target, size, tolerance and floor)."""
    return replace(
        plan,
        process=option.process,
        material=option.material,
        hinge=option.hinge,
        printer=option.printer,
        style=option.style,
        tiles=option.tiles,
        fabrication=f"{option.material} {option.hinge}"
        if option.process == "cut"
        else f"{option.printer} {option.style}",
    )


def tag(plan, option: Option) -> str:
    """What names an option's output folder beside the run's: the preset and style or hinge kind when
    they differ from the run's (nothing for another count of the same process)."""
    if option.group == 0:
        return ""
    if option.process == "cut":
        return f"{option.material}-{option.hinge}"
    return f"{option.printer}-{option.style}"


def limit_text() -> str:
    return (
        f"at most {MAX_RUNS} designs, and none once they cost {BUDGET:g}x the first design's CPU s"
    )
