"""``exchange.indented``: the text of ``json.dumps(indent=2, sort_keys=True)``, and a pattern file written without
the standard library's Python encoder."""

from __future__ import annotations

import json
import random

import pytest
from fabkiri.exchange.indented import indented
from fabkiri.exchange.pattern_json import dumps, read_pattern

from ..conftest import TEMPLATES

SCALARS = [
    0.1,
    -0.0,
    5e-324,
    1e300,
    1e-05,
    float("nan"),
    float("inf"),
    -float("inf"),
    0,
    -7,
    2**70,
    True,
    False,
    None,
    "",
    "é",
    'a "b"',
    "[1, 2]",
    "x\ny",
]


def _value(rnd: random.Random, depth: int = 0):
    """A random plain JSON value: nested dicts and lists, lists of numbers and of lists of numbers, empties."""
    kind = rnd.randrange(7 if depth < 4 else 1)
    if kind == 0:
        return rnd.choice(SCALARS + [rnd.uniform(-1e3, 1e3), rnd.randrange(-999, 999)])
    if kind == 1:
        return [rnd.uniform(-5, 5) for _ in range(rnd.randrange(0, 5))]
    if kind == 2:
        return [
            [rnd.uniform(-5, 5) for _ in range(rnd.randrange(0, 3))]
            for _ in range(rnd.randrange(4))
        ]
    if kind == 3:
        return [[[1.5, -2]] * 2, [3.25]] if rnd.random() < 0.5 else [[1, [2]], [3]]
    if kind == 4:
        return tuple(_value(rnd, depth + 1) for _ in range(rnd.randrange(3)))
    if kind == 5:
        return [_value(rnd, depth + 1) for _ in range(rnd.randrange(4))]
    keys = ["b", "a", "é", "1", "[]", "z"]
    return {rnd.choice(keys) + str(i): _value(rnd, depth + 1) for i in range(rnd.randrange(5))}


def test_the_text_of_json_dumps_indented_sorted():
    rnd = random.Random(50)
    for _ in range(3000):
        v = _value(rnd)
        assert indented(v) == json.dumps(v, indent=2, sort_keys=True), v


@pytest.mark.parametrize(
    "v",
    [
        [1.0, 2, -3e-07],
        [[1.0, 2.0], [3.0, 4.0]],
        [[1.0], [2.0, 3.0], [4.0, 5.0, 6.0]],
        [[1.0, 2.0], 3.0, [4.0]],  # numbers beside lists
        [1.0, [2.0, 3.0], 4.0],
        [[[1.0]], [[2.0]]],
        [[1.0, []], [2.0]],
        [[1.0, True], [2.0, None]],
        {2: "a", 1: [1.0]},  # keys that are not strings: the standard library's text
    ],
)
def test_lists_of_numbers_and_what_only_looks_like_them(v):
    assert indented(v) == json.dumps(v, indent=2, sort_keys=True)


def test_a_pattern_with_its_design_is_written_without_the_python_encoder(monkeypatch):
    """A design's stored target is thousands of numbers on lines of their own: the standard library encodes
    an indented value in Python (``json.encoder._make_iterencode``), one generator step per value."""
    pattern = read_pattern(TEMPLATES / "patterns" / "circle-8x8-rigid.json")
    assert pattern.design and len(pattern.design["target"]["points"]) > 100
    text = (TEMPLATES / "patterns" / "circle-8x8-rigid.json").read_text()
    calls = []
    real = json.encoder._make_iterencode
    monkeypatch.setattr(
        json.encoder, "_make_iterencode", lambda *a, **k: calls.append(1) or real(*a, **k)
    )
    assert dumps(pattern) == text
    assert calls == []
