"""The pattern model, the tessellation kinds and their standard lattices.

Pattern files are read and written by :mod:`fabkiri.exchange` (``read_pattern``, ``write_pattern``).
"""

from .kinds.quad.lattice import standard_pattern
from .model import Pattern
from .topology import FoldRule, Topology

__all__ = ["Pattern", "Topology", "FoldRule", "standard_pattern"]
