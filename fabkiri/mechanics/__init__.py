"""Mechanics of a pattern: contraction into the closed states, deployment."""

from .contract import (
    Contraction,
    adopt_state_labels,
    contract,
    contract_both,
    with_contracted_states,
)
from .info import PatternInfo, describe

__all__ = [
    "Contraction",
    "contract",
    "contract_both",
    "with_contracted_states",
    "adopt_state_labels",
    "describe",
    "PatternInfo",
]
