"""Test fixtures for the layout verifier: patterns with distinct chiral tiles and
minimal cut files written by the rules of docs/cut-files.md (ezdxf, svgwrite).

These writers are deliberately independent of fabkiri.fabricate: they are the
contract, not the implementation.
"""

from __future__ import annotations

import json
from functools import lru_cache
from pathlib import Path

import ezdxf
import numpy as np
import shapely
import svgwrite
from fabkiri.mechanics.contract import with_contracted_states
from fabkiri.pattern import Pattern, geometry, standard_pattern
from fabkiri.pattern.residuals import hinge_sums
from fabkiri.pattern.thinness import widths


def _residuals(pattern: Pattern, x: np.ndarray) -> np.ndarray:
    top = pattern.topology
    h = x[top.hinge_node]
    out = []
    for s in (1, 2):
        fold = top.fold(s)
        la = np.linalg.norm(x[fold.fold_ends[:, 0]] - h, axis=1)
        lb = np.linalg.norm(x[fold.fold_ends[:, 1]] - h, axis=1)
        out.append(la - lb)
    out.append(hinge_sums(pattern, x))
    return np.concatenate(out)


@lru_cache(maxsize=8)
def distinct_pattern(rows: int = 4, cols: int = 5, seed: int = 3, size: float = 20.0) -> Pattern:
    """A rigid-deployable reconfigurable pattern whose tiles are pairwise non-congruent and chiral.

    The standard lattice is perturbed at random and projected back onto the
    constraint set (edge pairs of both states and hinge sums) by Gauss-Newton.
    """
    base = standard_pattern(rows, cols, tile_size=size)
    rng = np.random.default_rng(seed)
    x0 = base.nodes + rng.normal(scale=0.03 * size, size=base.nodes.shape)

    def f(v):
        return _residuals(base, v.reshape(-1, 2))

    # Gauss-Newton with minimum-norm steps (dense central differences: a fixture, 5 steps). scipy's
    # least_squares from a larger perturbation landed on members with 1.8 mm and 0 mm tiles as
    # its defaults and builds changed; minimum-norm steps stay on the member nearest the start.
    x = x0.ravel()
    eye = 1e-7 * np.eye(len(x))
    for _ in range(40):
        r = f(x)
        if np.abs(r).max() < 1e-13:
            break
        J = np.stack([(f(x + e) - f(x - e)) / 2e-7 for e in eye], 1)
        x = x - np.linalg.lstsq(J, r, rcond=None)[0]
    nodes = x.reshape(-1, 2)
    assert np.abs(f(x)).max() < 1e-10, np.abs(f(x)).max()
    # the tests cut it at scale 1 in every material: a thin member would fail them for the wrong reason
    thinnest = widths(nodes[base.tiles]).min()
    assert thinnest > 0.5 * size, f"fixture member has a {thinnest:.2f} mm tile"
    p = Pattern(
        nodes=nodes,
        tiles=base.tiles,
        name=f"distinct {rows}x{cols} seed {seed}",
        design={"rigid_deployable": True, "source": "test fixture"},
    )
    return with_contracted_states(p)


# ------------------------------------------------------------------ cut-file writers


def _sheet_frame(corners: np.ndarray, margin: float = 10.0) -> tuple[np.ndarray, float, float]:
    """Shift corners into the positive quadrant; returns shifted corners, width, height."""
    lo = corners.reshape(-1, 2).min(0)
    out = corners - lo + margin
    hi = out.reshape(-1, 2).max(0)
    return out, float(hi[0] + margin + 70.0), float(hi[1] + margin)


def _ref_square(width: float) -> np.ndarray:
    x0 = width - 60.0
    return np.array([[x0, 5.0], [x0 + 50.0, 5.0], [x0 + 50.0, 55.0], [x0, 55.0]])


def unique_edges(corners: np.ndarray, decimals: int = 6) -> np.ndarray:
    """Every tile edge once (common-line cutting): ``(E, 2, 2)``."""
    a = corners.reshape(-1, 2)
    b = np.roll(corners, -1, axis=1).reshape(-1, 2)
    segs = np.stack([a, b], 1)
    key = np.round(segs, decimals)
    flip = (key[:, 0, 0] > key[:, 1, 0]) | (
        (key[:, 0, 0] == key[:, 1, 0]) & (key[:, 0, 1] > key[:, 1, 1])
    )
    key[flip] = key[flip][:, ::-1]
    _, idx = np.unique(key.reshape(-1, 4), axis=0, return_index=True)
    return segs[np.sort(idx)]


