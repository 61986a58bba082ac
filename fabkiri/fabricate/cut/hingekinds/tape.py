"""Tape hinges: the tiles cut in place, side by side, and joined with tape after cutting.

Coincident tile corners are one node of the linework, so the laser cuts each
shared edge once; tile A's corner of a hinge carries its face letter and tile
B's a chord where the tape ends. The cutting is :mod:`.tape_cut`.
"""

from __future__ import annotations

from . import HingeKind, register


class Tape(HingeKind):
    name = "tape"
    face_letter_corners = True
    tape_marks = True
    cutter = "fabkiri.fabricate.cut.hingekinds.tape_cut"


TAPE = register(Tape())
