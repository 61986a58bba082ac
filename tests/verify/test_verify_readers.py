"""Reading cut files: the fast DXF tag reader agrees with ezdxf; SVG units, y flip and transforms;
tile recovery is invariant to rigid motions of the sheet (Hypothesis)."""

from __future__ import annotations

import ezdxf
import numpy as np
import svgwrite
from fabkiri.exchange import file_formats as L
from fabkiri.exchange.dxf import reader as dxfreader
from fabkiri.exchange.dxf import tags as dxfcodec
from fabkiri.exchange.linework import Linework
from fabkiri.pattern import geometry
from fabkiri.verify import verify_layout
from fabkiri.verify.quads import quads_of
from hypothesis import given, settings
from hypothesis import strategies as st

from .. import layout_fixtures as lf


def _same(a: Linework, b: Linework) -> bool:
    return (
        len(a.polylines) == len(b.polylines)
        and a.closed == b.closed
        and all(np.array_equal(x, y) for x, y in zip(a.polylines, b.polylines))
    )


def test_fast_dxf_reader_matches_ezdxf(tmp_path):
    p = lf.distinct_pattern()
    for hinge in ("tape", "separate"):
        C = (
            lf.in_place_corners(p, 1, 0.4)
            if hinge == "tape"
            else lf.exploded_corners(p, np.random.default_rng(3))
        )
        path = lf.write_layout(tmp_path / hinge, p, C, hinge=hinge, fmt="dxf", kerf_offset=0.1)
        fast = dxfcodec.read_layer_tags(path)
        assert fast is not None and _same(fast, dxfreader._read_dxf_full(path))


def test_dxf_units_curves_and_plain_layers(tmp_path):
    doc = ezdxf.new("R2010", units=1)  # inches
    msp = doc.modelspace()
    msp.add_lwpolyline([(0, 0), (1, 0), (1, 1), (0, 1)], close=True, dxfattribs={"layer": "CUT"})
    msp.add_lwpolyline(
        [(2, 0), (3, 0, 0.5), (3, 1)], format="xyb", dxfattribs={"layer": "CUT"}
    )  # an arc
    msp.add_line((5, 5), (6, 6), dxfattribs={"layer": "ENGRAVE"})
    msp.add_line((0, 2), (1, 2), dxfattribs={"layer": "CUT"})
    path = tmp_path / "in.dxf"
    doc.saveas(path)
    assert dxfcodec.read_layer_tags(path) is None  # the bulge sends it to ezdxf
    lw = L.read_cut_file(path)
    assert lw.layer_found and len(lw.polylines) == 3
    assert np.allclose(lw.polylines[2], [[0, 50.8], [25.4, 50.8]])
    assert np.allclose(lw.polylines[0].max(0), [25.4, 25.4])  # inches -> mm
    assert len(lw.polylines[1]) > 3  # the arc was flattened
    # no CUT layer: every outline not on an annotation layer
    doc = ezdxf.new("R2010", units=4)
    doc.modelspace().add_lwpolyline(
        [(0, 0), (10, 0), (10, 10)], close=True, dxfattribs={"layer": "0"}
    )
    doc.modelspace().add_lwpolyline([(0, 0), (1, 1)], dxfattribs={"layer": "NOTES"})
    doc.saveas(tmp_path / "plain.dxf")
    lw = L.read_cut_file(tmp_path / "plain.dxf")
    assert not lw.layer_found and len(lw.polylines) == 1 and lw.closed == [True]


def test_svg_mm_flip_and_transforms(tmp_path):
    """An SVG from another tool: cm size, a group transform, relative path commands."""
    path = tmp_path / "t.svg"
    dwg = svgwrite.Drawing(str(path), size=("20cm", "10cm"), viewBox="0 0 400 200", debug=False)
    g = dwg.g(id="CUT", transform="translate(10 20)")
    g.add(dwg.path(d="M 0 0 l 40 0 l 0 20 l -40 0 z"))  # 2 user units per mm
    dwg.add(g)
    dwg.save()
    lw = L.read_cut_file(path)
    assert len(lw.polylines) == 1 and lw.closed == [True]
    pts = lw.polylines[0]
    # x: (10 + 0..40) / 2 mm; y flipped: 100 - (20 + 0..20) / 2 mm
    assert np.allclose(np.sort(np.unique(pts[:, 0])), [5.0, 25.0], atol=1e-9)
    assert np.allclose(np.sort(np.unique(pts[:, 1])), [80.0, 90.0], atol=1e-9)
    assert geometry.signed_areas(pts[None])[0] < 0  # clockwise in SVG, so still a mirror-free read


