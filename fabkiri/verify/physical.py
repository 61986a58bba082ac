"""Physical checks of a cut layout beyond the tile shapes: every ligament of a ligament sheet is
there and uncut, and every tape hinge has its mark (when the layout carries marks).

Both work on the tiles as recovered on the sheet (``cut_shapes``, design size, sheet frame), so a
file without its manifest is checked the same way; each failure names the hinge.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import shapely

from ..kdtree import KDTree
from ..pattern import geometry
from ..pattern.model import Pattern
from .report import Check

TOUCH_MM = 0.01  # a strip meets a tile core within this
MARK_EDGE_MM = 1.0  # a mark's end lies within this of its corner's edge
MARK_CORNER_FRAC = 0.5  # a tape piece covers this fraction of each corner edge ...
MARK_REACH_MM = 8.0  # ... but no further than this along an edge
MARK_FIT = 0.8  # the writer draws a mark when its margins take less than this share of the chord
MARK_EXPECT = 0.6  # the verifier asks for one only below this share (recovered tiles are ~µm off the writer's)
MARK_EXPECT_MARGIN_MM = (
    0.75  # ... with the writer's margin for a kerf up to 0.5 mm (0.5 + kerf / 2)
)
MARK_SPAN = 0.3  # a mark spans at least this fraction of the corner's shorter edge (at most 16 mm), times sin(angle)


def ligament_check(
    pattern: Pattern,
    material: shapely.Geometry,
    cores: np.ndarray,
    have: np.ndarray,
    cuts: list[np.ndarray],
    hinges: np.ndarray,
    g: str,
) -> Check:
    """Every hinge in ``hinges`` has a strip of material joining its two tiles' cores, and no cut
    line runs into that strip.

    ``material``: the sheet piece (outer outlines minus holes, after the kerf); ``cores``: shapely
    polygons of the tiles as cut (shrunk), per design tile (None where not found); ``cuts``: every
    CUT polyline, closed or not, so a stray cut across a strip is seen.
    """
    A, B = pattern.topology.hinge_tiles.T
    ids = np.flatnonzero(have)
    strips = shapely.get_parts(
        shapely.difference(
            material,
            shapely.unary_union(
                shapely.buffer(cores[ids], TOUCH_MM / 2, join_style="mitre", mitre_limit=10.0)
            ),
        )
    )
    strips = strips[shapely.area(strips) > 0]
    tree = shapely.STRtree(strips)
    si, ci = tree.query(cores[ids], predicate="dwithin", distance=TOUCH_MM)  # (core, strip) pairs
    touching: dict[int, set[int]] = {}
    for c, s in zip(ids[si], ci):
        touching.setdefault(int(s), set()).add(int(c))
    by_pair: dict[tuple[int, int], list[int]] = {}
    for s, tiles in touching.items():
        for a in tiles:
            for b in tiles:
                if a < b:
                    by_pair.setdefault((a, b), []).append(s)
    lines = (
        shapely.multilinestrings([shapely.linestrings(c) for c in cuts if len(c) >= 2])
        if cuts
        else None
    )
    if lines is not None:  # asked once per hinge: its index built once, not per call
        shapely.prepare(lines)
    missing, severed = [], []
    for h in np.asarray(hinges, dtype=int).tolist():
        a, b = sorted((int(A[h]), int(B[h])))
        cand = by_pair.get((a, b), [])
        if not cand:
            missing.append(h)
            continue
        inner = shapely.buffer(strips[cand], -TOUCH_MM / 5, join_style="mitre", mitre_limit=10.0)
        if lines is not None and shapely.intersects(lines, inner).all():
            severed.append(h)
    bad = missing + severed
    first = min(bad) if bad else None
    detail = (
        f"{len(hinges) - len(bad)} of {len(hinges)} ligaments joined and uncut"
        + (f"; missing {missing[:20]}" if missing else "")
        + (f"; cut into {severed[:20]}" if severed else "")
    )
    return Check(
        f"{g}: every ligament present and unsevered",
        ok=not bad,
        value=len(bad),
        tol=0,
        unit="count",
        group=g,
        worst=f"hinge {first}" if first is not None else None,
        detail=detail,
    )


def _corner_marked(Q: np.ndarray, k: int, segs: np.ndarray) -> bool:
    """Whether a segment of ``segs`` (n, 2, 2) spans corner ``k`` of tile ``Q``: one end within
    MARK_EDGE_MM of each of its two edges, both inside the corner, long enough not to be a letter."""
    n = len(Q)  # the tile arity
    q, q1, q0 = Q[k], Q[(k + 1) % n], Q[(k - 1) % n]
    e1, e0 = q1 - q, q0 - q
    l1, l0 = float(np.linalg.norm(e1)), float(np.linalg.norm(e0))
    if not len(segs) or l1 == 0 or l0 == 0:
        return False
    p, r = segs[:, 0], segs[:, 1]

    def near(
        x, e, le
    ):  # within the band along edge e, on the tile's side, within the edge's length
        d = geometry.cross2(e, x - q) / le
        t = geometry.dot2(x - q, e) / le
        return (np.abs(d) <= MARK_EDGE_MM) & (t > 0) & (t < le)

    spans = (near(p, e1, l1) & near(r, e0, l0)) | (near(r, e1, l1) & near(p, e0, l0))
    sin = float(abs(geometry.cross2(e1, e0))) / (l1 * l0)  # an acute corner's mark is shorter
    long = np.linalg.norm(r - p, axis=1) >= MARK_SPAN * min(l1, l0, 16.0) * max(sin, 0.2)
    return bool((spans & long).any())


def tape_reach(q: np.ndarray, q1: np.ndarray, frac: float = MARK_CORNER_FRAC) -> np.ndarray:
    """Fraction of the edge q -> q1 covered by a corner's tape: ``frac``, at most MARK_REACH_MM."""
    return np.minimum(frac, MARK_REACH_MM / np.maximum(np.linalg.norm(q1 - q, axis=1), 1e-300))


