"""Issue #18 (solver speed and start-up): the fast paths give the answers of the slow ones they replace
(timings live in bench/solve.py, not here)."""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st


@settings(max_examples=40, deadline=None)
@given(st.integers(2, 200), st.integers(0, 2 ** 32 - 1))
def test_closest_pair_equals_the_pairwise_minimum(n, seed):
    from fabkiri.fabricate.fabricability import closest_pair

    p = np.random.default_rng(seed).normal(size=(n, 2)) * 30.0
    dd = np.linalg.norm(p[:, None] - p[None], axis=-1)
    np.fill_diagonal(dd, np.inf)
    assert abs(closest_pair(p) - dd.min()) <= 1e-13 * dd.min()


def test_design_with_its_preview_imports_no_matplotlib(tmp_path):
    from tests.test_startup import _modules_after

    mods = _modules_after(["design", "--tiles", "3x3", "--target", "circle", "--rigid", "-o", str(tmp_path / "p.json")])
    png = (tmp_path / "p.png").read_bytes()
    assert png[:8] == b"\x89PNG\r\n\x1a\n"
    assert not {"matplotlib", "jsonschema"} & mods


def test_preview_is_deterministic_with_a_panel_per_outline(tmp_path):
    import io

    from fabkiri.api.design import PatternRequest, design_pattern
    from fabkiri.render import conformance as rc
    from PIL import Image

    out = design_pattern(PatternRequest(tiles=(3, 3), rigid=True, contracted_target=("1:square", "2:circle")))
    conf, shape = out.report["conformance"], out.report["shape"]
    png = rc.conformance_png(out.pattern, conf, shape)
    assert png == rc.conformance_png(out.pattern, conf, shape)
    img = Image.open(io.BytesIO(png))
    assert img.size[0] == 2 * (rc.PANEL_PX[0] + 2 * rc.MARGIN_PX)  # closed states 1 and 2
    pixels = np.asarray(img.convert("RGB")).reshape(-1, 3)
    for colour in ("tile", "target", "worst"):  # each layer is on the picture
        assert (pixels == rc.COLOURS[colour]).all(1).any(), colour


def test_every_shipped_preset_passes_its_schema():
    # load_material / load_printer skip the JSON Schema for shipped presets by name: this is their check
    import json

    from fabkiri.fabricate import materials, printers
    from fabkiri.schemas import load_schema, schema_problem

    for folder, package, schema, names in (
            (materials.MATERIALS_DIR, "fabkiri.fabricate", "material.schema.json", materials.available()),
            (printers.PRINTERS_DIR, "fabkiri.fabricate", "printer.schema.json", printers.available_printers())):
        assert names
        for name in names:
            data = json.loads((folder / f"{name}.json").read_text("utf-8"))
            assert schema_problem(data, load_schema(package, schema)) is None, name


def test_a_preset_file_by_path_is_still_checked_against_the_schema(tmp_path):
    import json

    import pytest
    from fabkiri.errors import InputError
    from fabkiri.fabricate import materials, printers

    for folder, name, load in ((materials.MATERIALS_DIR, materials.available()[0], materials.load_material),
                               (printers.PRINTERS_DIR, printers.available_printers()[0], printers.load_printer)):
        data = json.loads((folder / f"{name}.json").read_text("utf-8"))
        key = next(k for k, v in data.items() if isinstance(v, float) and v > 0)
        data[key] = -1.0
        bad = tmp_path / f"{name}.json"
        bad.write_text(json.dumps(data))
        with pytest.raises(InputError, match=key):
            load(str(bad))