def test_quads_of_drops_collinear_points_and_restores_bevelled_corners():
    sq = np.array([[0, 0], [10, 0], [10, 10], [0, 10]], float)
    with_tjunction = np.array([[0, 0], [5, 0], [10, 0], [10, 10], [0, 10]], float)
    bevel = np.array(
        [[0, 0], [9.6, 0], [10, 0.4], [10, 10], [0, 10]], float
    )  # one corner cut by 0.4 mm
    import shapely

    q, bad = quads_of(
        np.array([shapely.Polygon(sq), shapely.Polygon(with_tjunction), shapely.Polygon(bevel)])
    )
    assert bad == 0 and len(q) == 3
    for quad in q:
        assert (
            geometry.aligned_distance(quad, sq) < 1e-9
            or geometry.aligned_distance(np.roll(quad, 1, 0), sq) < 1e-9
            or min(geometry.aligned_distance(np.roll(quad, k, 0), sq) for k in range(4)) < 1e-9
        )


def test_bevelled_sliver_keeps_its_corners_next_to_a_nearly_straight_one():
    """Tile 240 of `design --tiles 16x16 --target star --size 150 --rigid` cut from pp-0.5 at
    --scale auto (7.878x): a 9.5° corner bevelled on the sheet next to a corner turning 2.4°. The
    long edge past that nearly straight corner was taken for the bevelled corner's side, which
    moved the corner 8.7 mm and failed the cut's read-back ("cut tiles congruent to design")."""
    import shapely

    Q = np.array([[-328.84, 205.82], [-291.53, 211.17], [-255.05, 226.91], [-304.77, 213.44]])
    pts = []
    for k in range(4):
        if k in (0, 2):  # the two sharp corners cut 0.7 mm back along both edges
            for other in (Q[k - 1], Q[(k + 1) % 4]):
                pts.append(Q[k] + 0.7 * (other - Q[k]) / np.linalg.norm(other - Q[k]))
        else:
            pts.append(Q[k])
    q, bad = quads_of(np.array([shapely.Polygon(pts)]))
    assert bad == 0 and len(q) == 1
    assert np.linalg.norm(q[0][:, None] - Q[None], axis=-1).min(axis=1).max() <= 1e-9


@settings(max_examples=12, deadline=None)
@given(
    st.floats(0, 2 * np.pi),
    st.floats(-300, 300),
    st.floats(-300, 300),
    st.sampled_from(["dxf", "svg"]),
    st.sampled_from(["tape", "separate"]),
)
def test_rigid_motions_of_the_sheet_are_accepted(tmp_path_factory, theta, dx, dy, fmt, hinge):
    p = lf.distinct_pattern()
    if hinge == "tape":
        C = lf.in_place_corners(p, 1, theta, (dx, dy))
    else:
        C = geometry.rotate(lf.exploded_corners(p, np.random.default_rng(0)), theta) + np.array(
            [dx, dy]
        )
    path = lf.write_layout(
        tmp_path_factory.mktemp("h"), p, C, hinge=hinge, fmt=fmt, kerf_offset=0.08
    )
    rep = verify_layout(p, path)
    assert rep.ok, rep.to_text()


def test_fast_reader_lines_on_cut(tmp_path):
    doc = ezdxf.new("R2010", units=4)
    msp = doc.modelspace()
    for a, b in (((0, 0), (10, 0)), ((10, 0), (10, 10)), ((10, 10), (0, 10)), ((0, 10), (0, 0))):
        msp.add_line(a, b, dxfattribs={"layer": "CUT"})
    msp.add_text(
        "0", dxfattribs={"layer": "ENGRAVE"}
    )  # a value line "0" must not look like an entity start
    path = tmp_path / "lines.dxf"
    doc.saveas(path)
    fast = dxfcodec.read_layer_tags(path)
    assert (
        fast is not None
        and len(fast.polylines) == 4
        and _same(fast, dxfreader._read_dxf_full(path))
    )


