"""How the verifier reads a sheet of each cut hinge kind: the verify layer's half of a hinge kind.

A hinge kind is written by its strategy in :mod:`fabkiri.fabricate.cut.hingekinds`; the verifier sits
below fabricate (it must read any file with nothing but the file and its manifest), so what it needs
to know of a kind is a :class:`HingeReading` registered here by name: how to recover the tiles from
one sheet's CUT linework, whether the kind is cut in place, and which physical checks apply. The
built-in readings are registered by :mod:`.recovery` (loaded on first use); a new kind that is to be
verified registers one more. A file without a manifest is read as :data:`PLAIN` (the kind guessed
from the linework).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING

from ..registry import Registry

if TYPE_CHECKING:
    import numpy as np

    from ..exchange.linework import Linework
    from .manifest import Allowances

PLAIN = "plain"  # no manifest: the reading is chosen from the linework itself


@dataclass(frozen=True)
class HingeReading:
    """What the verifier knows of one hinge kind.

    ``recover(linework, allowances, sheet, frame_tiles, arity) -> (polygons, how)`` gives one
    region per tile from a sheet's CUT linework (with ``closed_only``, only its closed outlines).
    ``in_place``: cut in place when the manifest names no layout. ``declared_hinges``: every hinge
    on a sheet is a feature the manifest declares (a ligament), so a hinge is present only if listed.
    ``tape_marks``: the hinges of an in-place sheet carry tape marks on the ENGRAVE layer.
    """

    name: str
    recover: Callable[[Linework, Allowances, int, np.ndarray | None, int], tuple[np.ndarray, str]]
    in_place: bool
    closed_only: bool = True
    declared_hinges: bool = False
    tape_marks: bool = False


# built-in readings, registered by the recovery module when first asked for
_READINGS: Registry[HingeReading] = Registry(
    {
        "tape": "fabkiri.verify.recovery",
        "separate": "fabkiri.verify.recovery",
        "ligament": "fabkiri.verify.recovery",
    }
)


def register_reading(r: HingeReading) -> HingeReading:
    """Add a reading to the registry (the module defining it calls this when imported)."""
    return _READINGS.add(r.name, r)


def reading(name: str) -> HingeReading | None:
    """The reading of the hinge kind ``name``; None if the verifier cannot read that kind."""
    return _READINGS.find(name)


def read_kinds() -> tuple[str, ...]:
    """The hinge kinds the verifier reads (the built-in ones first)."""
    return _READINGS.names()
