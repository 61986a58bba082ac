"""File formats, read and written: one module per format, and one registry naming them all.

Pattern files: ``pattern.json`` (:mod:`.pattern_json`), Wavefront OBJ (:mod:`.obj`), FOLD
(:mod:`.fold`), PyKirigami model folders (:mod:`.pykirigami`). Cut drawings: DXF (:mod:`.dxf`),
SVG (:mod:`.svg`), over the shared in-memory sheet (:mod:`.drawing`) and the linework they read
back (:mod:`.linework`). The registry (:mod:`.file_formats`) names these and the print formats
3MF, STL and STEP, whose modules live in ``fabricate/print``.

The names below are the stable way in (loaded on first use, PEP 562)::

    from fabkiri.exchange import read_pattern, write_pattern, loads, dumps
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from ..lazy import lazy_getattr

if TYPE_CHECKING:
    from .file_formats import (
        file_format,
        format_names,
        format_of,
        known_formats,
        pattern_format,
        read_cut_file,
        register_format,
    )
    from .obj import import_obj, obj_text, write_obj
    from .pattern_json import dumps, loads, read_pattern, write_pattern

_WHERE = {
    "dumps": ".pattern_json",
    "loads": ".pattern_json",
    "read_pattern": ".pattern_json",
    "write_pattern": ".pattern_json",
    "import_obj": ".obj",
    "obj_text": ".obj",
    "write_obj": ".obj",
    "file_format": ".file_formats",
    "format_names": ".file_formats",
    "format_of": ".file_formats",
    "known_formats": ".file_formats",
    "pattern_format": ".file_formats",
    "read_cut_file": ".file_formats",
    "register_format": ".file_formats",
}

__all__ = [
    "dumps",
    "file_format",
    "format_names",
    "format_of",
    "import_obj",
    "known_formats",
    "loads",
    "obj_text",
    "pattern_format",
    "read_cut_file",
    "read_pattern",
    "register_format",
    "write_obj",
    "write_pattern",
]

__getattr__ = lazy_getattr(__name__, _WHERE)