def tape_mark_chords(
    Q: np.ndarray, tiles: np.ndarray, ks: np.ndarray, margin: float, fit: float = MARK_FIT
) -> np.ndarray:
    """The tape mark of corner ``ks`` of each tile in ``tiles``: the chord where the tape ends,
    ``margin`` inside both tile edges, ``(n, 2, 2)``; NaN where the margins take ``fit`` of the chord
    or more (no room). One rule for the writer (``fit=MARK_FIT``) and the check (``MARK_EXPECT``)."""
    q = Q[tiles, ks]
    n = Q.shape[1]  # the tile arity
    q1 = Q[tiles, (ks + 1) % n]
    q0 = Q[tiles, (ks - 1) % n]
    a = q + tape_reach(q, q1)[:, None] * (q1 - q)
    b = q + tape_reach(q, q0)[:, None] * (q0 - q)
    chord = b - a
    L = np.linalg.norm(chord, axis=1)
    u = chord / np.maximum(L, 1e-300)[:, None]
    e1 = (q1 - q) / np.maximum(np.linalg.norm(q1 - q, axis=1), 1e-300)[:, None]
    e0 = (q0 - q) / np.maximum(np.linalg.norm(q0 - q, axis=1), 1e-300)[:, None]
    t1 = margin / np.maximum(np.abs(geometry.cross2(e1, u)), 1e-12)
    t0 = margin / np.maximum(np.abs(geometry.cross2(e0, u)), 1e-12)
    seg = np.stack([a + t1[:, None] * u, b - t0[:, None] * u], 1)
    seg[~(t1 + t0 < fit * L)] = np.nan
    return seg


def _segments_near(segs: dict[int, np.ndarray]) -> Callable[[int, np.ndarray, int], np.ndarray]:
    """``near(sheet, Q, k)``: the sheet's segments whose first end is close enough to corner ``k`` of
    ``Q`` to span it (a KD-tree per sheet: every corner against every engraved segment, labels
    included, took most of a 32x32 sheet's check)."""
    trees = {s: KDTree(v[:, 0]) for s, v in segs.items() if len(v)}
    none = np.zeros((0, 2, 2))

    def near(sheet: int, Q: np.ndarray, k: int) -> np.ndarray:
        if sheet not in trees:
            return none
        reach = geometry.edge_lengths(Q)[[k, (k - 1) % len(Q)]].max() + 2 * MARK_EDGE_MM
        return segs[sheet][trees[sheet].query_ball_point(Q[k], reach)]

    return near


def mark_status(
    pattern: Pattern,
    cut_shapes: np.ndarray,
    have: np.ndarray,
    found_on: np.ndarray,
    marks: dict[int, list[np.ndarray]],
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """For the tape hinges whose two tiles are on one sheet: their indices, whether each has a mark
    across its corner on one of its two tiles (an ENGRAVE chord where the tape ends), and whether its
    second tile's corner (where ``fabkiri cut`` draws it) has room for one: :func:`tape_mark_chords`,
    stricter than the writer (``MARK_EXPECT``, ``MARK_EXPECT_MARGIN_MM``) and long enough to be told from
    a letter, so a mark the writer left out, or drew too short to recognise, is never asked for."""
    top = pattern.topology
    A, B = top.hinge_tiles.T
    cA, cB = top.hinge_corner.T
    hs = np.flatnonzero(have[A] & have[B] & (found_on[A] == found_on[B]))
    near = _segments_near(
        {
            s: np.array([q[i : i + 2] for q in v for i in range(len(q) - 1)]).reshape(-1, 2, 2)
            for s, v in marks.items()
        }
    )
    marked = np.array(
        [
            _corner_marked(
                cut_shapes[B[h]], cB[h], near(int(found_on[B[h]]), cut_shapes[B[h]], cB[h])
            )
            or _corner_marked(
                cut_shapes[A[h]], cA[h], near(int(found_on[A[h]]), cut_shapes[A[h]], cA[h])
            )
            for h in hs
        ],
        dtype=bool,
    ).reshape(-1)
    # room: the writer's chord, taken stricter, exists and is one this check recognises (a sharp corner's
    # short chord is drawn but reads as a letter stroke)
    chords = tape_mark_chords(cut_shapes, B[hs], cB[hs], MARK_EXPECT_MARGIN_MM, MARK_EXPECT)
    room = np.array(
        [
            np.isfinite(ch).all() and _corner_marked(cut_shapes[B[h]], cB[h], ch[None])
            for h, ch in zip(hs, chords)
        ],
        dtype=bool,
    ).reshape(-1)
    return hs, marked, room


def tape_mark_check(hs: np.ndarray, marked: np.ndarray, room: np.ndarray, g: str) -> Check:
    """Every tape hinge with room for a mark has one (see :func:`mark_status`)."""
    lacking = hs[room & ~marked]
    return Check(
        f"{g}: tape marks at every hinge",
        ok=not len(lacking),
        value=int(len(lacking)),
        tol=0,
        unit="count",
        group=g,
        worst=f"hinge {int(lacking[0])}" if len(lacking) else None,
        detail=f"{int(marked.sum())} of {len(hs)} hinges marked (ENGRAVE chord across the hinge corner)"
        + (f"; unmarked {lacking[:20].tolist()}" if len(lacking) else ""),
    )
