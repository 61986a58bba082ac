"""bench/kagome.py --fit measures each written design's Hausdorff distance apart from the design's own
report (shapely, on the tip outline read back from the file): the two must agree (docs/kagome.md)."""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]


def _bench():
    sys.path.insert(0, str(ROOT / "bench"))  # the bench imports its sibling child.py
    try:
        spec = importlib.util.spec_from_file_location("bench_kagome", ROOT / "bench" / "kagome.py")
        mod = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(mod)
    finally:
        sys.path.remove(str(ROOT / "bench"))
    return mod


@pytest.mark.parametrize(
    "name, target, size",
    [("kagome-heart-6x11.json", "heart", "120"), ("kagome-ellipse-5x19.json", "ellipse", "198")],
)
def test_the_fit_table_measures_the_hausdorff_distance_apart_from_the_report(name, target, size):
    from fabkiri.design.core import conformance as conf
    from fabkiri.design.targets.lookup import load_target
    from fabkiri.exchange.pattern_json import read_pattern

    path = ROOT / "tests" / "data" / name
    p = read_pattern(path)
    reported = (
        100 * conf.deployed(p.nodes, p.topology, load_target(target, float(size)))["hausdorff_rel"]
    )
    measured = float(_bench()._shapely_hausdorff(path, target, size))
    assert reported > 0.5 and abs(measured - reported) <= 0.02, (measured, reported)
