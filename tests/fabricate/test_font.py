"""The engraved single-stroke font: every glyph rendered, every pair told apart by shape."""

from __future__ import annotations

import itertools

import numpy as np
from fabkiri.fabricate.cut.text import GLYPHS, text_strokes
from PIL import Image, ImageDraw
from scipy import ndimage

CAP_PX = 100  # rendered cap height
STROKE_PX = 6
ALL_PAIRS_MIN = 0.14  # cap heights: 0.42 mm on a 3 mm label, a few laser kerfs
# the pairs a reader mixes up in a blocky font get more
CONFUSABLE = ["8B", "0O", "1I", "5S", "2Z", "6G", "0D", "0Q", "8S", "5B"]
CONFUSABLE_MIN = 0.175


def _render(ch: str) -> np.ndarray:
    img = Image.new("L", (int(CAP_PX * 0.9), int(CAP_PX * 1.3)), 0)
    draw = ImageDraw.Draw(img)
    for s in text_strokes(ch, CAP_PX, (0.3 * CAP_PX + 0.15 * CAP_PX, 0.65 * CAP_PX)):
        pts = [(float(x), float(img.height - y)) for x, y in s]
        draw.line(pts, fill=255, width=STROKE_PX, joint="curve")
    return np.asarray(img) > 0


def _hausdorff(a: np.ndarray, b: np.ndarray) -> float:
    """Symmetric Hausdorff distance between two rendered glyphs, in cap heights."""
    da = ndimage.distance_transform_edt(~a)
    db = ndimage.distance_transform_edt(~b)
    return max(db[a].max(), da[b].max()) / CAP_PX


def test_every_glyph_renders():
    for ch in GLYPHS:
        if ch == " ":
            continue
        img = _render(ch)
        assert img.any(), ch
        assert img.mean() < 0.5, ch


def test_glyphs_are_pairwise_distinct():
    chars = [c for c in GLYPHS if c != " "]
    imgs = {c: _render(c) for c in chars}
    d = {frozenset(p): _hausdorff(imgs[p[0]], imgs[p[1]]) for p in itertools.combinations(chars, 2)}
    worst = min(d, key=d.get)
    assert d[worst] >= ALL_PAIRS_MIN, (sorted(worst), d[worst])
    for pair in CONFUSABLE:
        assert d[frozenset(pair)] >= CONFUSABLE_MIN, (pair, d[frozenset(pair)])


def test_no_stroke_retraces_another():
    for ch, strokes in GLYPHS.items():
        segs = set()
        for s in strokes:
            for a, b in zip(s[:-1].tolist(), s[1:].tolist()):
                key = frozenset((tuple(a), tuple(b)))
                assert key not in segs, ch  # a segment engraved twice burns deeper
                segs.add(key)
