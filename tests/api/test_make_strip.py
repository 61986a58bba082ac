"""``make`` on outlines the square lattice cannot follow (session 55): the next standard count after a far
miss (``maker_tiles.denser_tiles``) and the summary naming the lattice the design used (a bent strip of the
design step's own, ``design_strip.py``)."""

from __future__ import annotations

from types import SimpleNamespace

import pytest
from fabkiri.api import maker_tiles
from fabkiri.api.maker_once import name_lattice
from fabkiri.api.maker_result import MakeResult
from fabkiri.api.print_tiles import least_tile_mm
from fabkiri.design.targets.lookup import load_target
from fabkiri.fabricate import design_limits

from ..design.test_opening import DATA

U = str(
    DATA / "uasym.csv"
)  # the lead's asymmetric U, every corner rounded (radius 5): no sharp vertex
ELL = str(DATA / "letter-l.csv")


def _limits(target, material=None, printer=None):
    fab, _ = design_limits.resolve(material, None, printer, None, None, None, target)
    assert fab is not None
    return fab


@pytest.mark.slow  # the L's splits scored (~1 CPU s)
def test_a_far_miss_tries_the_next_count_up_at_the_size():
    ell = load_target(ELL, 100)
    card = _limits(ell, material="card-0.3")
    first = maker_tiles.choose_tiles(ell, card, card.source)
    assert (
        first.tiles == (4, 4) and first.corners is None
    )  # no strip of 16 or 36 tiles bends enough
    denser = maker_tiles.denser_tiles(ell, card, first)
    assert denser is not None and denser.count == (6, 6)
    assert (
        denser.corners is not None and denser.tiles[0] * denser.tiles[1] > 36
    )  # the strip, re-split
    feature = maker_tiles.min_feature_mm(card)
    assert denser.tile_width_mm >= maker_tiles.RETRY_COMFORT * feature
    # none once the next count's tiles would be thinner than the retry's comfort
    small = load_target(ELL, 60)
    first = maker_tiles.choose_tiles(small, card, card.source)
    assert maker_tiles.denser_tiles(small, card, first) is None


@pytest.mark.parametrize("given", [False, True])
def test_the_summary_names_the_lattice_the_design_bent(given):
    chose = maker_tiles.TilesChoice((6, 6), "the largest ...", 8.8, 4.1, given=given)
    result = MakeResult("u.csv", 100.0, "cut", "card-0.3 ligament", chose, "u")
    report = {"strip": {"tiles": [14, 4], "asked": [6, 6]}}
    result.pattern = SimpleNamespace(design={"report": report})  # type: ignore[assignment]
    name_lattice(result)
    assert result.tiles.tiles == (14, 4) and result.tiles.count == (6, 6)
    assert result.tiles.given == given
    first = result.summary()[0]
    assert "14x4 tiles" in first and "6x6 asked" in first
    assert result.to_dict()["tiles"] == [14, 4]
    # a design on the lattice asked is named as it was
    result.tiles, report["strip"] = chose, None
    name_lattice(result)
    assert result.tiles is chose


@pytest.mark.slow  # the boot's counts (~0.5 CPU s)
def test_a_near_miss_with_no_wider_count_left_tries_fewer_tiles():
    boot = load_target(str(DATA / "boot.csv"), 100)
    prusa = _limits(boot, printer="prusa-mk4")
    least = least_tile_mm("prusa-mk4", "tiles-and-strips")
    first = maker_tiles.choose_tiles(boot, prusa, prusa.source, least)
    assert first.tiles == (6, 6)
    assert maker_tiles.retry_tiles(boot, prusa, first, least) == []  # 7x7 is under the 8.7 mm tile
    [fewer] = maker_tiles.fewer_tiles(boot, prusa, first)
    assert fewer.tiles == (4, 4) and fewer.tile_width_mm > first.tile_width_mm
    smallest = maker_tiles.TilesChoice((4, 4), "", 1.0, 1.0)
    assert maker_tiles.fewer_tiles(boot, prusa, smallest) == []
