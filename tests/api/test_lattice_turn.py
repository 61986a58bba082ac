"""An outline whose mirror axis is off the lattice's axes is designed turned onto them and turned back (issue #37)."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from fabkiri.api.design import PatternRequest, design_pattern
from fabkiri.api.design_report import report_problem
from fabkiri.api.design_turn import lattice_angle, turned_design
from fabkiri.api.kagome import design_kagome_pattern
from fabkiri.design.core import conformance as conf
from fabkiri.design.core.request import MIRROR_TOL
from fabkiri.design.targets.axes import mirror_axis_deg, rotation, turned
from fabkiri.design.targets.lookup import load_target
from fabkiri.design.targets.shapes import ellipse, heart
from fabkiri.errors import InputError

DATA = Path(__file__).resolve().parents[2] / "bench" / "data"


def _heart(degrees: float):
    return turned(heart(512).scaled_to(100), degrees)[0]


def test_mirror_axis_of_turned_outlines():
    """The heart turned by 20 degrees has its axis at 110 degrees, the 2:1 ellipse turned by -30 at 150 (or 60);
    the bean has none within MIRROR_TOL."""
    angle, error = mirror_axis_deg(_heart(20))
    assert abs(angle - 110) < 0.05 and error <= MIRROR_TOL
    angle, error = mirror_axis_deg(turned(ellipse(n=256).scaled_to(100), -30)[0])
    assert min(abs(angle - 150), abs(angle - 60)) < 0.05 and error <= MIRROR_TOL
    assert mirror_axis_deg(load_target(str(DATA / "bean.csv"), 100))[1] > MIRROR_TOL


def test_lattice_angle_policy():
    """Turned onto the nearer lattice axis, or the requested one under --symmetry; the upright heart, the bean, a
    printer's request and an explicit angle keep theirs."""
    rot = _heart(20)

    def angle(target, **kw):
        return lattice_angle(PatternRequest(tiles=(8, 8), target=target, rigid=True, **kw), target)

    assert abs(angle(rot) - 20) < 0.05
    assert abs(angle(rot, symmetry="x") + 70) < 0.05  # the x axis laid on the heart's axis
    assert angle(load_target("heart", 100)) == 0
    assert angle(load_target(str(DATA / "bean.csv"), 100)) == 0
    assert angle(rot, printer="prusa-mk4") == 0
    assert (
        angle(load_target("heart", 100), symmetry="x") == 0
    )  # refused as before: the heart's axis is y
    # on 8 x 16 tiles (twice as wide as tall) the 2:1 ellipse, its long axis at 80 degrees, lies along x
    tilted = turned(ellipse(n=256).scaled_to(100), 80)[0]
    assert abs(angle(tilted) + 10) < 0.05
    wide = lattice_angle(PatternRequest(tiles=(8, 16), target=tilted, rigid=True), tilted)
    assert abs(wide - 80) < 0.05
    assert angle(rot, lattice_angle=5.0) == 5.0


def test_turned_design_is_the_turned_back_design_of_the_turned_outline(tmp_path):
    """Every node of the design and of both closed states is the turned outline's design turned back; the stored
    target and the shape verdict are the user's outline; the report says the lattice's angle."""
    rot = _heart(20)
    angle = lattice_angle(PatternRequest(tiles=(8, 8), target=rot, rigid=True), rot)
    base = PatternRequest(tiles=(8, 8), target=rot, rigid=True, quiet=True, init="rescaled")
    out = design_pattern(replace(base, shape_tol="10%", lattice_angle=angle))
    assert out.report["lattice_angle_deg"] == angle
    inner, shift = turned(rot, -angle)
    own = design_pattern(replace(base, target=inner, lattice_angle=0, shape_tol="10mm"))
    assert "lattice_angle_deg" not in own.report

    def back(p):
        return (p - shift) @ rotation(angle)

    assert np.allclose(back(own.pattern.nodes), out.pattern.nodes, atol=1e-9)
    for s in (1, 2):
        assert np.allclose(back(own.pattern.contracted[s]), out.pattern.contracted[s], atol=1e-9)
    assert np.allclose(out.pattern.design["target"]["points"], rot.points)
    measured = conf.deployed(out.pattern.nodes, out.pattern.topology, rot)
    assert out.report["conformance"]["deployed"]["hausdorff_rel"] == measured["hausdorff_rel"]
    assert out.report["shape"]["deployed"]["tol_mm"] == pytest.approx(0.1 * rot.size)
    assert any("laid at 20.0° along the outline's mirror axis" in line for line in out.summary())
    out.write(tmp_path / "p.json", preview=False)
    assert report_problem(out.pattern.design["report"]) is None
    assert report_problem({**out.pattern.design["report"], "lattice_angle_deg": "20"}) is not None


