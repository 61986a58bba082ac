"""The strip pads' areas of the fabricability summary: clipped in numpy where pads and tiles are convex."""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import pytest
import shapely
from fabkiri.exchange.pattern_json import read_pattern
from fabkiri.fabricate import fabricability, planrules
from fabkiri.mechanics.contract import contract
from fabkiri.pattern import geometry

DATA = Path(__file__).parents[1] / "data"
SQUARE = np.array([[0, 0], [1, 0], [1, 1], [0, 1]], float)


def _convex_quads(rng, n):
    ang = np.sort(rng.uniform(0, 2 * np.pi, (n, 4)), 1)
    r = rng.uniform(0.5, 2, (n, 1, 1))
    return np.stack([np.cos(ang), np.sin(ang)], -1) * r + rng.uniform(-1, 1, (n, 1, 2))


def _geos(a, b):
    return shapely.area(shapely.intersection(shapely.polygons(a), shapely.polygons(b)))


def test_clipped_areas_are_geos_intersection_areas():
    rng = np.random.default_rng(1)
    a, b = _convex_quads(rng, 2000), _convex_quads(rng, 2000)
    a[::3], b[::2] = a[::3, ::-1], b[::2, ::-1]  # either orientation
    dart = a.copy()
    dart[:, 0] = 0.9 * a[:, 2] + 0.1 * a[:, 0]  # concave subjects (the clip stays convex)
    assert geometry.strictly_convex(b).all() and not geometry.strictly_convex(dart).all()
    for subject in (a, dart):
        assert np.allclose(
            geometry.clipped_areas(subject, b), _geos(subject, b), rtol=0, atol=1e-13
        )


@pytest.mark.parametrize(
    "shift, scale, want",
    [((0, 0), 1, 1.0), ((1, 0), 1, 0.0), ((0.5, 0), 1, 0.5), ((0, 0), 0.5, 0.25), ((2, 2), 1, 0.0)],
)
def test_clipped_areas_of_shared_and_touching_edges(shift, scale, want):
    other = SQUARE * scale + np.array(shift, float)
    assert geometry.clipped_areas(SQUARE[None], other[None])[0] == pytest.approx(want, abs=1e-15)
    assert geometry.clipped_areas(other[None], SQUARE[None])[0] == pytest.approx(want, abs=1e-15)


def test_no_pads_no_areas():
    none = np.zeros((0, 4, 2))
    assert geometry.clipped_areas(none, none).shape == (0,)


def test_the_summary_clips_a_designs_pads_without_geos(monkeypatch):
    p = read_pattern(DATA / "circle-16x16-rigid.json")
    want = fabricability.summary(p)

    def refuse(*a, **k):
        raise AssertionError("GEOS intersection")

    monkeypatch.setattr(planrules.shapely, "intersection", refuse)
    assert fabricability.summary(p) == want


def test_a_designs_pad_areas_are_geoss(monkeypatch):
    p = read_pattern(DATA / "heart-16x16-rigid.json")
    top = p.topology
    c = np.asarray(p.contracted[1], float)
    ends = top.fold(1).fold_corner_ends
    printer = fabricability.load_printer("prusa-mk4")
    H = top.n_hinges
    args = (c, top.hinge_tiles, top.hinge_corner, ends, printer, np.full(H, 3.0), np.arange(H))
    mine = planrules._pad_areas(*args)
    # a tile that is not strictly convex sends the whole call to GEOS
    monkeypatch.setattr(
        planrules.geometry, "strictly_convex", lambda polys: np.zeros(len(polys), bool)
    )
    theirs = planrules._pad_areas(*args)
    assert (theirs > 0).any()
    assert np.allclose(mine, theirs, rtol=1e-12, atol=1e-12)


def _same_face_pairs_by_loop(hinge_tiles, face, n_tiles):
    """The pairs as the summary listed them before (a loop per tile over its hinges)."""
    H = len(hinge_tiles)
    t, h, side = hinge_tiles.ravel(), np.repeat(np.arange(H), 2), np.tile([0, 1], H)
    order = np.lexsort((h, t))
    t, h, side = t[order], h[order], side[order]
    out = []
    for a, b in zip(
        np.searchsorted(t, np.arange(n_tiles)), np.searchsorted(t, np.arange(n_tiles), "right")
    ):
        for i in range(a, b):
            for j in range(i + 1, b):
                if face[h[i]] == face[h[j]]:
                    out.append((t[i], h[i], side[i], h[j], side[j]))
    return tuple(np.asarray(out, dtype=np.int64).reshape(-1, 5).T)


