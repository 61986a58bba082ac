"""Assembly-map numbers never print over one another (fabricate/map_labels.py).

The map used to draw every number at its piece's centre: on dense maps neighbours ran together ("137"
and "9" read "1379"). Each test reads the boxes of the strokes actually drawn (``stroke_boxes``) and asks
that no two meet, with a gap of a fifth of the smaller label's height between them.
"""

from __future__ import annotations

import numpy as np
import pytest
from fabkiri.fabricate import assembly as asm
from fabkiri.fabricate.map_labels import overlapping_pairs, place_labels, stroke_boxes

from ..conftest import TEMPLATES

P = TEMPLATES / "patterns"
# the README's cut and print examples (but pp-0.5's ligament sheet: one piece, no map), and the report
# example's heart cut where its pieces are densest
EXAMPLES = {
    "standard-8x8": ["cut", P / "standard-8x8.json"],
    "circle": ["cut", P / "circle-8x8-rigid.json", "--width", "300"],
    "loose": [
        "cut",
        *(P / "circle-8x8-rigid.json", "--hinge", "separate", "--layout", "nested"),
        *("--width", "300"),
    ],
    "heart-120mm": [
        "cut",
        *(
            P.parents[1] / "tests" / "data" / "heart-16x16-rigid.json",
            "--material",
            "pp-0.5",
            "--hinge",
            "tape",
        ),
        *("--width", "120"),
    ],
    "strips": [
        "print",
        *(P / "circle-8x8-rigid.json", "--scale", "3", "--style", "strips", "--marks"),
    ],
}


def _apart(texts: list[str], layout) -> list[tuple[int, int]]:
    boxes = stroke_boxes(texts, layout)
    return overlapping_pairs(boxes, grow=0.1 * float(layout.heights.min()))


def test_crowded_numbers_are_shrunk_or_moved_apart():
    # 60 numbers whose pieces all sit within 2 mm: drawn in place they would be one smudge
    rng = np.random.default_rng(3)
    anchors = rng.uniform(0, 2, (60, 2))
    texts = [str(i + 1) for i in range(60)]
    layout = place_labels(anchors, texts, 1.5)
    assert _apart(texts, layout) == []
    assert layout.moved.any() and not layout.moved[0]  # the first keeps its place
    assert (layout.heights >= 1.5 * 0.65 - 1e-12).all()  # shrunk at most to 65 %
    # the check can fail: the same numbers at their anchors overlap
    same = type(layout)(anchors, anchors, np.full(60, 1.5), np.zeros(60, bool))
    assert len(_apart(texts, same)) > 100


@pytest.mark.slow
@pytest.mark.parametrize("name", list(EXAMPLES))
def test_readme_examples_maps_have_no_overlapping_numbers(name, monkeypatch, run_cli, tmp_path):
    calls = []
    real = asm.map_png

    def spy(*args, **kwargs):
        calls.append((args, kwargs))
        return real(*args, **kwargs)

    monkeypatch.setattr(asm, "map_png", spy)
    code, _, err = run_cli(*EXAMPLES[name], "-o", tmp_path / "out")
    assert code == 0, err
    assert calls and (tmp_path / "out" / "assembly.png").is_file()
    for args, kwargs in calls:
        faces = kwargs.get("faces", ("T", "B"))
        labels = asm.map_labels(args[0], args[1], args[2], faces)
        assert sum(len(t) for t, _ in labels.values()) == len(args[1])  # every piece has its number
        for face, (texts, layout) in labels.items():
            assert _apart(texts, layout) == [], (name, face)
