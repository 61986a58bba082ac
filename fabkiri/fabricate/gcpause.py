"""Pause Python's cyclic garbage collector while a large sheet is built or checked.

A 64x64 sheet allocates hundreds of thousands of short-lived strings, tuples
and arrays (label strokes, DXF/SVG text, tag tables). None of them form
reference cycles worth collecting mid-call, but every allocation burst
triggers collections that re-walk the whole heap: ~10% of the time of
``fabkiri cut`` on 64x64 (bench/cut.py). Reference counting still frees
everything as usual; the collector runs again when the call returns.
"""

from __future__ import annotations

import functools
import gc
from collections.abc import Callable
from typing import ParamSpec, TypeVar

P = ParamSpec("P")
R = TypeVar("R")


def gc_paused(fn: Callable[P, R]) -> Callable[P, R]:
    """Run ``fn`` with the cyclic GC disabled (restored afterwards, also on errors; nesting is fine)."""

    @functools.wraps(fn)
    def wrapper(*args: P.args, **kwargs: P.kwargs) -> R:
        was = gc.isenabled()
        gc.disable()
        try:
            return fn(*args, **kwargs)
        finally:
            if was:
                gc.enable()

    return wrapper
