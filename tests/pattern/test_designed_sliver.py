"""A designed pattern no reader takes is refused, not written (``limits.check_designed``): as bad input where
the target is too small for its tiles, as a failed design where one tile was squeezed to a sliver among tiles
of a sane size (the drop's point at 96x96 tiles, 100 mm: a 0.87 um edge among edges of about a millimetre)."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from fabkiri.errors import CheckFailed, InputError
from fabkiri.limits import check_designed
from fabkiri.pattern.kinds.quad.lattice import standard_pattern


def _with_sliver(tile_mm: float):
    sp = standard_pattern(4, 4, tile_size=tile_mm)
    nodes = np.array(sp.nodes, dtype=float)
    a, b = sp.tiles[5][0], sp.tiles[5][1]
    nodes[a] = nodes[b] + (nodes[a] - nodes[b]) * (5e-4 / np.linalg.norm(nodes[a] - nodes[b]))
    return dataclasses.replace(sp, nodes=nodes)


def test_a_sliver_among_millimetre_tiles_is_a_failed_design():
    with pytest.raises(CheckFailed, match="sliver among edges of"):
        check_designed(_with_sliver(1.0))


def test_tiles_all_under_a_tenth_of_a_millimetre_are_a_target_too_small():
    with pytest.raises(InputError, match="--size|size"):
        check_designed(_with_sliver(0.02))


def test_a_sane_design_passes():
    check_designed(standard_pattern(4, 4, tile_size=1.0))
