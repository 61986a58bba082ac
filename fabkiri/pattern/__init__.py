"""The pattern model, the standard lattice and pattern file I/O."""

from .io import dumps, import_obj, loads, obj_text, read_pattern, write_obj, write_pattern
from .lattice import standard_pattern
from .model import Pattern
from .topology import FoldRule, Topology

__all__ = [
    "Pattern",
    "Topology",
    "FoldRule",
    "standard_pattern",
    "read_pattern",
    "write_pattern",
    "loads",
    "dumps",
    "import_obj",
    "obj_text",
    "write_obj",
]