def write_layout(  # noqa: PLR0913 (a fixture taking the cut's options: hinge, layout, state, kerf)
    folder: Path,
    pattern: Pattern,
    corners: np.ndarray,
    *,
    hinge: str = "tape",
    fmt: str = "dxf",
    state: int = 1,
    kerf_offset: float = 0.0,
    order: np.ndarray | None = None,
    manifest: bool = True,
    reference: bool = True,
    layout: str | None = None,
) -> Path:
    """Write one sheet: ``corners`` (T', 4, 2) are the tiles as they sit on the sheet (mm).

    ``tape``: every edge once, as open 2-point polylines; ``separate``: closed
    outlines offset outward by ``kerf_offset`` (mitre). ``order`` permutes the
    written entities.
    """
    folder.mkdir(parents=True, exist_ok=True)
    corners, width, height = _sheet_frame(np.asarray(corners, dtype=float))
    if hinge == "tape":
        items = [(seg, False) for seg in unique_edges(corners)]
    else:
        polys = shapely.polygons(corners)
        if kerf_offset:
            polys = shapely.buffer(polys, kerf_offset, join_style="mitre", mitre_limit=10.0)
        items = [(np.asarray(p.exterior.coords)[:-1], True) for p in polys]
    if order is not None:
        items = [items[i % len(items)] for i in order] if len(order) == len(items) else items
    sq = _ref_square(width)
    stem = "layout"
    path = folder / f"{stem}.{fmt}"
    if fmt == "dxf":
        doc = ezdxf.new("R2010", units=4)
        for name, color in (("CUT", 1), ("SCORE", 5), ("ENGRAVE", 7), ("NOTES", 3)):
            doc.layers.add(name, color=color)
        msp = doc.modelspace()
        for pts, closed in items:
            msp.add_lwpolyline(pts.tolist(), close=closed, dxfattribs={"layer": "CUT"})
        if reference:
            msp.add_lwpolyline(sq.tolist(), close=True, dxfattribs={"layer": "CUT"})
        msp.add_lwpolyline(
            [(0, 0), (width, 0), (width, height), (0, height)],
            close=True,
            dxfattribs={"layer": "NOTES"},
        )
        doc.saveas(path)
    else:
        dwg = svgwrite.Drawing(
            str(path),
            size=(f"{width}mm", f"{height}mm"),
            viewBox=f"0 0 {width} {height}",
            debug=False,
        )

        def flip(p):
            return [(float(x), float(height - y)) for x, y in p]

        g = dwg.g(id="CUT", fill="none", stroke="#ff0000", stroke_width=0.01)
        for pts, closed in items:
            g.add(dwg.polygon(flip(pts)) if closed else dwg.polyline(flip(pts)))
        if reference:
            g.add(dwg.polygon(flip(sq)))
        dwg.add(g)
        notes = dwg.g(id="NOTES", fill="none", stroke="#00ff00")
        notes.add(dwg.rect((0, 0), (width, height)))
        dwg.add(notes)
        dwg.save()
    if manifest:
        data = {
            "format": "fabkiri.cut",
            "version": 1,
            "units": "mm",
            "pattern": "pattern.json",
            "hinge": hinge,
            "state": state,
            "layout": layout or ("in-place" if hinge == "tape" else "exploded"),
            "scale": 1.0,
            "kerf_mm": 2 * kerf_offset,
            "kerf_offset_mm": kerf_offset,
            "tile_shrink_mm": 0.0,
            "hinge_features": [],
            "reference_square": {"sheet": 1, "corners": sq.tolist()} if reference else None,
            "sheets": [{"index": 1, "width_mm": width, "height_mm": height, fmt: path.name}],
            "tiles": [{"tile": t, "sheet": 1, "label": str(t)} for t in range(pattern.n_tiles)],
        }
        (folder / "manifest.json").write_text(json.dumps(data, indent=1))
    return path


def in_place_corners(
    pattern: Pattern, state: int = 1, theta: float = 0.0, shift=(0.0, 0.0)
) -> np.ndarray:
    Y = pattern.contracted[state]
    return geometry.rotate(Y, theta) + np.asarray(shift)


def exploded_corners(
    pattern: Pattern, rng: np.random.Generator, spacing: float = 1.6
) -> np.ndarray:
    """Deployed tile shapes, each turned at random, on a grid with clearance."""
    X = pattern.corners()
    c = X.mean(axis=1, keepdims=True)
    local = geometry.rotate(X - c, rng.uniform(0, 2 * np.pi, size=(len(X), 1)))
    r = np.linalg.norm(local, axis=-1).max()
    n = int(np.ceil(np.sqrt(len(X))))
    slots = rng.permutation(n * n)[: len(X)]
    centre = np.stack([slots % n, slots // n], -1) * (2 * r * spacing)
    return local + centre[:, None, :]


# ------------------------------------------------------------------ mutations


def rotate_tile(C: np.ndarray, t: int, deg: float) -> np.ndarray:
    C = C.copy()
    c = C[t].mean(0)
    C[t] = geometry.rotate(C[t] - c, np.radians(deg)) + c
    return C


def scale_tile(C: np.ndarray, t: int, f: float) -> np.ndarray:
    C = C.copy()
    c = C[t].mean(0)
    C[t] = (C[t] - c) * f + c
    return C


def mirror_tile(C: np.ndarray, t: int) -> np.ndarray:
    C = C.copy()
    c = C[t].mean(0)
    m = C[t] - c
    m[:, 0] *= -1
    C[t] = m[::-1] + c  # keep CCW
    return C


def move_corner(C: np.ndarray, t: int, k: int, d: float, angle: float) -> np.ndarray:
    C = C.copy()
    C[t, k] += d * np.array([np.cos(angle), np.sin(angle)])
    return C


def swap_tiles(C: np.ndarray, i: int, j: int) -> np.ndarray:
    C = C.copy()
    ci, cj = C[i].mean(0), C[j].mean(0)
    C[i], C[j] = C[j] - cj + ci, C[i] - ci + cj
    return C


def drop_tile(C: np.ndarray, t: int) -> np.ndarray:
    return np.delete(C, t, axis=0)
