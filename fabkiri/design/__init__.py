"""Inverse design of reconfigurable quad kirigami.

The method: docs/algorithm.md#constraints through docs/algorithm.md#solver.

``design(DesignRequest(rows, cols, target, rigid=...))`` returns the deployed
pattern and the solver report; contraction into the closed states is left to
:mod:`fabkiri.mechanics` (this layer sits below it).

The names below load on first use: a reader of one submodule (``cut`` and ``print`` measure a stored
target with ``design.conformance``) does not load the solver.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from ..lazy import lazy_getattr

if TYPE_CHECKING:
    from .quad.solve import DesignRequest, DesignResult, design
    from .targets.lookup import Target, load_target, named_targets

_WHERE = {
    "DesignRequest": ".quad.solve",
    "DesignResult": ".quad.solve",
    "design": ".quad.solve",
    "Target": ".targets.lookup",
    "load_target": ".targets.lookup",
    "named_targets": ".targets.lookup",
}

__all__ = ["DesignRequest", "DesignResult", "design", "Target", "load_target", "named_targets"]

__getattr__ = lazy_getattr(__name__, _WHERE)
