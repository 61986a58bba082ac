"""Library front doors: one call per task, the policy the CLI commands used to hold.

This layer sits above ``render`` and below ``cli`` (and ``sweep``): a front door
may use every lower layer; the CLI only parses arguments, calls it and prints.

The names below load on first use: ``fabkiri cut`` and ``print`` import their own front door
(``fabkiri.api.cut``, ``fabkiri.api.print``), not the design solver behind ``design_pattern``.
The top-level doors over these (``fabkiri.design``, ``fabkiri.cut``, ...) are in :mod:`.front` and
:mod:`.front_fabricate`, their results in :mod:`.results`.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from ..lazy import lazy_getattr

if TYPE_CHECKING:
    from .cut import CutOutcome, cut_files, cut_material
    from .deploy import DeployOutcome, deploy_pattern
    from .design import DesignOutcome, PatternRequest, design_pattern
    from .designers import design_by_kind
    from .maker import make
    from .maker_result import MakeResult
    from .patterns import export_pattern, import_pattern, load_pattern
    from .print import PrintOptions, PrintOutcome, print_pattern

_WHERE = {
    "CutOutcome": ".cut",
    "cut_files": ".cut",
    "cut_material": ".cut",
    "DeployOutcome": ".deploy",
    "deploy_pattern": ".deploy",
    "design_by_kind": ".designers",
    "export_pattern": ".patterns",
    "import_pattern": ".patterns",
    "load_pattern": ".patterns",
    "PrintOptions": ".print",
    "PrintOutcome": ".print",
    "print_pattern": ".print",
    "DesignOutcome": ".design",
    "PatternRequest": ".design",
    "design_pattern": ".design",
    "make": ".maker",
    "MakeResult": ".maker_result",
}

__all__ = [
    "CutOutcome",
    "DeployOutcome",
    "DesignOutcome",
    "MakeResult",
    "PatternRequest",
    "PrintOptions",
    "PrintOutcome",
    "cut_files",
    "cut_material",
    "deploy_pattern",
    "design_by_kind",
    "design_pattern",
    "export_pattern",
    "import_pattern",
    "load_pattern",
    "make",
    "print_pattern",
]

__getattr__ = lazy_getattr(__name__, _WHERE)
