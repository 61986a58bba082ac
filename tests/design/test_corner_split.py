"""An L re-split as a bent strip (``design/quad/corner_split.py``) and its fold-free start
(``design/quad/inverse_map.py``): the lattice's corners at the strip's ends, a tip on the reflex corner, no
folded tile, and the fit within the shape tolerance; outlines the default split takes keep it."""

from __future__ import annotations

import numpy as np
import pytest
from fabkiri.api import maker_tiles
from fabkiri.design.core.stencils import Stencils
from fabkiri.design.quad import corner_split as cs
from fabkiri.design.quad.initial import initial_guess
from fabkiri.design.quad.inverse_map import inverse_harmonic_map
from fabkiri.design.targets.lookup import load_target
from fabkiri.pattern import geometry
from fabkiri.pattern.kinds.quad.lattice import standard_pattern

from ..api.test_make import _limits
from .test_opening import DATA

ELL = str(DATA / "letter-l.csv")  # 60 x 100 mm, reflex corner at (25, 25): centred (-5, -25)
STRIP_ENDS = [(30.0, -50.0), (30.0, -25.0), (-5.0, 50.0), (-30.0, 50.0)]  # BL, BR, TR, TL


def _pattern(rows: int, cols: int):
    sp = standard_pattern(rows, cols, tile_size=1.0)
    return sp.nodes - sp.nodes.mean(0), Stencils.from_pattern(sp)


def test_the_fold_free_start_puts_a_tip_on_the_reflex_corner():
    ell = load_target(ELL, None)
    base, st = _pattern(8, 8)
    x = inverse_harmonic_map(base, st.tip_nodes, st.tip_side, ell)
    assert (geometry.signed_areas(x[st.tiles]) > 0).all()  # the pattern's own map folds 2 of them
    assert cs.default_folds(ell, 8, 8)
    tips = x[st.tip_nodes]
    assert np.linalg.norm(tips - [-5.0, -25.0], axis=1).min() < 1e-9
    # every tip on the outline (the mesh's boundary is the polyline's own vertices and samples)
    assert np.abs(ell.signed_distance(tips)).max() < 1e-6 * ell.size


def test_an_l_is_split_at_its_strips_ends_with_rows_along_it():
    ell = load_target(ELL, None)
    split, tiles, d, d0 = cs.best_split(ell, [(8, 8), *cs.lattice_shapes(64)])
    assert split.corner_points() == pytest.approx(np.array(STRIP_ENDS), abs=1e-6)
    assert tiles[0] > 3 * tiles[1] and tiles[0] * tiles[1] <= 64  # a strip about 4x as long as wide
    assert d < cs.RESPLIT_GAIN * d0
    # the start from the re-split target is the fold-free one, placed on the outline
    base, st = _pattern(*tiles)
    x, L0 = initial_guess(base, st, split, "conformal")
    assert (geometry.signed_areas(x[st.tiles]) > 0).all()
    assert np.abs(split.signed_distance(x[st.tip_nodes] * L0)).max() < 1e-6 * split.size


@pytest.mark.parametrize("name", [pytest.param("star", marks=pytest.mark.slow), "heart", "circle"])
def test_outlines_the_default_split_takes_keep_it(name):
    acrylic = _limits(material="acrylic-3")
    t = load_target(name, 150)
    c = maker_tiles.choose_tiles(t, acrylic, "acrylic-3 tape")
    assert c.corners is None and c.tiles[0] == c.tiles[1]


def test_make_chooses_the_strip_for_the_l():
    acrylic = _limits(material="acrylic-3")
    c = maker_tiles.choose_tiles(load_target(ELL, 150), acrylic, "acrylic-3 tape")
    assert c.corners is not None and c.tiles[0] > 3 * c.tiles[1]
    assert "bends round the outline's pocket" in c.reason
    # tiles the user names keep the target's own corners
    given = maker_tiles.given_tiles((8, 8), load_target(ELL, 150), acrylic)
    assert given.tiles == (8, 8) and given.corners is None


@pytest.mark.slow  # a 16x4 design (~3 CPU s from the fold-free start, more where it retries)
def test_the_l_is_met_on_the_strip_split():
    from fabkiri.api.design import PatternRequest, design_pattern

    ell = load_target(ELL, None)
    split, tiles, _, _ = cs.best_split(ell, [(16, 4)])
    req = PatternRequest(tiles=tiles, target=ELL, size=100.0, corners=tuple(split.corners))
    outcome = design_pattern(req)
    shape = outcome.report["shape"]["deployed"]
    assert outcome.report["status"] == "converged"
    assert shape["hausdorff_rel"] <= 0.02, shape  # the default 2 %; on main's split: 21-33 %


def test_a_missed_l_names_the_strip_make_would_use():
    from fabkiri.design.core.conformance import describe_miss

    from .test_opening import CONF, _missed

    strip = {"tiles": [16, 4], "corners": STRIP_ENDS}
    pocket = {"depth_mm": 25.0, "deepest": [-5.0, -25.0], "area_mm2": 1312.5, "strip": strip}
    why = describe_miss("deployed", _missed(tried_inits=["conformal"], pocket=pocket), CONF)
    assert "try it as a bent strip: 16x4 tiles" in why and "(30, -50); (30, -25)" in why
    assert "--tiles 16x4" in why and len(why.splitlines()) == 1
    # the strip is the one bent_strip finds for an 8x8 L (what annotate stores)
    split, tiles, _, _ = cs.bent_strip(load_target(ELL, None), 8, 8)
    assert tiles == (16, 4) and split.corner_points() == pytest.approx(np.array(STRIP_ENDS))


def test_a_target_on_its_own_split_keeps_the_pattern_s_map():
    """The fold-free start is only for a re-split target: a star on its own split (its corner
    parameters wrap past 1) still refuses the folding harmonic map, as before."""
    from fabkiri.errors import SolveError

    star = load_target("star", 100)
    assert star.corners[-1] > 1.0  # stored unwrapped: 0.888, 1.112 against the default's 0.112
    base, st = _pattern(8, 8)
    assert cs.default_folds(star, 8, 8)
    with pytest.raises(SolveError, match="folds"):
        initial_guess(base, st, star, "conformal")


@pytest.mark.parametrize("tried", [[], [{"init": "strip", "tiles": [4, 16]}]])
def test_a_strip_the_design_tried_is_not_advised_again(tried):
    """The miss names make's bent strip only when the design did not try a strip of those tiles: an M at
    16x16 missed on its 42x6 strip, then advised the same 42x6 strip."""
    import dataclasses

    from fabkiri.api.shape_limits import annotate

    ell = load_target(ELL, None)
    sp = standard_pattern(8, 8, tile_size=1.0)
    box = ell.point(np.linspace(0.0, 1.0, 400))
    lo, hi = box.min(0), box.max(0)  # the lattice's square outline runs across the L's pocket
    nodes = (sp.nodes - sp.nodes.min(0)) / np.ptp(sp.nodes, 0) * (hi - lo) + lo
    report = {"shape": {"deployed": {"status": "missed", "local_minimum": True}}}
    annotate(report, [{"init": "rescaled"}, *tried], ell, dataclasses.replace(sp, nodes=nodes))
    pocket = report["shape"]["deployed"]["pocket"]
    assert pocket["covered"] == pytest.approx(1.0)
    assert ("strip" in pocket) == (not tried)
