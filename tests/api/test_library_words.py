"""What a refused cut or print tells a Python caller names the keywords it passes (``scale ≥ 0.3``,
``force=True``); the same error on the command line names the flags (``--scale ≥ 0.3``, ``--force``)."""

from __future__ import annotations

from dataclasses import replace

import fabkiri
import numpy as np
import pytest
from fabkiri.errors import InputError


@pytest.fixture(scope="module")
def square():
    return fabkiri.standard("4x4")


def _no_flags(text: str) -> None:
    assert " --" not in text and "(--" not in text and not text.startswith("--")


def test_too_thin_names_scale_and_width(square):
    r = fabkiri.cut(square, "acrylic-3", scale=0.1)
    _no_flags(r.problems[0])
    assert r.problems[0].endswith("cut at scale ≥ 0.3, width ≥ 12.01 mm (or scale='auto')")
    assert r.error.cli_message().endswith(
        "cut at --scale ≥ 0.3, --width ≥ 12.01 mm (or --scale auto)"
    )


def test_shrunk_ligament_names_the_gap_field(square):
    r = fabkiri.cut(square, "felt-2", hinge="ligament", scale=0.5)
    _no_flags(r.problems[0])
    assert r.problems[0].endswith("(or scale='auto'); or use a smaller gap_mm")
    assert r.error.cli_message().endswith("(or --scale auto); or use a smaller --gap")


def test_scale_auto_that_finds_none(square):
    r = fabkiri.cut(square, "acrylic-3", hinge="ligament", scale="auto", settings=["gap_mm=0.1"])
    assert r.problems[0].startswith("scale='auto': acrylic-3 with ligament hinges: no scale works")
    assert r.error.cli_message().startswith("--scale auto: acrylic-3 with ligament hinges")


def test_a_pattern_that_does_not_close_names_force(square):
    states = dict(square.contracted)
    states[1] = states[1] + np.random.default_rng(0).normal(0, 0.5, states[1].shape)
    r = fabkiri.cut(replace(square, contracted=states))
    assert not r.ok and r.problems[0].endswith("nothing cut (force=True cuts it anyway)")
    assert r.error.cli_message().endswith("nothing cut (--force cuts it anyway)")


def test_print_refusal_and_description_name_scale(square):
    r = fabkiri.print_pattern(square, scale=0.05)
    _no_flags(r.problems[0])
    assert "(at scale=0.05); print at scale ≥ 0.8705 (or scale='auto')" in r.problems[0]
    assert r.problems[0].endswith("the bed of prusa-mk4 takes up to scale=5.245")
    cli = r.error.cli_message()
    assert "(at --scale 0.05); print at --scale ≥ 0.8705 (or --scale auto)" in cli
    assert cli.endswith("takes up to --scale 5.245")
    made = fabkiri.print_pattern(square)
    assert made.description.startswith("tiles-and-strips at scale=1, closed state 1")
    assert made.outcome.describe().startswith("tiles-and-strips at --scale 1, closed state 1")


@pytest.mark.parametrize(
    ("given", "words"), [({"scale": 1e12}, "scale"), ({"width": 1e9}, "width")]
)
def test_sizes_out_of_bounds_name_the_keyword(square, given, words):
    with pytest.raises(InputError) as err:
        fabkiri.cut(square, **given)
    assert str(err.value).startswith(f"{words} ") and err.value.cli_message().startswith(
        f"--{words} "
    )
