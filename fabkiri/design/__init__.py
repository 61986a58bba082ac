"""Inverse design of reconfigurable quad kirigami (algorithm spec §2-§5).

``design(DesignRequest(rows, cols, target, rigid=...))`` returns the deployed
pattern and the solver report; contraction into the closed states is left to
:mod:`fabkiri.mechanics` (this layer sits below it).
"""

from .solve import DesignRequest, DesignResult, design
from .targets import Target, load_target, named_targets

__all__ = ["DesignRequest", "DesignResult", "design", "Target", "load_target", "named_targets"]
