"""A kagome lattice cut to the outline (``--trim``, design/kagome/trim.py): the cut, its rows, its fit."""

from __future__ import annotations

import numpy as np
import pytest
from fabkiri.design.kagome import rows as KR
from fabkiri.design.kagome import trim as KT
from fabkiri.design.targets.lookup import load_target
from fabkiri.errors import InputError
from fabkiri.mechanics.contract import with_contracted_states
from fabkiri.pattern.kinds.kagome.lattice import standard_kagome, trimmed_kagome
from fabkiri.verify import verify_pattern


def _cut(name: str, rows: int, cols: int, size: float = 120.0):
    target = load_target(name, size)
    keep = KT.kept_tiles(rows, cols, target)
    return target, keep, trimmed_kagome(rows, cols, keep, tile_size=10.0)


def test_the_cut_keeps_the_tiles_inside_the_outline_as_one_piece_that_closes():
    target, keep, p = _cut("circle", 10, 17)
    assert 100 < len(keep) < 170 * 0.9  # a circle fills π/4 of its box
    assert p.topology.n_tiles == len(keep)
    # the kept tiles' centres lie inside the circle scaled into the block
    w, h = np.ptp(p.nodes, axis=0)
    assert abs(w / h - 1.0) < 0.15
    closed = with_contracted_states(p)
    failed = [c.name for c in verify_pattern(closed).failed() if c.name != "target shape"]
    assert failed == []  # topology (no R x C counts to match), closure, no overlaps


def test_a_cut_lattice_names_its_block_and_tiles_not_rows_and_cols():
    _, keep, p = _cut("heart", 7, 13)
    assert p.lattice["trimmed_from"] == [7, 13]
    assert p.lattice["keep"] == sorted(keep.tolist())
    assert "rows" not in p.lattice and "cols" not in p.lattice
    # the whole block cut to every tile is the standard lattice
    full = trimmed_kagome(4, 5, np.arange(20), tile_size=10.0)
    assert np.allclose(full.nodes, standard_kagome(4, 5, tile_size=10.0).nodes)


def test_the_cut_keeps_the_largest_piece():
    heart = load_target("heart", 120)
    keep = KT.kept_tiles(10, 17, heart)
    p = trimmed_kagome(10, 17, keep, tile_size=10.0)  # would raise PatternError on two pieces
    assert p.topology.n_tiles == len(keep)


def test_a_cut_lattices_tips_face_four_sides_in_order():
    _, _, p = _cut("circle", 10, 17)
    order = KR.tip_order(p)
    sides = KR.tip_sides(p, order)
    runs = sides[np.r_[True, sides[1:] != sides[:-1]]]
    runs = runs[:-1] if runs[0] == runs[-1] and len(runs) > 1 else runs
    assert sorted(runs.tolist()) == [0, 1, 2, 3]  # one run per side
    k = int(np.flatnonzero(runs == 0)[0])
    assert np.roll(runs, -k).tolist() == [0, 1, 2, 3]  # B, R, T, L counter-clockwise


def test_a_cut_lattice_has_boundary_fans_of_its_own_tiles():
    _, keep, p = _cut("circle", 10, 17)
    fans = KR.partial_fans(p)
    assert fans and all(len(t) < 6 for t, _ in fans)
    assert max(int(t.max()) for t, _ in fans) < len(keep)


def test_a_cut_that_keeps_no_tile_is_refused_in_one_line():
    tiny = load_target("star", 120)
    with pytest.raises(InputError, match="keeps"):
        KT.kept_tiles(2, 2, tiny)


def test_the_block_for_a_count_keeps_about_that_many_tiles():
    for name in ("circle", "ellipse", "heart"):
        target = load_target(name, 120)
        rows, cols = KT.block_for(target, 130)
        assert 90 <= len(KT.kept_tiles(rows, cols, target)) <= 170


# the 10x17 block cut to a 180 mm circle (126 tiles) within 1.5 %: `bench/kagome.py --check` (the path
# of a cut lattice, in the suite: test_kagome_aspect.py's 6x11 cut to the circle)


def test_trim_on_a_quad_design_is_refused_in_one_line(tmp_path, run_cli):
    out = tmp_path / "q.json"
    code, _, err = run_cli("design", "--tiles", "4x4", "--target", "circle", "--trim", "-o", out)
    assert code == 2 and "--trim cuts kagome lattices" in err and len(err.strip().splitlines()) == 1
    assert not out.exists()


