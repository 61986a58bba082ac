"""A lattice chosen from the outline that misses the shape: the front door designs the next lattices of the
outline's aspect and keeps the first that meets every check (api/kagome_lattices.py; docs/kagome.md "The
lattices next to the chosen one"). A lattice the user names is kept, and only the next one is named."""

from __future__ import annotations

import pytest
from fabkiri.api import kagome as AK
from fabkiri.api.design import PatternRequest
from fabkiri.design.kagome import trim as KT
from fabkiri.design.targets.lookup import load_target


def _front_door(monkeypatch, near: dict, tiles=None, trim=False):
    """``design_kagome_pattern`` on an 80 mm heart with each lattice's design faked: ``near[(R, C)]`` is
    its Hausdorff fraction (met, and valid, at most 2 %). Returns the outcome, the lattices designed and
    the notes."""
    designed: list[tuple[int, int]] = []

    def fake(rows, cols, target, size=None, **kw):
        designed.append((rows, cols))
        h = near[rows, cols]
        report = {"shape": {"status": "met" if h <= 0.02 else "missed"}}
        report["conformance"] = {"hausdorff_rel": h}
        return AK.KagomeOutcome(None, report, h <= 0.02, (rows, cols))  # type: ignore[arg-type]

    monkeypatch.setattr(AK, "design_kagome", fake)
    notes: list[str] = []
    req = PatternRequest(tiles=tiles, target="heart", size=80.0, kind="kagome", trim=trim)
    return AK.design_kagome_pattern(req, notify=notes.append), designed, notes


def test_the_chosen_lattice_and_its_next_ones_are_the_aspect_rules_order():
    assert KT.blocks_for(load_target("heart", 80.0), 66)[:3] == [(7, 14), (8, 16), (8, 15)]


def test_a_chosen_lattice_that_misses_gives_way_to_the_first_next_one_that_meets(monkeypatch):
    near = {(7, 14): 0.0323, (8, 16): 0.025, (8, 15): 0.012}
    out, designed, notes = _front_door(monkeypatch, near)
    assert designed == [(7, 14), (8, 16), (8, 15)]
    assert out.tiles == (8, 15) and out.valid
    aspect = out.report["aspect"]
    assert [t["tiles"] for t in aspect["tried"]] == [[7, 14], [8, 16], [8, 15]]
    assert [t["valid"] for t in aspect["tried"]] == [False, False, True]
    assert "3.23 %" in notes[1] and "8x16" in notes[1]  # the miss and the next lattice, said
    assert (
        aspect["note"] == notes[-1] and "8x15" in notes[-1] and "kept instead of 7x14" in notes[-1]
    )


def test_the_next_lattices_stop_at_the_first_that_meets(monkeypatch):
    out, designed, _ = _front_door(monkeypatch, {(7, 14): 0.0323, (8, 16): 0.0119})
    assert designed == [(7, 14), (8, 16)] and out.tiles == (8, 16)


def test_when_no_next_lattice_meets_the_chosen_one_is_kept(monkeypatch):
    near = {(7, 14): 0.0323, (8, 16): 0.025, (8, 15): 0.026}
    out, designed, notes = _front_door(monkeypatch, near)
    assert len(designed) == 3 and out.tiles == (7, 14)  # two next lattices at most
    assert [t["tiles"] for t in out.report["aspect"]["tried"]] == [[7, 14], [8, 16], [8, 15]]
    assert "kept 7x14" in notes[-1] and "8x16 2.50 %" in notes[-1]


def test_a_chosen_lattice_that_meets_is_the_only_design(monkeypatch):
    out, designed, notes = _front_door(monkeypatch, {(7, 14): 0.0092})
    assert designed == [(7, 14)] and "tried" not in out.report["aspect"] and len(notes) == 1


@pytest.mark.parametrize("trim", [True, False])
def test_a_lattice_the_user_names_is_kept_and_the_next_one_only_named(monkeypatch, trim):
    out, designed, notes = _front_door(monkeypatch, {(7, 14): 0.0323}, tiles=(7, 14), trim=trim)
    assert designed == [(7, 14)] and out.tiles == (7, 14)
    hints = [n for n in notes if n.startswith("hint:")]
    if trim:  # a cut lattice: the next lattice of the outline's aspect named, not designed
        assert len(hints) == 1 and "--tiles " in hints[0] and "--trim" in hints[0]
        assert "--tiles 7x14" not in hints[0]
    else:  # the whole block: its own hint (--trim) comes with the summary
        assert hints == []
