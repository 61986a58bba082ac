"""``fabkiri coupon``: laser coupons open at their size in mm; print coupons are watertight."""

from __future__ import annotations

import json

import ezdxf
import numpy as np
import pytest
import svgelements
import trimesh


def _cut_polylines_dxf(path):
    doc = ezdxf.readfile(path)
    assert doc.header["$INSUNITS"] == 4  # millimetres
    auditor = doc.audit()
    assert not auditor.has_errors and not auditor.has_fixes  # a clean DXF for laser software
    assert {e.dxf.layer for e in doc.modelspace()} <= {"CUT", "ENGRAVE", "SCORE", "NOTES"}
    out = []
    for e in doc.modelspace().query("LWPOLYLINE[layer=='CUT']"):
        pts = np.array([p[:2] for p in e.get_points()])
        out.append((pts, e.closed))
    return out


@pytest.mark.parametrize("material", ["acrylic-3", "pp-0.5", "card-0.3"])
def test_laser_coupon_opens_at_its_size(run_cli, tmp_path, material):
    code, _, err = run_cli("coupon", "--material", material, "-o", tmp_path)
    assert code == 0, err
    doc = json.loads((tmp_path / "coupon.json").read_text())
    W, H = doc["sheet_mm"]
    assert W < 200 and H < 120  # a small piece, not a sheet
    assert [r["sets"] for r in doc["instructions"]][0].startswith("kerf_mm")
    polys = _cut_polylines_dxf(tmp_path / f"coupon-{material}.dxf")
    boxes = np.array([np.r_[p.min(0), p.max(0)] for p, _ in polys])
    assert boxes[:, :2].min() >= 0 and (boxes[:, 2] <= W).all() and (boxes[:, 3] <= H).all()
    # the kerf comb: a closed 100 x 12 mm bar and 9 cross cuts 10 mm apart
    size = boxes[:, 2:] - boxes[:, :2]
    bar = [
        i for i, (p, c) in enumerate(polys) if c and np.allclose(size[i], [100.0, 12.0], atol=1e-6)
    ]
    assert len(bar) == 1
    x0, y0, _, y1 = boxes[bar[0]]
    cross = sorted(
        p[0, 0] - x0
        for p, c in polys
        if not c
        and len(p) == 2
        and abs(p[0, 0] - p[1, 0]) < 1e-9
        and np.allclose(sorted(p[:, 1]), [y0, y1])
    )
    assert np.allclose(cross, np.arange(1, 10) * 10.0, atol=1e-6)
    # the slots: widths thickness + delta, read back from the slot plate's outline
    slots = doc["slots"]["widths_mm"]
    plate = max((p for p, c in polys if c and len(p) > 20), key=len)
    steps = np.abs(np.diff(plate[:, 0]))
    bottom = plate[:, 1].max() - 8.0  # slot floors, 8 mm below the plate's top edge
    found = sorted(
        {
            round(float(s), 6)
            for s, a, b in zip(steps, plate[:-1, 1], plate[1:, 1])
            if abs(a - bottom) < 1e-9 and abs(b - bottom) < 1e-9
        }
    )
    assert found == sorted({round(w, 6) for w in slots})
    # the SVG says the same size in mm, and its CUT group spans the same box
    svg = svgelements.SVG.parse(str(tmp_path / f"coupon-{material}.svg"))
    assert svg.values["width"] == f"{W:g}mm" and svg.values["height"] == f"{H:g}mm"
    cut = next(
        e
        for e in svg.elements()
        if isinstance(e, svgelements.Group) and e.values.get("id") == "CUT"
    )
    bb = cut.bbox()
    px_per_mm = 96 / 25.4  # svgelements works in CSS px
    assert bb[2] / px_per_mm == pytest.approx(boxes[:, 2].max(), abs=1e-3)
    assert (bb[2] - bb[0]) / px_per_mm == pytest.approx(
        boxes[:, 2].max() - boxes[:, 0].min(), abs=1e-3
    )


def test_laser_coupon_hinge_pieces_sweep_the_hinge_field(run_cli, tmp_path):
    run_cli("coupon", "--material", "pp-0.5", "-o", tmp_path)
    doc = json.loads((tmp_path / "coupon.json").read_text())
    hp = doc["hinge_pieces"]
    assert hp["field"] == "ligament_width_mm" and len(hp["values"]) >= 3
    assert doc["instructions"][2]["sets"] == "ligament_width_mm"


def test_printer_coupon_is_watertight_and_separate(run_cli, tmp_path):
    code, _, err = run_cli("coupon", "--printer", "prusa-mk4", "-o", tmp_path)
    assert code == 0, err
    doc = json.loads((tmp_path / "coupon.json").read_text())
    for k, v in doc["checks"].items():
        assert v["watertight"] and v["winding_consistent"], k
        assert v["volume_mm3"] == pytest.approx(v["solid_volume_mm3"], rel=1e-9)
    assert max(doc["intersection_mm3"].values()) < 1e-6
    for k in ("plate", "pegs", "strips"):
        m = trimesh.load(tmp_path / f"coupon-prusa-mk4_{k}.stl")
        assert m.is_watertight
    scene = trimesh.load(tmp_path / "coupon-prusa-mk4.3mf")
    assert len(scene.geometry) == 3
    ext = scene.bounds[1] - scene.bounds[0]
    assert ext == pytest.approx(doc["size_mm"], abs=1e-3)
    assert {r["sets"] for r in doc["instructions"]} == {"radial_clearance_mm", "strip_width_mm"}


def test_coupon_needs_one_preset(run_cli, tmp_path):
    with pytest.raises(SystemExit) as exc:
        run_cli("coupon", "-o", tmp_path / "c")
    assert exc.value.code == 2
    code, _, err = run_cli("coupon", "--material", "nope", "-o", tmp_path / "c")
    assert code == 2 and not (tmp_path / "c").exists()
