"""Kagome inverse design (design/kagome/fit.py): the rows beyond closure, the lattice's mirrors, and fits
that close in both states without overlaps (docs/kagome.md, "Design")."""

from __future__ import annotations

import numpy as np
import pytest
from fabkiri.design.kagome import constraints as K
from fabkiri.design.kagome import rows as KR
from fabkiri.pattern.kinds.kagome.lattice import standard_kagome

from .kagome_routes import design_solving_only


def _fd_check(fam, x, h=1e-6):
    r, J = fam(x)
    fd = np.zeros(J.shape)
    for i in range(x.size):
        d = np.zeros(x.size)
        d[i] = h
        fd[:, i] = (fam(x + d.reshape(x.shape))[0] - fam(x - d.reshape(x.shape))[0]) / (2 * h)
    return r, np.abs(J.toarray() - fd).max()


def test_inequality_and_symmetry_jacobians_match_finite_differences():
    p = standard_kagome(4, 5, angle_deg=50.0)
    x = p.nodes / p.tile_size + 0.05 * np.random.default_rng(3).standard_normal(p.nodes.shape)
    # floors above the values at x, so every row is active and its gradient is checked
    for fam in (
        KR.gap_family(p, np.radians(130.0), np.radians(100.0)),
        KR.quality_family(p, 1.01),
        KR.fan_family(p, 2 * np.pi - np.radians(120.0)),
        KR.symmetry_family(KR.mirror_map(standard_kagome(4, 5), "y"), "y", p.topology.n_nodes),
    ):
        r, err = _fd_check(fam, x)
        assert np.count_nonzero(r) > 0 and err <= 1e-7, fam.name


def test_inequalities_are_inactive_on_the_standard_and_catch_a_folded_tile():
    p = standard_kagome(4, 5)
    x = p.nodes / p.tile_size
    fams = (
        KR.gap_family(p, np.radians(10.0)),
        KR.quality_family(p, 0.35),
        KR.fan_family(p, np.radians(10.0)),
    )
    assert all(not f(x)[0].any() for f in fams)
    q, _ = KR.tile_quality(x, p.topology.tiles)
    assert np.allclose(q, 1.0)  # equilateral
    y = x.copy()
    t = p.topology.tiles[7]
    y[t[2]] = (
        y[t[0]] + y[t[1]] - y[t[2]]
    )  # reflect a corner through the opposite edge: the tile folds over
    assert KR.tile_quality(y, p.topology.tiles)[0][7] < 0 and fams[1](y)[0][7] < 0


