"""Mechanics of a pattern: contraction into the closed states, deployment.

The names below load on first use: a reader of one submodule (a design's fabricability summary contracts
with ``mechanics.contract``) does not load ``describe``'s report, the tube frames and the seams.
``contract`` is the function, as it always was, also once the submodule of its name is loaded.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from ..lazy import lazy_getattr, names_over_submodules

if TYPE_CHECKING:
    from .contract import (
        Contraction,
        adopt_state_labels,
        contract,
        contract_both,
        with_contracted_states,
    )
    from .info import PatternInfo, describe

_WHERE = {
    "Contraction": ".contract",
    "adopt_state_labels": ".contract",
    "contract": ".contract",
    "contract_both": ".contract",
    "with_contracted_states": ".contract",
    "PatternInfo": ".info",
    "describe": ".info",
}

__all__ = [
    "Contraction",
    "contract",
    "contract_both",
    "with_contracted_states",
    "adopt_state_labels",
    "describe",
    "PatternInfo",
]

__getattr__ = lazy_getattr(__name__, _WHERE)
names_over_submodules(__name__, ("contract",))
