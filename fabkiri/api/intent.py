"""What a design was made for: the defaults ``cut`` and ``print`` take from a pattern (apart from
:mod:`.cut`, so that ``print`` reads them without loading the cutter and its SVG writer)."""

from __future__ import annotations

from ..pattern.model import Pattern


def design_intent(pattern: Pattern, key: str):
    """What the design was made for (``design.options.fabrication``): the defaults of ``cut``/``print``."""
    fabrication = ((pattern.design or {}).get("options") or {}).get("fabrication") or {}
    return fabrication.get(key)