def test_one_dxf_codec_reads_what_it_writes(tmp_path):
    """The writer's bulk entities are exactly the canonical form the tag readers take: every ENGRAVE
    stroke split from the ENTITIES section is canonical, with its points and closed flag, and the
    verifier's layer scan returns the same polylines; a prototype export of another shape is refused."""
    from fabkiri.exchange.drawing import SheetDrawing
    from fabkiri.exchange.dxf.writer import dxf_bytes

    rng = np.random.default_rng(3)
    sd = SheetDrawing(1, 200.0, 100.0)
    strokes = [(rng.uniform(0, 100, (int(n), 2)), bool(n % 2)) for n in rng.integers(2, 7, 40)]
    for pts, closed in strokes:
        sd.add("ENGRAVE", pts, closed)
    sd.add("CUT", np.array([[0.0, 0.0], [10.0, 0.0], [10.0, 10.0]]), True)
    text = dxf_bytes(sd).decode("ascii")
    lo, hi = dxfcodec.entities_span(text)
    tags = dxfcodec.split_tags(text[lo:hi].split("\n")[:-1])
    canon = np.flatnonzero(~tags.bad)
    assert len(canon) == len(strokes) + 1 and set(tags.at(canon, 4).tolist()) == {"ENGRAVE", "CUT"}
    written = sd.layers["ENGRAVE"]
    assert tags.nv[tags.good][: len(written)].tolist() == [len(p) for p, _ in written]
    assert (tags.flags[tags.good][: len(written)] == "1").tolist() == [c for _, c in written]
    path = tmp_path / "s.dxf"
    path.write_text(text)
    lw = dxfcodec.read_layer_tags(path, "ENGRAVE")
    assert lw is not None and len(lw.polylines) == len(written)
    for (p, c), q, cq in zip(written, lw.polylines, lw.closed):
        assert np.array_equal(p, q) and c == cq
    proto = "  0\nLWPOLYLINE\n  5\nF0\n330\n1F\n100\nAcDbEntity\n  8\nL\n370\n0\n100\nAcDbPolyline\n 90\n2\n 70\n0\n"
    pts = [(1.25, 2.5), (3.75, 4.5)]
    verts = "".join(f" 10\n{x}\n 20\n{y}\n" for x, y in pts)
    assert (
        dxfcodec.split_prototype(proto + verts, "F0", pts) is None
    )  # a lineweight tag: not canonical
    assert dxfcodec.split_prototype(proto.replace("370\n0\n", "") + verts, "F0", pts) is not None


def test_the_verifier_reads_a_hinge_kind_through_its_registered_reading(monkeypatch):
    """The verifier asks a kind's reading (not its name) how to recover tiles and which layout a
    manifest without one means; a kind with no reading is refused with one line naming those known."""
    from dataclasses import replace
    from pathlib import Path

    import pytest
    from fabkiri.errors import VerifyError
    from fabkiri.exchange.linework import Linework
    from fabkiri.verify import hingeread
    from fabkiri.verify.manifest import CutManifest, _allowances, _named_problems
    from fabkiri.verify.recovery import recover_polygons

    monkeypatch.setattr(hingeread._READINGS, "members", dict(hingeread._READINGS.members))
    tape, calls = hingeread.reading("tape"), []

    def recover(lw, al, sheet, frame_tiles, arity):
        calls.append((al.hinge, len(lw.polylines)))
        return tape.recover(lw, al, sheet, frame_tiles, arity)

    hingeread.register_reading(replace(tape, name="scored", recover=recover))
    lw = Linework(Path("s.dxf"))
    for pts in (
        [[0, 0], [2, 0], [2, 1], [0, 1]],
        [[1, 0], [1, 1]],
    ):  # a rectangle and a cut across it
        lw.add(np.array(pts, float), len(pts) > 2)
    polys, how = recover_polygons(lw, replace(_allowances({"hinge": "tape"}, "m"), hinge="scored"))
    assert (
        calls == [("scored", 2)] and how == "polygonize of the noded linework" and len(polys) == 2
    )
    assert (
        CutManifest(hinge="scored").default_layout() == "in-place"
    )  # (the schema's enum lists the names)
    assert _allowances({"hinge": "separate"}, "m").layout == "exploded"
    _named_problems({"hinge": "scored"}, "m")  # registered: accepted
    with pytest.raises(
        VerifyError, match=r"^m: unknown hinge kind 'glued' \(tape, separate, ligament or scored\)$"
    ):
        _named_problems({"hinge": "glued"}, "m")
