"""The printed strips' pad rows (fabkiri/design/quad/print_rows.py): exact gradients, and the area ``print`` measures."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
import shapely
from fabkiri.design.core.dual import values_only
from fabkiri.design.quad import fabrication as F
from fabkiri.design.quad import print_rows as PR
from fabkiri.design.quad.constraints import Stencils
from fabkiri.exchange.pattern_json import read_pattern
from fabkiri.fabricate import design_limits
from fabkiri.fabricate import fabricability as fb
from fabkiri.fabricate.print import geometry as printgeom
from fabkiri.fabricate.print.printers import load_printer
from fabkiri.pattern.kinds.quad.lattice import standard_pattern

from ..conftest import TEMPLATES

MK4 = F.FabricationLimits(
    **design_limits.printer_limits(load_printer("prusa-mk4"), "tiles-and-strips")
)


def test_clipped_area_of_two_squares():
    x = np.array([[0, 0], [2, 0], [2, 2], [0, 2], [1, 1], [3, 1], [3, 3], [1, 3]], float)
    polys = np.arange(8)[None]
    rows = np.arange(1)
    P = [F.dual_corner(x, polys, rows, np.array([k])) for k in range(8)]
    assert PR.clipped_area(P[:4], P[4:]).v == pytest.approx([1.0])
    assert PR.clipped_area(P[4:], P[:4]).v == pytest.approx([1.0])
    far = [(a[0] + 5.0, a[1]) for a in P[4:]]
    assert PR.clipped_area(P[:4], far).v == pytest.approx([0.0])


@pytest.mark.slow
@pytest.mark.parametrize("seed", [0])
def test_pad_rows_jacobian_matches_finite_differences(seed):
    p = standard_pattern(3, 3, tile_size=1.0)
    stc = Stencils.from_pattern(p)
    x = p.nodes + 0.05 * np.random.default_rng(seed).standard_normal(p.nodes.shape)
    # 4 mm tiles: the band (4 mm along, 4.2 mm either side) is clipped by every tile
    (fam,) = PR.families(stc, len(x), MK4, 4.0)
    r, J = fam(x)
    J = J.toarray()
    h = 1e-6
    Jn = np.empty_like(J)
    for i in range(x.size):
        e = np.zeros(x.size)
        e[i] = h
        Jn[:, i] = (fam.residual(x + e.reshape(x.shape)) - fam.residual(x - e.reshape(x.shape))) / (
            2 * h
        )
    assert np.abs(J - Jn).max() < 1e-6
    assert len(r) == 2 * len(stc.hinge_tiles) and np.ptp(r) > 0.05


def test_residual_only_rows_carry_no_gradients_and_the_same_values():
    """A residual-only call (the solvers' check of every inequality at each trial step) evaluates each
    fabrication family without its gradient arrays, to the same bits as the full evaluation."""
    p = standard_pattern(3, 3, tile_size=1.0)
    stc = Stencils.from_pattern(p)
    x = p.nodes + 0.05 * np.random.default_rng(1).standard_normal(p.nodes.shape)
    lim = F.FabricationLimits(**{**MK4.to_dict(), "min_hole_mm": 0.5})
    fams = F.families(stc, len(x), lim, 4.0, p.nodes)
    assert "fabrication_strip_pads" in {f.name for f in fams}
    for f in fams:
        assert np.array_equal(f.residual(x), f(x)[0]), f.name
    args = PR.pad_args(stc.tiles, stc.hinge_tiles, stc.hinge_corner, stc.folds[1].fold_corner_ends)
    plain = PR.pad_rows(values_only(x), *args, *PR.strip_pad(MK4, 4.0))
    dual = PR.pad_rows(x, *args, *PR.strip_pad(MK4, 4.0))
    assert plain.g is None and dual.g.shape == (len(dual.v), 16)
    assert np.array_equal(plain.v, dual.v)


@pytest.mark.parametrize(("n", "noise", "unit"), [(6, 0.02, 12.0), (5, 0.15, 4.0), (4, 0.4, 2.0)])
def test_residual_only_rows_are_the_dual_rows_to_the_bit(n, noise, unit):
    """The residual-only values (plain arrays, ``row_values.py``) are the bytes of the Dual path's values: on
    lattices from nearly standard to folded tiles (empty clips, obtuse hinge corners), in both closed states,
    at a continuation's first step and without shrink, every fabrication family."""
    p = standard_pattern(n, n, tile_size=1.0)
    stc = Stencils.from_pattern(p)
    full = F.FabricationLimits(**{**MK4.to_dict(), "min_hole_mm": 0.5})
    limits = [
        full,
        full.step(0.25, 0.02),
        replace(full, shrink_mm=0.0),
        replace(full, print_state=2),
    ]
    for seed in range(4):
        x = p.nodes + noise * np.random.default_rng(seed).standard_normal(p.nodes.shape)
        for lim in limits:
            for f in F.families(stc, len(x), lim, unit, p.nodes):
                assert f.residual(x).tobytes() == np.asarray(f(x)[0]).tobytes(), (f.name, seed, lim)


def test_gradients_of_the_active_rows_only_are_the_full_jacobians_rows():
    """The solvers ask an inequality's gradients only inside its margin: ``jacobian_where`` gives exactly the
    full Jacobian's rows there and zero rows elsewhere, in the full Jacobian's sparsity."""
    p = standard_pattern(3, 3, tile_size=1.0)
    stc = Stencils.from_pattern(p)
    x = p.nodes + 0.05 * np.random.default_rng(2).standard_normal(p.nodes.shape)
    lim = F.FabricationLimits(**{**MK4.to_dict(), "min_hole_mm": 0.5, "hinge_spacing_mm": 1.0})
    for f in F.families(stc, len(x), lim, 4.0, p.nodes):
        r, J = f(x)
        act = r < np.median(r)
        assert 0 < act.sum() < len(r), f.name
        Jw = f.jacobian_where(x, act)
        assert np.array_equal(Jw.indptr, J.indptr) and np.array_equal(Jw.indices, J.indices), f.name
        dense, full = Jw.toarray(), J.toarray()
        assert np.array_equal(dense[act], full[act]) and not dense[~act].any(), f.name
        nodes, grads = f.stencil_where(x, act)
        assert not grads[~act].any() and np.abs(grads[act]).max() > 0, f.name
        rows = np.flatnonzero(act)  # the rigid family's block path asks these rows alone
        assert np.array_equal(f.rows_jacobian(x, rows, len(r)).toarray(), full[rows]), f.name


def _print_pads(pattern, state):
    """The pad areas ``print`` measures ``(H, 2)``, or its refusal."""
    pr = load_printer("prusa-mk4")
    plan = printgeom.closed_plan(pattern, state, pr)
    return shapely.area(printgeom.strip_outlines(plan, pr, check=False).pads)


def _row_pads(pattern, state):
    top = pattern.topology
    lim = MK4
    args = PR.pad_args(
        top.tiles, top.hinge_tiles, top.hinge_corner, top.fold(state).fold_corner_ends
    )
    g = PR.pad_rows(pattern.nodes, *args, *PR.strip_pad(lim, 1.0))
    return (g.v * lim.strip_width_mm + lim.strip_pad_mm2).reshape(-1, 2)


@pytest.mark.parametrize("state", [1, 2])
@pytest.mark.parametrize("k", [1.25, 1.6])
def test_pad_rows_are_the_pads_print_measures(state, k):
    """The 8x8 circle at 1.25 and 1.6 times its size (clipped pads of 4.2 to 16 mm²): the rows' areas are
    print's to a micrometre², and print refuses at 1.0 exactly where a row is negative."""
    pattern = read_pattern(TEMPLATES / "patterns" / "circle-8x8-rigid.json")
    big = fb.scaled(pattern, k)
    ref, mine = _print_pads(big, state), _row_pads(big, state)
    assert ref.min() < 0.9 * ref.max()  # some pads are clipped
    assert np.abs(mine - ref).max() < 1e-4
    small = _row_pads(pattern, state)
    assert small.min() < MK4.strip_pad_mm2
    with pytest.raises(Exception, match="strip pads"):
        _print_pads(pattern, state)


@pytest.mark.slow
@pytest.mark.parametrize("state", [1, 2])
def test_kagome_pad_rows_are_the_pads_print_measures(state):
    """The standard 4x4 kagome at 1.1 times 10 mm triangles (pads clipped by every triangle): the kagome rows
    (kagome_fab) carry the pads, and their areas are print's."""
    from fabkiri.design.kagome import fabrication as KF
    from fabkiri.mechanics.contract import with_contracted_states
    from fabkiri.pattern.kinds.kagome.lattice import standard_kagome

    k = with_contracted_states(standard_kagome(4, 4, tile_size=11.0))
    ref = _print_pads(k, state)
    lim = F.FabricationLimits(**{**MK4.to_dict(), "source": "", "print_state": state})
    (pads,) = [r for r in KF.rows(k, lim, 1.0) if r.name == "fabrication_strip_pads"]
    mine = (pads.g(k.nodes).v * lim.strip_width_mm + lim.strip_pad_mm2).reshape(-1, 2)
    assert ref.max() < 15.0 and np.abs(mine - ref).max() < 1e-4
    # exact gradients on triangles too (a jittered kagome; a margin that makes every soft row active)
    x = k.nodes + 0.3 * np.random.default_rng(state).standard_normal(k.nodes.shape)
    (fam,) = [
        f for f in KF.families(k, lim, 1.0, margin=100.0) if f.name == "fabrication_strip_pads"
    ]
    J = fam(x)[1].toarray()
    h = 1e-6
    for i in range(x.size):
        e = np.zeros(x.size)
        e[i] = h
        fd = (fam.residual(x + e.reshape(x.shape)) - fam.residual(x - e.reshape(x.shape))) / (2 * h)
        assert np.abs(J[:, i] - fd).max() < 1e-5
