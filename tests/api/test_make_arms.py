"""Arms too narrow for a strip's tiles are a lower bound on the sizes ``make`` designs at
(:mod:`fabkiri.api.maker_arms`): the size asked is skipped, the larger sizes of its ladder start above
the bound, and no size is named that was not designed and met. The designs are stubbed (cheap)."""

from __future__ import annotations

from pathlib import Path

import fabkiri
import pytest
from fabkiri.api import maker, maker_design, maker_options
from fabkiri.api.maker_arms import arm_width_mm
from fabkiri.api.maker_design import arms_of
from fabkiri.api.maker_once import StepRun
from fabkiri.design.targets.lookup import load_target

LETTER_L = str(Path(__file__).resolve().parents[1] / "data" / "letter-l.csv")


def test_the_letter_ls_arm_is_its_bar_width():
    # the L's bars are 25 mm wide at 100 mm (a 60 x 100 mm outline), and the width scales with the size
    assert arm_width_mm(load_target(LETTER_L, 100)) == pytest.approx(25.0, abs=0.3)
    assert arm_width_mm(load_target(LETTER_L, 200)) == pytest.approx(50.0, abs=0.6)
    # a disc has no arm narrower than itself
    assert arm_width_mm(load_target("circle", 100)) == pytest.approx(100.0, abs=0.2)


def _missing(designed):
    def design(result, plan, say):  # every design misses by 3x the tolerance, recorded
        designed.append((plan.process, plan.printer, plan.size))
        result.figures = {"hausdorff_rel": 0.06, "shape_tol_rel": 0.02}
        return StepRun(False, 1, "shape missed", {}, [])

    return design


def test_make_designs_no_size_whose_arms_are_too_narrow_and_names_none_unmet(monkeypatch):
    # the L's 25 mm bar at 100 mm holds 4 tiles of 6.25 mm, under prusa-mk4's 8.70 mm: no count meets
    # there (docs/maker-kit.md), nor at 130 mm (8.1 mm); the ladder's first size past the bound is 150 mm
    designed: list[tuple] = []
    monkeypatch.setattr(maker_design, "_design", _missing(designed))
    monkeypatch.setattr(maker_options, "options", lambda plan: [])  # the ladder alone
    result = fabkiri.make(LETTER_L, size=100, printer="prusa-mk4")
    assert not result.ok and result.exit_code == 1 and result.pattern is None
    assert designed == [("print", "prusa-mk4", 150.0)]
    assert result.alternatives == []
    details = result.steps[0].details
    assert any(d.startswith("130 mm not designed: at 130 mm the letter-l's arms") for d in details)
    assert "no larger size or option designed here made it: no size is named" in details


def test_the_bound_is_the_processs_own_and_leaves_the_users_tiles_alone():
    plan = maker._plan(LETTER_L, 100, None, None, "prusa-mk4", None, None, "2%", None, None)
    arms = arms_of(plan)
    assert arms is not None and arms.arm_mm / arms.across < arms.need_mm == pytest.approx(
        8.7, abs=0.05
    )
    # a cut's thinnest feature (card-0.3: 4.1 mm) fits 4 times across the same arm: designed as before
    cut = maker._plan(LETTER_L, 100, "card-0.3", None, None, None, None, "2%", None, None)
    assert arms_of(cut) is None
    # tiles the user named are designed as asked
    given = maker._plan(LETTER_L, 100, None, None, "prusa-mk4", None, (4, 4), "2%", None, None)
    assert arms_of(given) is None


def test_an_early_refusal_designs_no_size_whose_arms_are_too_narrow(monkeypatch):
    # 4x4 tiles of the L at 80 mm are 8.2 mm, under prusa-mk4's 8.70 mm: refused before any design; by the
    # tile estimate 4x4 is wide enough from 90 mm, but there the 22.5 mm bar holds 4 tiles of 5.6 mm: the
    # size make designs is the first (10 mm steps) whose bar holds them, 140 mm, and nothing unmet is named
    designed: list[tuple] = []
    monkeypatch.setattr(maker_design, "_design", _missing(designed))
    monkeypatch.setattr(maker_options, "options", lambda plan: [])
    result = fabkiri.make(LETTER_L, size=80, printer="prusa-mk4")
    assert result.exit_code == 1 and result.alternatives == []
    assert designed == [("print", "prusa-mk4", 140.0)]
    why, details = result.steps[0].figures, result.steps[0].details
    assert "4x4 would be from about 90 mm (the same estimate; no size was checked)" in why
    assert "--size" not in why
    assert any(
        d.startswith("140 mm, where make chooses") and "arms hold 4 tiles" in d for d in details
    )
    assert "no size or option designed here made it: no size is named" in details


def test_an_early_refusal_does_not_design_the_count_make_would_skip_for_its_arms(monkeypatch):
    # 8x8 asked of the L at 100 mm: make's own count there (4x4) is not designed, its bar being too narrow
    # (as make alone would skip 100 mm); the 8x8 at 170 mm, where the bar holds 4 tiles, is
    designed: list[tuple] = []
    monkeypatch.setattr(maker_design, "_design", _missing(designed))
    monkeypatch.setattr(maker_options, "options", lambda plan: [])
    result = fabkiri.make(LETTER_L, size=100, printer="prusa-mk4", tiles=(8, 8))
    assert designed == [("print", "prusa-mk4", 170.0)]
    assert any(
        d.startswith("4x4 tiles at 100 mm (make's choice there): not designed: at 100 mm")
        for d in result.steps[0].details
    )