@pytest.mark.parametrize("name", ["heart-16x16-rigid.json", "kagome-heart-6x11.json"])
def test_same_face_pairs_are_listed_as_the_loop_listed_them(name):
    from fabkiri.pattern import thinness as fab

    top = read_pattern(DATA / name).topology
    rng = np.random.default_rng(2)
    for face in (np.zeros(top.n_hinges, np.int64), rng.integers(0, 2, top.n_hinges)):
        got = fab.same_face_pairs(top.hinge_tiles, face, top.n_tiles)
        want = _same_face_pairs_by_loop(top.hinge_tiles, face, top.n_tiles)
        assert len(got) == 5 and all(np.array_equal(a, b) for a, b in zip(got, want))
        assert len(got[0]) > 0


@pytest.mark.parametrize("name", ["heart-16x16-rigid.json", "star-16x16-nonrigid.json"])
@pytest.mark.parametrize("printer", ["prusa-mk4", "bambu-x1-petg"])  # two gaps
def test_pads_that_hold_the_needed_rectangle_are_the_pads_not_short(name, printer):
    """The summary's first pass clips only the pads not shown to hold the needed area: the short pads
    are those of clipping every pad, at scales where some pads are short, some barely not, and boundary
    tiles' pads among them; every pad left unclipped really has the area (GEOS)."""
    p = read_pattern(DATA / name)
    top, c = p.topology, np.asarray(contract(p, 1).corners, float)  # as the summary closes it
    ends, pr, H = top.fold(1).fold_corner_ends, fabricability.load_printer(printer), top.n_hinges
    need = 0.25 * pr.strip_width_mm * min(pr.strip_reach_mm, pr.strip_width_mm)
    held_any = short_any = 0
    for scale in (0.5, 1.0, 1.6, 2.2, 3.0, 6.0):
        args = (c, top.hinge_tiles, top.hinge_corner, ends, pr, np.full(H, scale), np.arange(H))
        every, first = planrules._pad_areas(*args), planrules._pad_areas(*args, need)
        assert np.array_equal(first.min(1) < need, every.min(1) < need)
        held = np.isinf(first)
        assert (every[held] >= need).all() and np.array_equal(first[~held], every[~held])
        held_any, short_any = held_any + held.sum(), short_any + (every < need).sum()
    assert held_any and short_any


def test_a_degenerate_pad_is_neither_held_nor_warned_about():
    """A tile whose edge turns back (its mitre 0/0) has no pad: the first pass gives it the same area, 0, and
    no warning the plain clipping does not give (its frames' NaN are compared, never held)."""
    p = read_pattern(DATA / "heart-16x16-rigid.json")
    top, c = p.topology, np.array(p.contracted[1], float)
    t = int(top.hinge_tiles[0, 0])
    c[t] = c[t, 0] + np.array([[0, 0], [1, 0], [0.5, 0], [0, 1]]) * 0.2 * p.tile_size
    ends, pr, H = (
        top.fold(1).fold_corner_ends,
        fabricability.load_printer("prusa-mk4"),
        top.n_hinges,
    )
    need = 0.25 * pr.strip_width_mm * min(pr.strip_reach_mm, pr.strip_width_mm)
    args = (c, top.hinge_tiles, top.hinge_corner, ends, pr, np.full(H, 3.0), np.arange(H))
    with warnings.catch_warnings(record=True) as plain:
        warnings.simplefilter("always")
        every = planrules._pad_areas(*args)
    with warnings.catch_warnings(record=True) as first_pass:
        warnings.simplefilter("always")
        first = planrules._pad_areas(*args, need)
    assert every[0, 0] == first[0, 0] == 0.0 and np.isinf(first).any()
    assert [str(w.message) for w in first_pass] == [str(w.message) for w in plain]
    assert np.array_equal(first.min(1) < need, every.min(1) < need)