@pytest.mark.parametrize(
    "tiles, trim, cut", [(None, False, True), ((6, 11), False, False), ((6, 11), True, True)]
)
def test_the_front_door_cuts_a_lattice_chosen_from_the_outline_or_asked_to(
    monkeypatch, tiles, trim, cut
):
    """Without --tiles the lattice chosen from the outline is cut to it; --tiles RxC is the whole block
    unless --trim."""
    from fabkiri.api import kagome as AK
    from fabkiri.api.design import PatternRequest

    seen = {}

    def fake(rows, cols, target, size=None, **kw):
        seen.update(rows=rows, cols=cols, trim=kw["trim"])
        report = {"shape": {"status": "met"}}
        return AK.KagomeOutcome(None, report, False, (rows, cols))  # type: ignore[arg-type]

    monkeypatch.setattr(AK, "design_kagome", fake)
    notes: list[str] = []
    req = PatternRequest(tiles=tiles, target="circle", size=120.0, kind="kagome", trim=trim)
    AK.design_kagome_pattern(req, notify=notes.append)
    assert seen["trim"] is cut
    if tiles is None:
        assert (seen["rows"], seen["cols"]) == KT.block_for(load_target("circle", 120.0), 66)
        assert "cut to the outline" in notes[0] and "chosen from the outline" in notes[0]


def test_the_heart_lattice_chosen_from_the_outline_is_a_7x14_block():
    """`design --lattice kagome --target heart --size 120` cuts a 7x14 block to the outline; that design meets
    the 2 % shape by the other Lawson routes (measured with the tests' pinned kernels 3.27 % -> 1.16 %, with
    this machine's default ones 2.42 -> 0.92 %; docs/kagome.md "Other Lawson routes on a cut lattice"), a
    claim `bench/kagome.py --check` checks; the routes themselves, below, on a smaller block."""
    from fabkiri.api.kagome import choose_lattice

    rows, cols, _ = choose_lattice(None, load_target("heart", 120.0), trim=True)
    assert (rows, cols) == (7, 14)


@pytest.mark.slow  # three designs of an 18-tile cut lattice
def test_a_cut_lattice_that_misses_the_shape_is_designed_again_by_other_lawson_routes(monkeypatch):
    """A 4x7 block cut to an 80 mm heart misses the 2 % shape by its full Lawson steps: the front door
    designs it again damped and from the best design so far, and keeps the nearest that closes (measured:
    full 8.66 %, damped 7.89 %, from best 9.45 %). The vertical mirror is named, so it is kept on every route
    (a mirror imposed by default is first dropped: test_kagome_mirror_route.py)."""
    from fabkiri.api import kagome as AK

    real, designs = AK.design, []

    def design(*args, **kw):
        designs.append((kw.get("lawson_route", "full"), real(*args, **kw)))
        return designs[-1][1]

    monkeypatch.setattr(AK, "design", design)
    out = AK.design_kagome(4, 7, "heart", 80.0, symmetry="y", trim=True)
    r = out.report
    assert [route for route, _ in designs] == ["full", "damped", "from best"]
    assert r["status"] == "converged" and r["verify_failed"] == ["target shape"]
    h = r["conformance"]["hausdorff_rel"]
    # another route's design is kept: nearer than every candidate of the full steps
    assert h < min(c[0] for c in designs[0][1].candidates)
    assert any(h == pytest.approx(c[0], rel=1e-9) for _, d in designs[1:] for c in d.candidates)


def test_a_solve_asked_again_with_the_same_start_and_weights_is_taken_from_the_earlier_design(
    monkeypatch,
):
    """``fit.design(solves=...)``: the Lawson routes of one lattice share their first solve (the initial
    guess, uniform weights); a route's own steps (other weights) are solved; without ``solves`` each is."""
    from fabkiri.design.kagome import fit as KF
    from fabkiri.design.kagome import solve as KS

    calls: list[bool] = []

    def solve(rows, x0, max_iter=60, tol=1e-9, warm=False):  # a stand-in: the start, as if solved
        calls.append(warm)
        return KS.Solve(np.asarray(x0, float), 0, 1.0, 0.0, True)

    monkeypatch.setattr(KS, "solve", solve)
    std, target = standard_kagome(2, 3, tile_size=10.0), load_target("circle", 30.0)
    solves: dict = {}
    full = KF.design(std, target, symmetry=False, refine_steps=2, solves=solves)
    assert calls == [False, True, True]
    again = KF.design(std, target, symmetry=False, refine_steps=2, solves=solves)
    assert len(calls) == 3 and np.array_equal(
        again.pattern.nodes, full.pattern.nodes
    )  # the same solves
    KF.design(std, target, symmetry=False, refine_steps=2, solves=solves, lawson_route="damped")
    assert calls[3:] == [True, True]  # the first solve shared, the damped steps solved
    KF.design(std, target, symmetry=False, refine_steps=2, lawson_route="damped")
    assert calls[5:] == [False, True, True]  # no solves given: all three solved