def test_kagome_refuses_a_lattice_angle():
    with pytest.raises(InputError, match="lattice-angle"):
        design_kagome_pattern(PatternRequest(tiles=(4, 4), target="circle", lattice_angle=10.0))


def test_the_turned_lattice_is_a_retry_for_a_design_that_fails():
    """Where the design on the drawing's axes misses (a 4x4 heart at 0.1 mm) the turned lattice is tried, mirrored
    about the heart's axis (onto y), then unmirrored; the best is kept and the report lists every attempt, the
    turned ones marked. One that passes on the drawing's axes (at 20 %) is left as it was."""
    rot = _heart(20)
    req = PatternRequest(tiles=(4, 4), target=rot, rigid=True, quiet=True, init="rescaled")
    out = design_pattern(replace(req, shape_tol="0.1mm"))
    attempts = out.report["attempts"]
    assert len(attempts) == 3 and "lattice_angle_deg" not in attempts[0]
    assert [a.get("mirrored") for a in attempts[1:]] == ["y", None]
    assert all(abs(a["lattice_angle_deg"] - 20) < 0.05 for a in attempts[1:])
    h = [a["hausdorff_max_rel"] for a in attempts]
    best = int(np.argmin(h))
    assert out.report["conformance"]["deployed"]["hausdorff_rel"] == pytest.approx(h[best])
    assert out.report["lattice_angle_deg"] == (attempts[best].get("lattice_angle_deg") or 0.0)
    assert out.report.get("mirrored") == attempts[best].get("mirrored")
    assert any("trying the lattice along the outline's mirror axis" in m for m in out.messages)
    passed = design_pattern(replace(req, shape_tol="20%"))
    assert passed.success and len(passed.report["attempts"]) == 1
    assert "lattice_angle_deg" not in passed.report
    # an explicit angle is not second-guessed
    given = design_pattern(replace(req, shape_tol="0.1mm", lattice_angle=20.0))
    assert len(given.report["attempts"]) == 1 and given.report["lattice_angle_deg"] == 20.0


def test_a_refused_mirrored_retry_leaves_the_unmirrored_one():
    """A mirrored turned design that cannot be made (InputError: here refused outright) is skipped, not raised."""
    rot = _heart(20)

    def refusing(request, notify=None):
        if request.symmetry == "y":
            raise InputError("no mirrored lattice")
        return design_pattern(request, notify)

    req = PatternRequest(
        tiles=(4, 4), target=rot, rigid=True, quiet=True, init="rescaled", shape_tol="0.1mm"
    )
    out = turned_design(req, rot, lattice_angle(req, rot), refusing, None)
    attempts = out.report["attempts"]
    assert (
        len(attempts) == 2 and "mirrored" not in attempts[1] and "lattice_angle_deg" in attempts[1]
    )


def test_the_mirror_axis_is_sought_only_after_a_design_fails(monkeypatch):
    """A design that passes on the drawing's axes pays no axis test or scan; one that fails asks both once."""
    from fabkiri.api import design_turn

    calls = []
    for name in ("axis_distances", "mirror_axis_deg"):
        real = getattr(design_turn, name)
        monkeypatch.setattr(
            design_turn, name, lambda *a, _n=name, _f=real: calls.append(_n) or _f(*a)
        )
    req = PatternRequest(tiles=(4, 4), target=_heart(20), rigid=True, quiet=True, init="rescaled")
    assert design_pattern(replace(req, shape_tol="20%")).success and calls == []
    design_pattern(replace(req, shape_tol="0.1mm"))
    assert (
        calls[:2] == ["axis_distances", "mirror_axis_deg"] and calls.count("mirror_axis_deg") == 1
    )