@pytest.mark.parametrize(
    "how, tiles, warned",
    [
        (("--printer", "prusa-mk4"), "4x4", True),  # 10.3 mm tiles, but the 25 mm bar holds 6.2 mm
        (("--material", "card-0.3"), "4x4", False),  # the card's 4.1 mm feature: 4 fit across
        (("--printer", "prusa-mk4"), "8x8", False),  # refused up front for the tiles (print_tiles)
    ],
)
def test_design_for_a_process_says_before_solving_that_the_arms_are_too_narrow(
    monkeypatch, run_cli, tmp_path, how, tiles, warned
):
    from fabkiri.api import designers
    from fabkiri.errors import InputError

    def stub(request, notify):  # reached after the warning: no solve
        raise InputError("stub reached")

    monkeypatch.setattr(designers, "designer", lambda kind: stub)
    args = ("design", "--tiles", tiles, "--target", LETTER_L, "--size", "100", *how)
    _, _, err = run_cli(*args, "-o", tmp_path / "p.json", "--no-preview")
    line = (
        "warning: at 100 mm the letter-l's arms are about 25 mm wide (20% of its area lies in narrower "
        "parts): 4 tiles across (the fewest a strip along an arm has) would be 6.24 mm, narrower than "
        f"the 8.7 mm tile prusa-mk4 tiles-and-strips needs; make designs none of its own counts at such "
        f"a size (none met in its surveys, docs/maker-kit.md), so the {tiles} tiles given may miss the "
        "shape or not print; they are designed as given"
    )
    assert (line in err.splitlines()) == warned, err
    assert "stub reached" in err  # the warning is said before the design, which runs as asked


def test_make_designs_the_tiles_given_saying_the_arms_are_too_narrow(monkeypatch):
    designed: list[tuple] = []
    heard: list[str] = []
    monkeypatch.setattr(maker_design, "_design", _missing(designed))
    monkeypatch.setattr(maker_options, "options", lambda plan: [])
    fabkiri.make(LETTER_L, size=100, printer="prusa-mk4", tiles=(4, 4), progress=heard.append)
    assert designed[0] == ("print", "prusa-mk4", 100.0)  # as asked
    warned = [h for h in heard if h.startswith("make: warning: at 100 mm the letter-l's arms")]
    assert len(warned) == 1 and "the 4x4 tiles given may miss the shape" in warned[0]


def test_an_early_refusal_designs_no_size_past_makes_own_ladder(monkeypatch):
    # 4x4 of the L at 40 mm are 4.1 mm wide; by the estimate they are wide enough from 90 mm, where the bar
    # (22.5 mm) holds 4 tiles of 5.6 mm only; the bar holds them from 140 mm, past twice the size asked
    designed: list[tuple] = []
    monkeypatch.setattr(maker_design, "_design", _missing(designed))
    monkeypatch.setattr(maker_options, "options", lambda plan: [])
    result = fabkiri.make(LETTER_L, size=40, printer="prusa-mk4")
    assert designed == [] and result.alternatives == []
    assert any(
        d.startswith("90 mm, where the tiles asked are wide enough: not designed: at 90 mm")
        for d in result.steps[0].details
    )


def test_the_ladder_asks_no_count_of_a_size_whose_arms_are_too_narrow(monkeypatch):
    # make's count at a size is a bent strip's split for an outline with arms (seconds of CPU): a rung the
    # arms rule out is skipped before it is asked
    asked: list[float] = []
    choose = maker_design.choose_tiles

    def counting(target, *args):
        asked.append(float(target.size))
        return choose(target, *args)

    monkeypatch.setattr(maker_design, "choose_tiles", counting)
    monkeypatch.setattr(maker_design, "_design", _missing([]))
    monkeypatch.setattr(maker_options, "options", lambda plan: [])
    fabkiri.make(LETTER_L, size=100, printer="prusa-mk4")
    assert asked == [150.0]  # 130 mm (an 8.1 mm tile across the bar) is not asked


def test_make_splits_each_count_once_per_size(monkeypatch):
    # every setting of make's options asks for its count at the size; an outline with arms is split for a
    # bent strip at each count (seconds each): the hand at 120 mm on prusa-mk4 split 4 counts 26 times
    from collections import Counter

    from fabkiri.api import maker_tiles

    splits: Counter = Counter()
    split = maker_tiles.bent_strip

    def counting(target, rows, cols):
        splits[(float(target.size), rows, cols)] += 1
        return split(target, rows, cols)

    monkeypatch.setattr(maker_tiles, "bent_strip", counting)
    monkeypatch.setattr(maker_tiles, "_strips", {}, raising=False)
    monkeypatch.setattr(maker_design, "_design", _missing([]))
    fabkiri.make(LETTER_L, size=100, printer="prusa-mk4")
    assert len(splits) >= 2 and max(splits.values()) == 1, splits
