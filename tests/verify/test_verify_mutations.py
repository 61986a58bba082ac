"""Mutation tests of the layout verifier at the default tolerance (0.05 mm).

From valid cut files (in-place tape linework and separate kerf-offset tiles,
DXF and SVG) of a pattern whose tiles are pairwise non-congruent and chiral,
every perturbed layout must be rejected and every harmless variant accepted.
"""

from __future__ import annotations

import numpy as np
import pytest
from fabkiri.verify import verify_layout

from .. import layout_fixtures as lf

KERF = 0.1
FORMATS = ("dxf", "svg")


@pytest.fixture(scope="module")
def pattern():
    return lf.distinct_pattern()


def _write(tmp_path, name, pattern, corners, hinge, fmt, **kw):
    kw.setdefault("kerf_offset", KERF if hinge == "separate" else 0.0)
    return lf.write_layout(tmp_path / name, pattern, corners, hinge=hinge, fmt=fmt, **kw)


def _base(pattern, hinge, rng):
    if hinge == "tape":
        return lf.in_place_corners(pattern, 1, rng.uniform(0, 2 * np.pi), rng.uniform(-50, 50, 2))
    return lf.exploded_corners(pattern, rng)


def boundary_tiles(pattern):
    top = pattern.topology
    return np.unique(np.flatnonzero(np.isin(pattern.tiles, top.free_nodes).any(1)))


