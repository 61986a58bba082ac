"""The built-in print styles' rules: what each prints, what its hinges ask of the tiles in ``design``
(``limits``) and how ``--scale auto``, ``design`` and ``info`` size it (``plan``), registered by name.

Their building and checks are one module each (:mod:`.strips`, :mod:`.tiles_and_strips`,
:mod:`.pinned`), imported at their first call (:func:`~..job.built_by`): a design sizes every style
for its fabricability summary and loads none of the solids.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from ...design_limits import strip_limits
from ...planrules import PIN_PLAN, STRIP_PLAN
from ..job import PrintStyle, built_by, register_style

if TYPE_CHECKING:
    from ..printers import Printer

_HERE = "fabkiri.fabricate.print.styles."


def pin_limits(printer: Printer) -> dict:
    """What pins ask of the tiles (``design --style pinned``): pivots far enough apart for two ears."""
    hollow = printer.pin.ear_radius_mm + printer.radial_clearance_mm
    return {"hinge_spacing_mm": 2.0 * hollow + 2.0 * printer.nozzle_mm}


def _style(name: str, module: str, **rules) -> PrintStyle:
    """The built-in style ``name``, built by ``module``'s ``build`` and ``clearances``; its ``tiles``,
    ``advise`` and ``checks``, where ``rules`` has them, are the functions of ``module`` they name."""
    at = _HERE + module
    for role in ("tiles", "advise", "checks"):
        if role in rules:
            rules[role] = built_by(at, rules[role])
    return register_style(
        PrintStyle(name, built_by(at, "build"), built_by(at, "clearances"), **rules)
    )


STRIPS = _style("strips", "strips", loose_strips=True, limits=strip_limits, plan=STRIP_PLAN)
TILES_AND_STRIPS = _style(
    "tiles-and-strips",
    "tiles_and_strips",
    tiles="tiles",
    checks="layout_checks",
    body_per_material=True,
    has_layout=True,
    limits=strip_limits,
    plan=STRIP_PLAN,
)
PINNED = _style(
    "pinned",
    "pinned",
    tiles="tiles",
    advise="pinned_advice",
    checks="pinned_checks",
    own_tile_thickness=True,
    strip_hinges=False,
    limits=pin_limits,
    plan=PIN_PLAN,
)