@pytest.mark.parametrize("rows, cols", [(4, 5), (6, 11), (5, 18), (3, 4)])
def test_tip_sides_follow_the_lattice(rows, cols):
    p = standard_kagome(rows, cols)
    order = KR.tip_order(p)
    side = KR.tip_sides(p, order)
    n = np.bincount(side, minlength=4)
    top_ups = sum((rows - 1 + c) % 2 == 0 for c in range(cols))
    assert n.tolist() == [cols // 2, rows, top_ups, rows]
    # counter-clockwise: B, R, T, L in turn, each side one run (the first tip is the bottom-left corner)
    runs = side[np.r_[True, side[1:] != side[:-1]]]
    assert runs.tolist() == [3, 0, 1, 2, 3]


@pytest.mark.parametrize("rows, cols, axes", [(4, 5, "yx"), (5, 7, "y"), (4, 4, "x"), (5, 6, "")])
def test_mirrors_exist_where_the_lattice_allows_them(rows, cols, axes):
    """Vertical mirror for C odd (it swaps the two hole pairings), horizontal for R even (it keeps them);
    the standard lattice lies on both mirrors' rows (at ψ = 60°: the vertical mirror maps ψ to 120° - ψ)."""
    p = standard_kagome(rows, cols)
    top = p.topology
    for axis in "yx":
        m = KR.mirror_map(p, axis)
        assert (m is not None) == (axis in axes)
        if m is None:
            continue
        assert np.array_equal(m[m], np.arange(len(m)))  # an involution
        f1 = top.fold(1)
        g1 = {(h, *sorted(e)) for h, e in zip(top.hinge_node.tolist(), f1.fold_ends.tolist())}
        image = {(int(m[h]), *sorted((int(m[a]), int(m[b])))) for h, a, b in g1}
        assert (image != g1) == (
            axis == "y"
        )  # the vertical mirror maps state 1's pairing onto state 2's
        sym = KR.symmetry_family(m, axis, top.n_nodes)
        assert np.abs(sym(p.nodes / p.tile_size)[0]).max() <= 1e-12


def test_the_symmetric_subfamily_dimension():
    """Measured: the 4x5 family has dimension 16; its vertical-mirror subfamily 8, its horizontal 9
    (modulo the one translation along the axis), about half: symmetry costs fitting freedom."""
    p = standard_kagome(4, 5)
    x = p.nodes / p.tile_size
    fams = K.families(p, (1, 2))
    _, J = K.stacked(fams, x)
    assert 2 * len(x) - K.numerical_rank(J) - 3 == 16
    for axis, dim in (("y", 8), ("x", 9)):
        sym = KR.symmetry_family(KR.mirror_map(p, axis), axis, p.topology.n_nodes)
        _, Js = K.stacked(fams + [sym], x)
        assert 2 * len(x) - K.numerical_rank(Js) - 1 == dim


def _front_door(design_kagome, rows, cols, target, size):
    from fabkiri.design.core import conformance as DC
    from fabkiri.design.targets.lookup import load_target
    from fabkiri.verify import verify_pattern

    out = design_kagome(rows, cols, target, size)
    p = out.pattern
    r = out.report
    assert r["status"] == "converged" and r["max_equality_residual"] <= 1e-10
    failed = {c.name for c in verify_pattern(p, tol_mm=0.05).failed()}
    assert failed <= {"target shape"}, failed  # both states closed, no overlaps, tiles simple
    conf = DC.deployed(p.nodes, p.topology, load_target(target, size))
    assert conf["hausdorff_rel"] == pytest.approx(r["conformance"]["hausdorff_rel"])
    return out, failed, conf["hausdorff_rel"]


def _mirror_error(p, axis):
    """Largest distance of a node's mirror image from the nearest node (mm)."""
    x = p.nodes
    flip = np.array([-1.0, 1.0]) if axis == "y" else np.array([1.0, -1.0])
    from scipy.spatial import cKDTree

    return float(cKDTree(x).query(x * flip)[0].max())


@pytest.mark.slow
@pytest.mark.xdist_group("kagome-circle-6x11-120")  # shares its design (shared_kagome_designs)
def test_a_circle_on_a_symmetric_lattice_meets_every_check(shared_kagome_designs):
    """6x11 has both mirrors, the circle too: imposed, and met to rounding. Measured 1.23 % of the size."""
    out, failed, h = _front_door(shared_kagome_designs, 6, 11, "circle", 120.0)
    assert not failed and h <= 0.02 and out.report["symmetry"] == ["y", "x"]
    assert max(_mirror_error(out.pattern, "y"), _mirror_error(out.pattern, "x")) <= 1e-9


# the 5x19 ellipse at 198 mm (a lattice of its aspect, the vertical mirror only) meeting every check within
# 1.5 %: `bench/kagome.py --check` (the circle above and the heart below take the same path)


@pytest.mark.slow
@pytest.mark.xdist_group("kagome-heart-6x11-120")  # shares its design (shared_kagome_designs)
def test_a_heart_closes_in_both_states_without_overlaps_and_reports_its_conformance(
    shared_kagome_designs,
):
    """6x11 heart at 120 mm, mirror symmetric: closed, no overlaps; the shape is missed (measured 6.84 % of
    the size since session 50's stall stop, 7.4 % before; docs/kagome.md), and verify says so."""
    out, failed, h = _front_door(shared_kagome_designs, 6, 11, "heart", 120.0)
    assert failed == {"target shape"} and h <= 0.09
    assert out.report["symmetry"] == ["y"] and _mirror_error(out.pattern, "y") <= 1e-9


@pytest.mark.slow
# the 12x21 heart at 240 mm (measured 9.84 %, within 12 %) is checked by `bench/kagome.py --check`
@pytest.mark.parametrize("rows, cols, size, bound", [(6, 11, 120.0, 0.055)])
def test_a_free_heart_at_two_sizes_closes_without_overlaps(
    rows, cols, size, bound, shared_kagome_designs
):
    """Without the mirror (twice the freedom) the heart comes nearer: measured 4.63 % at 6x11 / 120 mm (4.35 %
    before session 50's stall stop) and
    9.84 % at 12x21 / 240 mm (docs/kagome.md). Closed in both states, no overlaps; the shape is missed."""
    from fabkiri.verify import verify_pattern

    out = shared_kagome_designs(rows, cols, "heart", size, symmetry=False)
    r = out.report
    assert (
        r["status"] == "converged" and r["max_equality_residual"] <= 1e-10 and r["symmetry"] == []
    )
    assert {c.name for c in verify_pattern(out.pattern, tol_mm=0.05).failed()} == {"target shape"}
    assert r["conformance"]["hausdorff_rel"] <= bound


# the 6x10 heart at 120 mm, whose first designs' candidates all overlap, closing with convex holes within
# 15 %: `bench/kagome.py --check`; the route itself, below, on a lattice small enough for one design
@pytest.mark.slow  # one design of a 4x5 lattice
def test_when_no_candidate_closes_the_front_door_designs_again_with_convex_holes(monkeypatch):
    """The front door's last route: when no candidate of the designs before closes without overlaps (the
    6x10 heart's all have tiles crossing a hole), it designs again with every hole corner at most 175°.
    Here the designs before it are given no candidate (not solved), so the route is the one taken: the
    convex-hole design is the one reported, closed in both states without overlaps."""
    from fabkiri.verify import verify_pattern

    out, routes = design_solving_only(monkeypatch, "convex", 4, 5, "heart", 80.0)
    r = out.report
    assert routes == ["first", "pairs", "convex"]
    assert (
        r["convex_holes"] is True
        and r["pair_rows"] is False
        and r["max_equality_residual"] <= 1e-10
    )
    assert r["status"] == "converged"
    assert {c.name for c in verify_pattern(out.pattern, tol_mm=0.05).failed()} <= {"target shape"}


def test_convex_rows_bound_the_hole_corners_only():
    p = standard_kagome(4, 5)
    x = p.nodes / p.tile_size
    assert not KR.gap_family(p, np.radians(10.0), np.radians(5.0))(x)[0].any()  # 120° corners
    # a bound below 120°: every hole corner's row is active, the exterior gaps' are not
    r, _ = KR.gap_family(p, np.radians(10.0), np.radians(70.0))(x)
    hole_gaps = sum(
        int(
            (
                p.topology.gap_face[np.arange(p.topology.n_hinges), p.topology.fold(s).fold_gap]
                >= 0
            ).sum()
        )
        for s in (1, 2)
    )
    assert np.count_nonzero(r) == hole_gaps < 2 * p.topology.n_hinges


def test_a_hole_corner_gap_may_have_its_own_floor():
    """``hole_floor``: the gaps that are a hole's corner are held above it, the outline's gaps above
    ``floor`` (the outline's gaps keep the end tiles of two rows apart; docs/kagome.md, "What limits
    the fit")."""
    p = standard_kagome(4, 5)
    x = p.nodes / p.tile_size  # every gap 120°
    top = p.topology
    hole = np.concatenate(
        [top.gap_face[np.arange(top.n_hinges), top.fold(s).fold_gap] >= 0 for s in (1, 2)]
    )
    r, _ = KR.gap_family(p, np.radians(10.0), hole_floor=np.radians(130.0))(x)
    assert np.allclose(r[hole], np.radians(-10.0)) and not r[~hole].any() and (~hole).any()
    r, _ = KR.gap_family(p, np.radians(130.0), hole_floor=np.radians(10.0))(x)
    assert np.allclose(r[~hole], np.radians(-10.0)) and not r[hole].any()
    r, err = _fd_check(
        KR.gap_family(p, np.radians(130.0), hole_floor=np.radians(125.0)),
        x + 0.05 * np.random.default_rng(4).standard_normal(x.shape),
    )
    assert np.count_nonzero(r) > 0 and err <= 1e-7


def test_symmetry_is_every_shared_mirror_one_named_mirror_or_none():
    """``design(symmetry=...)``: True takes every mirror the lattice and the target share, a named axis
    that one alone (refused when the lattice or the target lacks it), False none."""
    from fabkiri.design.kagome.fit import mirror_axes
    from fabkiri.design.targets import lookup as TG
    from fabkiri.errors import InputError

    odd, even = standard_kagome(6, 11), standard_kagome(6, 10)  # a vertical mirror needs C odd
    circle, heart = TG.circle().scaled_to(120.0), TG.heart().scaled_to(120.0)
    assert [a for a, _ in mirror_axes(odd, circle)] == ["y", "x"]
    assert [a for a, _ in mirror_axes(odd, circle, "y")] == ["y"]
    assert [a for a, _ in mirror_axes(odd, heart)] == ["y"]  # a heart has no horizontal mirror
    assert mirror_axes(odd, circle, False) == []
    with pytest.raises(InputError, match="no mirror about the y axis"):
        mirror_axes(even, circle, "y")
    with pytest.raises(InputError, match="not symmetric about the x axis"):
        mirror_axes(odd, heart, "x")


def test_cli_kagome_symmetry_that_the_lattice_lacks_is_refused(tmp_path, run_cli):
    code, _, err = run_cli(
        "design",
        "--lattice",
        "kagome",
        "--tiles",
        "6x10",
        "--target",
        "circle",
        "--symmetry",
        "y",
        "-o",
        tmp_path / "k.json",
    )
    assert code == 2 and "no mirror about the y axis" in err and len(err.strip().splitlines()) == 1
    assert not (tmp_path / "k.json").exists()


def test_damped_lawson_steps_grow_the_weights_by_the_square_root_of_the_miss():
    """The damped Lawson route: a row that misses four times another gets twice its squared weight; the
    full route keeps the full ratio (docs/kagome.md, "Other Lawson routes on a cut lattice")."""
    from fabkiri.design.kagome import fit as KF
    from fabkiri.design.targets.lookup import load_target

    p = standard_kagome(2, 3, tile_size=10.0)
    rows, x0, _ = KF.fit_rows(p, load_target("circle", 30.0), symmetry=False)
    for power in (KF.DAMPED_LAWSON_POWER, 1.0):
        w = KF.lawson(rows, x0, power)
        for f in rows.fit:
            miss = np.abs(f.residual(x0))
            a, b = np.argsort(miss)[[-1, len(miss) // 2]]
            assert miss[b] > 0 and w[f.name][a] < 1.0e3**0.5  # not clipped
            ratio = (w[f.name][a] / w[f.name][b]) ** 2
            assert ratio == pytest.approx((miss[a] / miss[b]) ** power, rel=1e-9), f.name
    assert KF.DAMPED_LAWSON_POWER == 0.5
