"""Argument types shared by the commands: a number parsed and range-checked, one line on refusal; the
options and the pattern reader several commands share (here, not in one command's module, so that a command
does not load another's)."""

from __future__ import annotations

import argparse
import math
from collections.abc import Callable
from typing import TYPE_CHECKING

from .. import limits
from ..pattern.tilecount import tile_count

if TYPE_CHECKING:
    from ..pattern.model import Pattern


def bounded(
    cast: Callable[[str], float], ok: Callable[[float], bool], expected: str, refused: str
) -> Callable[[str], float]:
    """An ``argparse`` type: ``cast(text)`` when ``ok`` accepts it.

    Text ``cast`` cannot read is refused as "``expected``, got 'text'"; a value ``ok`` refuses with
    ``refused``, a format string that may name the text (``{text!r}``) or the value (``{v}``).
    argparse turns either into a one-line usage error (exit 2).
    """

    def parse(text: str):
        try:
            v = cast(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"{expected}, got {text!r}") from None
        if not ok(v):
            raise argparse.ArgumentTypeError(refused.format(text=text, v=v))
        return v

    return parse


length_mm = bounded(
    float,
    lambda v: math.isfinite(v) and 0 < v <= limits.MAX_LENGTH_MM,
    "expected a length in mm",
    f"size must be a positive length up to {limits.MAX_LENGTH_MM:g} mm, " + "got {text!r}",
)
"""A length in mm: finite, positive, at most :data:`limits.MAX_LENGTH_MM` (``--size``, ``--min-feature``)."""


positive_number = bounded(
    float,
    lambda v: 0 < v < float("inf"),
    "expected a number",
    "expected a positive finite number, got {text!r}",
)
nonnegative_number = bounded(
    float,
    lambda v: 0 <= v < float("inf"),
    "expected a number",
    "expected a finite number >= 0, got {text!r}",
)


def load_any(path: str) -> Pattern:
    """A pattern from ``pattern.json`` or, by suffix, any readable format (a design ``.obj``, ...)."""
    from ..api.patterns import load_pattern  # not for `design`, which reads no pattern

    return load_pattern(path)


def parse_tiles(text: str) -> tuple[int, int]:
    """``ROWSxCOLS`` -> (rows, cols), both >= 1 (the library's :func:`~fabkiri.pattern.tilecount.tile_count`)."""
    return tile_count(text, "--tiles")


def add_i_know(p: argparse.ArgumentParser) -> None:
    """``--i-know`` (``new``, ``design``): here, not in a command's module, so that ``design`` does not load
    ``new``'s command module and what it imports."""
    p.add_argument(
        "--i-know",
        action="store_true",
        help="try a lattice larger than the largest tested (the refusal says what it would need)",
    )
