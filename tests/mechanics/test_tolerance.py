"""``fabkiri tolerance``: the Monte-Carlo's measures against exact geometry and its CLI."""

from __future__ import annotations

import json

import numpy as np
import pytest
import shapely
from fabkiri.exchange.pattern_json import read_pattern
from fabkiri.mechanics.deploy import closed_states
from fabkiri.mechanics.tolerance import corner_shift, seam_edges, seam_misfit, tolerance_analysis

from ..conftest import TEMPLATES

CIRCLE = TEMPLATES / "patterns" / "circle-8x8.json"


def test_corner_shift_moves_edges_by_their_offsets():
    rng = np.random.default_rng(1)
    quad = np.array([[0, 0], [10, 1], [11, 9], [-1, 8]], float)
    off = rng.normal(0, 0.1, 4)
    moved = quad + corner_shift(quad[None], off[None])[0]
    for k in range(4):  # each moved edge lies on its line shifted outward by off[k]
        e = quad[(k + 1) % 4] - quad[k]
        n = np.array([e[1], -e[0]]) / np.linalg.norm(e)
        for p in (moved[k], moved[(k + 1) % 4]):
            assert (p - quad[k]) @ n == pytest.approx(off[k], abs=1e-12)


def test_no_error_means_no_gap_no_overlap():
    r = tolerance_analysis(read_pattern(CIRCLE), kerf_sd=0.0, hinge_sd=0.0, n=3)
    for s in r.gap:
        assert r.gap[s].max() < 1e-9
    for s in r.overlap_max:
        assert r.overlap_max[s].max() < 1e-9 and r.seam_gap[s].max() < 1e-9
    assert r.outline.max() < 1e-6


def test_gaps_scale_linearly_with_the_errors():
    p = read_pattern(CIRCLE)
    a = tolerance_analysis(p, kerf_sd=0.01, hinge_sd=0.02, n=50, seed=3)
    b = tolerance_analysis(p, kerf_sd=0.03, hinge_sd=0.06, n=50, seed=3)
    for s in a.gap:  # the model is linear in the errors: same draws, three times the sd
        assert np.allclose(b.gap[s], 3 * a.gap[s], rtol=1e-9)


def test_seam_overlap_matches_exact_overlay():
    p = read_pattern(CIRCLE)
    c = closed_states(p)[1]
    seams = seam_edges(c, 1e-3 * p.tile_size)
    assert len(seams) >= p.topology.n_hinges  # every hinge closes a seam on at least one side
    rng = np.random.default_rng(5)
    moved = c + rng.normal(0, 0.03, c.shape)
    over, _, _ = seam_misfit(moved[None], seams)
    polys = shapely.polygons(moved)
    exact = shapely.area(
        shapely.intersection(polys[seams[:, 0]], polys[seams[:, 2]], grid_size=1e-9)
    )
    big = exact > 1e-3
    assert big.sum() > 20
    # first order in the errors: the sliver areas agree to a few per cent
    assert np.median(np.abs(over[0][big] - exact[big]) / exact[big]) < 0.05


@pytest.mark.slow
def test_cli_writes_json_and_plot(run_cli, tmp_path):
    code, _, err = run_cli(
        "tolerance", CIRCLE, "--kerf-sd", "0.02", "--n", "200", "-o", tmp_path / "t"
    )
    assert code == 0, err
    d = json.loads((tmp_path / "t" / "tolerance.json").read_text())
    assert d["model"]["samples"] == 200
    assert set(d["closure_gap_mm"]) == {"closed state 1", "deployed", "closed state 2"}
    assert (
        0
        < d["closure_gap_mm"]["closed state 1"]["p50"]
        < d["closure_gap_mm"]["closed state 1"]["p95"]
    )
    assert len(d["most_sensitive_tiles"]) == 5
    assert (tmp_path / "t" / "tolerance.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert "most sensitive tiles" in err


def test_cli_rejects_bad_sd(run_cli, tmp_path):
    with pytest.raises(SystemExit) as exc:
        run_cli("tolerance", CIRCLE, "--kerf-sd", "-1", "-o", tmp_path / "t")
    assert exc.value.code == 2 and not (tmp_path / "t").exists()
