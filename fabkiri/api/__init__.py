"""Library front doors: one call per task, the policy the CLI commands used to hold.

This layer sits above ``render`` and below ``cli`` (and ``sweep``): a front door
may use every lower layer; the CLI only parses arguments, calls it and prints.
"""

from .design import DesignOutcome, PatternRequest, design_pattern
from .maker import make
from .maker_result import MakeResult

__all__ = ["DesignOutcome", "MakeResult", "PatternRequest", "design_pattern", "make"]
