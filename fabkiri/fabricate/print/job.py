"""Print styles and their registry.

A print style turns a closed state into the bodies printed on each bed
(:class:`~.build.PrintJob`) and says how the clearances between them are measured. A
new style is one module that calls :func:`register_style` and one line in the built-in
table of :data:`_STYLES`, loaded on first use as trimesh loads its file-format handlers.
The built-in styles' rules (limits, plan rule, what they print) are one module,
:mod:`fabkiri.fabricate.print.styles.rules`; their building, one module each in
:mod:`fabkiri.fabricate.print.styles`, is loaded at its first call (:func:`built_by`).
"""

from __future__ import annotations

import importlib
from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from ...errors import FabricationError
from ...registry import Registry

# the job, the plan geometry and the solids are annotations here: a style lookup (a cut's web checks, a
# design's fabricability summary) loads none of them
if TYPE_CHECKING:
    from ...pattern.model import Pattern
    from ..planrules import PlanRule
    from .build import PrintJob, Realised, StyleChecks
    from .checks import MeshReport
    from .printers import Printer


@dataclass(frozen=True, eq=False)
class PrintStyle:
    """One way of printing a closed state (a strategy object, chosen by name).

    ``build`` makes the job; ``clearances`` measures, on the realised solids,
    the clearances between bodies that may move apart, filling a
    :class:`~.meshchecks.MeshReport`. ``tiles`` gives the solid of the printed
    tiles, the height of the section the tile check takes, and what that check
    masks out (``None``: the style prints no tiles). ``advise`` adds to a refusal
    what would make the job print (then ``build`` names the scales itself). With
    ``body_per_material`` each bed holds one body per material (one STL each; their
    overlap is their intersection). ``checks`` are the style's own checks of a
    realised job (pinned: the sweep along the deployment path; tiles-and-strips: the
    layout verifier on the printed top faces). ``own_tile_thickness``: the tiles have
    their own preset thickness, which ``--tile-thickness`` sets. ``loose_strips``: the
    strips are printed on their own and glued on by hand (assembly pieces and map; the
    tiles may be laser-cut with the pads engraved, ``print --marks``). ``strip_hinges``:
    the hinges are printed strips (the bill of materials counts them; pinned: pins).
    ``has_layout``: the job's ``layout`` (recessed or stacked strips) is the style's and
    goes in the manifest. ``limits(printer)``: what ``design --printer --style`` asks of
    every tile for this style's hinges (mm, as :func:`~.design_limits.printer_limits`).
    ``plan``: how ``--scale auto``, ``design`` and ``info`` size it (:class:`~.planrules.PlanRule`:
    its plan check, closed-form bound and the preset fields they read).
    """

    name: str
    build: Callable[[Pattern, int, Printer], PrintJob]
    clearances: Callable[[Realised, MeshReport], None]
    tiles: Callable[..., tuple[Any, float, Any]] | None = None
    advise: Callable[[Pattern, int, Printer, float], str] | None = None
    body_per_material: bool = False
    checks: Callable[[Pattern, Realised, MeshReport], StyleChecks] | None = None
    own_tile_thickness: bool = False
    loose_strips: bool = False
    strip_hinges: bool = True
    has_layout: bool = False
    limits: Callable[[Printer], dict] | None = None
    plan: PlanRule | None = None


def built_by(module: str, name: str) -> Callable[..., Any]:
    """The function ``name`` of ``module``, imported at its first call: a built-in style's building,
    which its rules (what a design asks) never need."""

    def call(*args: Any, **kwargs: Any) -> Any:
        return getattr(importlib.import_module(module), name)(*args, **kwargs)

    call.__qualname__ = call.__name__ = name
    return call


# built-in styles' rules, imported when first asked for (the module calls register_style())
_STYLES: Registry[PrintStyle] = Registry(
    dict.fromkeys(("strips", "tiles-and-strips", "pinned"), "fabkiri.fabricate.print.styles.rules")
)
STYLES = tuple(_STYLES.builtin)


def register_style(style: PrintStyle) -> PrintStyle:
    """Add a style to the registry (a style's module calls this when it is imported)."""
    return _STYLES.add(style.name, style)


def print_style(name: str) -> PrintStyle:
    """The registered style of this name, or :class:`FabricationError` naming the known ones."""
    found = _STYLES.find(name)
    if found is None:
        known = ", ".join(_STYLES.names())
        raise FabricationError(f"unknown print style {name!r}; choose one of {known}")
    return found
