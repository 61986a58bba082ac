"""The cut front door: `fabkiri cut` is `cut_material` + `cut_files` plus argument parsing, writing and printing."""

from __future__ import annotations

import json
import re

import pytest
from fabkiri.api.cut import CutOutcome, cut_files, cut_material, design_intent
from fabkiri.errors import CheckFailed, InputError
from fabkiri.exchange.pattern_json import write_pattern
from fabkiri.fabricate.cut.sheets import CutOptions
from fabkiri.mechanics import with_contracted_states
from fabkiri.pattern import standard_pattern


@pytest.fixture(scope="module")
def square():
    return with_contracted_states(standard_pattern(3, 3))


def test_cut_files_are_the_bytes_the_cli_writes(square, tmp_path, run_cli):
    material, hinge = cut_material(
        square, None, None, changes={"kerf_mm": 0.1}, settings=["min_web_mm=2"]
    )
    assert (
        material.name == "acrylic-3"
        and material.kerf_mm == 0.1
        and material.min_web_mm == 2
        and hinge is None
    )
    out = cut_files(square, CutOptions(material=material, stem="sq", pattern_file="sq.json"))
    assert isinstance(out, CutOutcome) and out.readback.ok
    man = json.loads(out.files["manifest.json"])
    assert man["verification"]["ok"] and {"sq.dxf", "sq.svg", "manifest.json"} <= set(out.files)
    write_pattern(square, tmp_path / "sq.json")
    code, _, err = run_cli(
        "cut", tmp_path / "sq.json", "--kerf", "0.1", "--set", "min_web_mm=2", "-o", tmp_path / "o"
    )
    assert code == 0, err
    written = {p.name: p.read_bytes() for p in (tmp_path / "o").iterdir()}
    assert written == out.files


def test_the_design_intent_chooses_material_and_hinge_unless_a_material_is_named(square):
    from dataclasses import replace

    made_for = replace(
        square, design={"options": {"fabrication": {"material": "pp-0.5", "hinge": "ligament"}}}
    )
    assert design_intent(made_for, "hinge") == "ligament" and design_intent(square, "hinge") is None
    material, hinge = cut_material(made_for)
    assert material.name == "pp-0.5" and hinge == "ligament"
    material, hinge = cut_material(
        made_for, "acrylic-3"
    )  # a named material drops the design's hinge kind too
    assert material.name == "acrylic-3" and hinge is None
    with pytest.raises(InputError, match="settings expects FIELD=VALUE"):  # the library's words
        cut_material(square, settings=["nope"])


def test_refusals_raise_and_return_nothing(square):
    material, _ = cut_material(square)
    with pytest.raises(InputError, match="^scale 1e\\+300 puts the pattern") as big:
        cut_files(square, CutOptions(material=material, scale=1e300))
    assert big.value.cli_message().startswith("--scale 1e+300 puts the pattern")
    thin = with_contracted_states(standard_pattern(3, 3, tile_size=2.0))
    with pytest.raises(
        CheckFailed, match="thinner than the minimum web .* \\(or scale='auto'\\)"
    ) as refused:
        cut_files(thin, CutOptions(material=material))
    assert re.search(
        "thinner than the minimum web .* \\(or --scale auto\\)", refused.value.cli_message()
    )
