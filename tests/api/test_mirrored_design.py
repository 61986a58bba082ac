"""A rigid request without a symmetry on a mirror-symmetric target also gets the mirrored design (issue #37)."""

from __future__ import annotations

import json
from pathlib import Path

from fabkiri.api.design import PatternRequest, design_pattern
from fabkiri.api.design_mirror import mirror_axis
from fabkiri.api.design_report import report_problem
from fabkiri.api.design_summary import summary_lines
from fabkiri.design.quad.solve import DesignRequest
from fabkiri.design.targets.lookup import load_target
from fabkiri.mechanics.path import RIGID_TOL_RAD

PEANUT = str(Path(__file__).resolve().parents[2] / "bench" / "data" / "peanut.csv")


def test_rigid_peanut_keeps_its_closer_mirrored_design(tmp_path):
    """The rigid 16x16 peanut (symmetric about x): the unmirrored route stops at 0.37 % of the size, the
    mirrored one reaches 0.17 %; the closer one is kept, rigid-deployable, and the report and the CLI's lines
    say it is mirrored."""
    out = design_pattern(PatternRequest(tiles=(16, 16), target=PEANUT, size=100, rigid=True))
    report = out.report
    assert report.get("mirrored") == "x"
    assert out.valid
    assert report["checks"]["hinge_sum_max_rad"] <= RIGID_TOL_RAD
    unmirrored = [a["hausdorff_max_rel"] for a in report["attempts"] if "mirrored" not in a]
    assert unmirrored, (
        "the mirrored design missed the gate here: the unmirrored route must have run"
    )
    assert report["conformance"]["deployed"]["hausdorff_rel"] < min(unmirrored)
    assert any("mirrored about x" in line for line in summary_lines(None, report))
    out.write(tmp_path / "p.json", preview=False)
    written = json.loads((tmp_path / "p.json").read_text())["design"]["report"]
    # the schema names the new keys
    assert written["mirrored"] == "x" and report_problem(written) is None
    assert report_problem({**written, "mirrored": "z"}) is not None


def test_mirror_axis_only_for_rigid_requests_without_a_symmetry():
    """Explicit symmetries, free requests and asymmetric targets keep their own route."""
    peanut = load_target(PEANUT, 100)
    rigid = PatternRequest(tiles=(8, 8), target=PEANUT, size=100, rigid=True)
    req = DesignRequest(rows=8, cols=8, target=peanut, rigid=True)
    assert mirror_axis(rigid, req) == "x"
    assert mirror_axis(PatternRequest(tiles=(8, 8), target=PEANUT, size=100), req) is None
    sym = PatternRequest(tiles=(8, 8), target=PEANUT, size=100, rigid=True, symmetry="x")
    assert mirror_axis(sym, req) is None
    for one_axis in ("heart", str(Path(PEANUT).with_name("drop.csv"))):  # symmetric about y only
        req = DesignRequest(rows=8, cols=8, target=load_target(one_axis, 100), rigid=True)
        assert mirror_axis(rigid, req) is None
    # symmetric about both axes but round and convex: the circle keeps its one route (issue #36's rows)
    circle = DesignRequest(rows=8, cols=8, target=load_target("circle", 100), rigid=True)
    assert mirror_axis(rigid, circle) is None
    ellipse = DesignRequest(rows=8, cols=8, target=load_target("ellipse", 100), rigid=True)
    assert mirror_axis(rigid, ellipse) == "x"
    # the x mirror needs an even row count, the y mirror an even column count
    assert mirror_axis(rigid, DesignRequest(rows=5, cols=6, target=peanut, rigid=True)) == "y"
    assert mirror_axis(rigid, DesignRequest(rows=5, cols=5, target=peanut, rigid=True)) is None