def mutations(pattern, rng):
    """(description, hinge kind, mutated sheet corners) — at least 200 cases."""
    T = pattern.n_tiles
    out = []
    for n in range(36):  # one corner moved 0.1 mm
        hinge = ("tape", "separate")[n % 2]
        t, k = rng.integers(T), rng.integers(4)
        C = lf.move_corner(_base(pattern, hinge, rng), t, k, 0.1, rng.uniform(0, 2 * np.pi))
        out.append((f"corner {k} of tile {t} moved 0.1 mm", hinge, C))
    for _ in range(30):  # one tile rotated 0.5° in place (only meaningful in place)
        t = rng.integers(T)
        C = lf.rotate_tile(_base(pattern, "tape", rng), t, 0.5 * rng.choice([-1, 1]))
        out.append((f"tile {t} rotated 0.5°", "tape", C))
    for _ in range(30):  # two tiles swapped on the sheet
        i, j = rng.choice(T, 2, replace=False)
        C = lf.swap_tiles(_base(pattern, "tape", rng), i, j)
        out.append((f"tiles {i} and {j} swapped", "tape", C))
    for _ in range(30):  # a tile mirrored
        hinge = ("tape", "separate")[n % 2]
        t = rng.integers(T)
        out.append((f"tile {t} mirrored", hinge, lf.mirror_tile(_base(pattern, hinge, rng), t)))
    edge = boundary_tiles(pattern)
    for _ in range(30):  # a tile dropped (in place: a boundary tile; interior ones have no own cut)
        hinge = ("tape", "separate")[n % 2]
        t = rng.choice(edge) if hinge == "tape" else rng.integers(T)
        out.append((f"tile {t} dropped", hinge, lf.drop_tile(_base(pattern, hinge, rng), t)))
    for _ in range(30):  # a tile scaled 1 %
        hinge = ("tape", "separate")[n % 2]
        t = rng.integers(T)
        f = rng.choice([0.99, 1.01])
        out.append((f"tile {t} scaled {f}", hinge, lf.scale_tile(_base(pattern, hinge, rng), t, f)))
    for n in range(16):  # the whole sheet scaled 1 %
        hinge = ("tape", "separate")[n % 2]
        f = (0.99, 1.01)[(n // 2) % 2]
        out.append((f"sheet scaled {f}", hinge, _base(pattern, hinge, rng) * f))
    return out


@pytest.mark.slow
def test_at_least_200_mutations_all_rejected(pattern, tmp_path):
    rng = np.random.default_rng(2024)
    cases = mutations(pattern, rng)
    assert len(cases) >= 200
    accepted = []
    for n, (what, hinge, C) in enumerate(cases):
        fmt = FORMATS[n % 2]
        path = _write(tmp_path, f"m{n}", pattern, C, hinge, fmt)
        rep = verify_layout(pattern, path)
        if rep.ok:
            accepted.append(f"{what} ({hinge}, {fmt})")
    assert not accepted, accepted


def test_mutations_name_the_right_failure(pattern, tmp_path):
    rng = np.random.default_rng(7)
    X = _base(pattern, "separate", rng)
    rep = verify_layout(
        pattern, _write(tmp_path, "mir", pattern, lf.mirror_tile(X, 5), "separate", "dxf")
    )
    chk = rep.get("layout: (a) cut tiles congruent to design")
    assert not chk.ok and chk.worst == "tile 5" and "mirrored tiles [5]" in chk.detail
    rep = verify_layout(
        pattern, _write(tmp_path, "drop", pattern, lf.drop_tile(X, 3), "separate", "dxf")
    )
    chk = rep.get("layout: tiles recovered")
    assert not chk.ok and chk.value == pattern.n_tiles - 1 and chk.worst == "tile 3"
    assert not rep.get("layout: (d) every hinge present").ok
    Y = _base(pattern, "tape", rng)
    rep = verify_layout(
        pattern, _write(tmp_path, "rot", pattern, lf.rotate_tile(Y, 11, 0.5), "tape", "svg")
    )
    assert not rep.ok
    # failures are listed first in the text table
    lines = rep.to_text().splitlines()
    assert lines[2].startswith("FAIL")


def valid_variants(pattern, rng):
    out = []
    for n in range(56):
        hinge = ("tape", "separate")[n % 2]
        C = _base(
            pattern, hinge, rng
        )  # random sheet rotation + translation / random exploded placement
        if rng.random() < 0.5:
            C = C + rng.uniform(-500, 500, 2)
        kerf = float(rng.choice([0.0, 0.05, 0.1, 0.15])) if hinge == "separate" else 0.0
        out.append((hinge, C, kerf))
    return out


@pytest.mark.slow
def test_at_least_50_valid_variants_all_accepted(pattern, tmp_path):
    rng = np.random.default_rng(99)
    cases = valid_variants(pattern, rng)
    assert len(cases) >= 50
    rejected = []
    for n, (hinge, C, kerf) in enumerate(cases):
        fmt = FORMATS[(n // 2) % 2]
        order = None
        if hinge == "separate":
            C = C[rng.permutation(len(C))]  # tiles reordered
        else:
            order = rng.permutation(len(lf.unique_edges(C)))  # linework reordered
        path = _write(tmp_path, f"v{n}", pattern, C, hinge, fmt, kerf_offset=kerf, order=order)
        rep = verify_layout(pattern, path)
        if not rep.ok:
            rejected.append((hinge, fmt, kerf, [(c.name, c.value) for c in rep.failed()]))
    assert not rejected, rejected


def test_plain_files_from_other_tools(pattern, tmp_path):
    """No manifest, no CUT layer conventions needed: closed outlines are the tiles."""
    rng = np.random.default_rng(5)
    for fmt in FORMATS:
        for hinge in ("tape", "separate"):
            C = _base(pattern, hinge, rng)
            path = _write(
                tmp_path,
                f"plain-{fmt}-{hinge}",
                pattern,
                C,
                hinge,
                fmt,
                kerf_offset=0.0,
                manifest=False,
                reference=False,
            )
            rep = verify_layout(pattern, path)
            assert rep.ok, rep.to_text()
            assert rep.meta["layout"] == ("in-place" if hinge == "tape" else "separate")
            assert any("(b)" in n for n in rep.names()) == (hinge == "tape")
    # an in-place sheet of closed state 2 without a manifest: the state is found, not assumed
    C = lf.in_place_corners(pattern, 2, 1.0)
    path = _write(
        tmp_path, "plain-state2", pattern, C, "tape", "dxf", manifest=False, reference=False
    )
    rep = verify_layout(pattern, path)
    assert (
        rep.ok and rep.meta["state"] == 2 and "layout: (b) in place = closed state 2" in rep.names()
    )


def test_kerf_must_be_declared(pattern, tmp_path):
    """Kerf-offset outlines read without the declared offset are 0.1 mm too big: rejected."""
    rng = np.random.default_rng(6)
    path = _write(tmp_path, "k", pattern, _base(pattern, "separate", rng), "separate", "dxf")
    assert verify_layout(pattern, path).ok
    import json

    m = json.loads((path.parent / "manifest.json").read_text())
    m["kerf_offset_mm"] = 0.0
    rep = verify_layout(pattern, path, manifest=m)
    assert not rep.get("layout: (a) cut tiles congruent to design").ok
