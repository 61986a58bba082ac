"""The fabricability summary asks each measure of closed state 1 once, however many presets ask it (#36)."""

from __future__ import annotations

from pathlib import Path

import pytest
from fabkiri.exchange.pattern_json import read_pattern
from fabkiri.fabricate import fabricability
from fabkiri.fabricate.cut.materials import HINGE_KINDS, available, load_material
from fabkiri.fabricate.print.printers import available_printers, load_printer
from fabkiri.pattern import thinness

DATA = Path(__file__).parents[1] / "data"


def _counted(monkeypatch, name: str, owner=thinness) -> list:
    calls: list = []
    real = getattr(owner, name)

    def count(*a, **k):
        calls.append(a[1:])
        return real(*a, **k)

    monkeypatch.setattr(owner, name, count)
    return calls


@pytest.mark.parametrize("name", ["circle-16x16-rigid.json", "heart-16x16-rigid.json"])
def test_the_summary_is_each_presets_own_answer(name):
    """Every preset's row equals what the function gives for that preset alone (no memo)."""
    p = read_pattern(DATA / name)
    out = fabricability.summary(p)
    c1 = p.contracted[1]
    for m in available():
        mat = load_material(m)
        for kind in HINGE_KINDS:
            assert out["cut"][m][kind] == fabricability.cut_minimum(c1, mat, kind).to_dict()
    for pname in available_printers():
        pr = load_printer(pname)
        for style in fabricability.PRINT_STYLES:
            alone = fabricability.print_bound(p, style, pr, 1, c1)
            assert out["print"][pr.name][style]["min_scale"] == alone.min_scale
            assert out["print"][pr.name][style]["limit"] == alone.limit


def test_the_summary_measures_each_shrink_and_the_hinge_faces_once(monkeypatch):
    p = read_pattern(DATA / "circle-16x16-rigid.json")
    want = fabricability.summary(p)
    scales = _counted(monkeypatch, "_answer", thinness.TileScales)
    tiles = _counted(monkeypatch, "__init__", thinness.TileScales)
    folds = _counted(monkeypatch, "coincident_hinges")
    assert fabricability.summary(p) == want
    assert scales and len(scales) == len(set(scales))  # one answer per (web, shrink, edge)
    assert len(tiles) == 1  # the tiles' geometry once for all of them
    assert 0 < len(folds) <= 2  # once per closed state's fold rule, not per printer
