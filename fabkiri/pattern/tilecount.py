"""A lattice's tile count given as plain values: ``"8x8"``, ``"8 x 12"``, ``(8, 12)`` or ``[8, 12]``.

Every library door that takes ``tiles`` reads it here, so a notebook can write the count as the CLI's
``--tiles`` does or as a pair of numbers, and a bad one is refused in one sentence.
"""

from __future__ import annotations

import re
from numbers import Integral
from typing import Any

from ..errors import InputError

_TEXT = re.compile(r"\s*(\d+)\s*[xX×]\s*(\d+)\s*")


def tile_count(value: Any, what: str = "tiles") -> tuple[int, int]:
    """``(rows, cols)`` from ``"RxC"`` text or a pair of whole numbers, each at least 1; anything else
    raises :class:`~fabkiri.errors.InputError` naming ``what``."""
    if isinstance(value, str):
        m = _TEXT.fullmatch(value)
        pair: tuple[Any, ...] = (int(m.group(1)), int(m.group(2))) if m else ()
    elif isinstance(value, tuple | list) and len(value) == 2:
        pair = tuple(value)
    else:
        pair = ()
    if len(pair) != 2 or not all(_whole(v) for v in pair):
        raise InputError(
            f"{what} expects 'ROWSxCOLS' such as '8x8' or a (rows, cols) pair, got {value!r}"
        )
    rows, cols = int(pair[0]), int(pair[1])
    if rows < 1 or cols < 1:
        raise InputError(f"{what} needs at least one row and one column, got {rows}x{cols}")
    return rows, cols


def _whole(v: Any) -> bool:
    """A whole number that is not a bool (``True`` is an int in Python, not a tile count)."""
    return isinstance(v, Integral) and not isinstance(v, bool)


class TakesTiles:
    """A request dataclass whose ``tiles`` may also be given as ``"RxC"`` text or a list: read into
    ``(rows, cols)`` as the request is made (None stays None: the kind chooses)."""

    tiles: Any

    def __post_init__(self) -> None:
        if self.tiles is not None:
            self.tiles = tile_count(self.tiles)
