"""Honest verification (issue 15): no false failures on valid designs, no silent passes on broken ones."""

from __future__ import annotations

import numpy as np
import pytest
import shapely
from fabkiri.exchange.pattern_json import read_pattern
from fabkiri.verify import verify_layout, verify_pattern
from fabkiri.verify.pattern_checks import enclosed_gaps


def test_a_crack_around_an_island_is_not_a_gap():
    """A ring of tiles with a rounding-width crack around an inner tile: the gap is the crack, not the ring."""
    outer = shapely.Polygon(
        [(0, 0), (30, 0), (30, 30), (0, 30)], [[(10, 10), (20, 10), (20, 20), (10, 20)]]
    )
    island = shapely.Polygon([(10 + 1e-9, 10), (20, 10), (20, 20), (10, 20)])
    gaps = enclosed_gaps(shapely.union_all([outer, island]))
    assert sum(g.area for g in gaps) < 1e-7
    # a real hole is still a hole
    gaps = enclosed_gaps(
        shapely.union_all([outer, shapely.Polygon([(12, 12), (18, 12), (18, 18), (12, 18)])])
    )
    assert abs(sum(g.area for g in gaps) - 64.0) < 1e-9


@pytest.fixture(scope="module")
def parallelogram(tmp_path_factory):
    from fabkiri.cli.main import main

    path = tmp_path_factory.mktemp("para") / "para.json"
    assert (
        main(
            [
                "design",
                "--tiles",
                "6x6",
                "--holes",
                "parallelogram",
                "--target",
                "circle",
                "-o",
                str(path),
            ]
        )
        == 0
    )
    return path


@pytest.mark.slow
def test_parallelogram_design_verifies_and_cuts(parallelogram, tmp_path, run_cli):
    p = read_pattern(parallelogram)
    rep = verify_pattern(p)
    assert rep.ok, rep.to_text()
    assert (
        "T-junctions" in rep.get("state 1: folded gaps closed").detail
    )  # the design really is parallelogram
    code, _, err = run_cli(
        "cut", parallelogram, "--hinge", "separate", "--formats", "dxf,svg", "-o", tmp_path / "c"
    )
    assert code == 0, err
    for f in ("para.dxf", "para.svg"):
        lay = verify_layout(p, tmp_path / "c" / f)
        assert lay.ok, lay.to_text()
        for s in (1, 2):
            assert lay.get(f"layout: (c) state {s} from cut tiles: no interior gaps").value < 1e-3


@pytest.mark.slow
def test_deploy_exits_1_on_its_own_failed_check_and_sizes_the_overlaps(run_cli, tmp_path):
    from ..conftest import ref

    out = tmp_path / "ref"
    code, _, err = run_cli(
        "deploy", ref("compact_reconfigurable_design"), "--steps", "10", "--no-frames", "-o", out
    )
    assert code == 1  # without --check too
    assert (out / "energy.csv").exists()  # the figures are written first
    import re

    m = re.search(
        r"collisions: (\d+) overlaps .* largest tiles \d+/\d+ ([0-9.e+-]+) mm² \(([0-9.e+-]+) mm deep\)",
        err,
    )
    assert m, err
    assert float(m.group(2)) > 0 and float(m.group(3)) > 0


def _outline_checks(rep):
    return {c.name: c for c in rep.checks if "outline" in c.name and "one outline" not in c.name}


def test_closed_state_outline_targets_are_checked():
    from fabkiri.pattern import Pattern

    from ..conftest import TEMPLATES

    p = read_pattern(TEMPLATES / "patterns" / "square-circle-9x9-rigid.json")
    import copy

    # asked for a 2:1 rectangle, the square state is refused
    d = copy.deepcopy(p.design)
    del d["contracted_targets"]["1"]
    d["options"]["contracted"]["1"] = {"rectangle": True, "ratio": 2.0}
    rect = _outline_checks(
        verify_pattern(Pattern(nodes=p.nodes, tiles=p.tiles, lattice=p.lattice, design=d))
    )
    assert (
        not rect["state 1: outline aspect ratio"].ok
        and rect["state 1: outline aspect ratio"].value > 10
    )


@pytest.mark.slow
def test_a_degenerate_contracted_rectangle_is_reported(tmp_path, run_cli):
    path = tmp_path / "rr.json"
    code, _, err = run_cli(
        "design",
        "--tiles",
        "6x6",
        "--target",
        "circle",
        "--contracted-target",
        "1:rect",
        "--contracted-target",
        "2:rect",
        "-o",
        path,
    )
    assert path.exists(), (
        err
    )  # (design itself exits 1 when the deployed circle is missed: written anyway)
    code, out, _ = run_cli("verify", path)
    assert code == 1
    chk = verify_pattern(read_pattern(path)).get("state 1: outline not degenerate")
    assert not chk.ok and chk.value > 10 and "collapsed strip" in chk.detail
    code, _, err = run_cli("cut", path, "-o", tmp_path / "c")
    assert code == 1 and "outline not degenerate" in err and not (tmp_path / "c").exists()


def _near_closed(pattern, d_mm: float, tile: int = 7):
    """``pattern`` with one corner of one tile of its stored closed state 2 moved by ``d_mm``
    (published patterns close to about 1e-6 of the tile size, not 1e-9)."""
    from dataclasses import replace

    Y = pattern.contracted[2].copy()
    Y[tile, 1] += d_mm * np.array([0.6, 0.8])
    return replace(pattern, contracted={1: pattern.contracted[1], 2: Y})


def test_one_tolerance_in_mm_angles_as_displacement(tmp_path, run_cli):
    from fabkiri.exchange.pattern_json import write_pattern

    from .. import layout_fixtures as lf

    base = lf.distinct_pattern()  # 20 mm tiles
    p = _near_closed(base, 3e-4)
    exact = verify_pattern(p)  # the relative tier: 1e-9 of the tile edge
    assert (
        not exact.get("state 2: tiles congruent (angles)").ok
        and exact.get("state 2: tiles congruent (angles)").unit == "rad"
    )
    mm = verify_pattern(p, tol_mm=0.05)
    assert mm.ok, mm.to_text()
    ang = mm.get("state 2: tiles congruent (angles)")
    assert (
        ang.unit == "mm"
        and 1e-5 < ang.value < 1e-3
        and ang.tol == 0.05
        and "displacement" in mm.meta["tolerance"]
    )
    # a real error is still one at 0.05 mm, named by tile
    bad = verify_pattern(_near_closed(base, 0.2), tol_mm=0.05)
    for name in ("state 2: tiles congruent (lengths)", "state 2: tiles congruent (angles)"):
        assert not bad.get(name).ok and bad.get(name).worst == "tile 7"
    # the CLI: 0.05 mm by default, --exact for solver output, and the report says which
    pj = tmp_path / "near.json"
    write_pattern(p, pj)
    code, out, _ = run_cli("verify", pj)
    assert (
        code == 0
        and "0.05 mm for lengths, and for angles as their displacement" in out.splitlines()[0]
    )
    code, out, _ = run_cli("verify", pj, "--exact")
    assert code == 1 and "exact" in out.splitlines()[0]
    code, _, err = run_cli(
        "cut", pj, "--hinge", "separate", "--formats", "dxf", "-o", tmp_path / "c"
    )
    assert code == 0, err
    code, _, err = run_cli(
        "cut", pj, "--hinge", "separate", "--formats", "dxf", "--exact", "-o", tmp_path / "x"
    )
    assert code == 1 and "tiles congruent" in err and not (tmp_path / "x").exists()
