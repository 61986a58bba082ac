"""Library front doors: one call per task, the policy the CLI commands used to hold.

This layer sits above ``render`` and below ``cli`` (and ``sweep``): a front door
may use every lower layer; the CLI only parses arguments, calls it and prints.

The names below load on first use: ``fabkiri cut`` and ``print`` import their own front door
(``fabkiri.api.cut``, ``fabkiri.api.print``), not the design solver behind ``design_pattern``.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from ..lazy import lazy_getattr

if TYPE_CHECKING:
    from .design import DesignOutcome, PatternRequest, design_pattern
    from .maker import make
    from .maker_result import MakeResult

_WHERE = {
    "DesignOutcome": ".design",
    "PatternRequest": ".design",
    "design_pattern": ".design",
    "make": ".maker",
    "MakeResult": ".maker_result",
}

__all__ = ["DesignOutcome", "MakeResult", "PatternRequest", "design_pattern", "make"]

__getattr__ = lazy_getattr(__name__, _WHERE)
