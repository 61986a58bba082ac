"""Valid variants and breakages of real cut files, for bench/verify_mutations.py and its fast test subset.

A cut file is read into a neutral sheet (polylines per layer, mm, y up), changed
(rigid motion, splitting, rounding, a tile scaled, a slit shortened, ...), and
written back by one of several writers that mimic what other tools produce
(LINEs, POLYLINEs, blocks, a flipped OCS, colour-only layers, R2018, inch units;
SVG polylines, relative paths, Inkscape layers, group transforms, px or cm units).
The writers are independent of fabkiri.fabricate: they are other tools, not the
implementation. Every mutation knows whether it must be accepted or rejected.
"""

from __future__ import annotations

import json
import math
import shutil
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import ezdxf
import numpy as np
import shapely
from fabkiri.mechanics.contract import contract

ACI = {"CUT": 1, "SCORE": 5, "ENGRAVE": 7, "NOTES": 3}
HEX = {"CUT": "#ff0000", "SCORE": "#0000ff", "ENGRAVE": "#000000", "NOTES": "#00ff00"}


@dataclass
class Sheet:
    layers: dict[str, list[tuple[np.ndarray, bool]]]
    width: float
    height: float

    def copy(self) -> Sheet:
        return Sheet(
            {k: [(p.copy(), c) for p, c in v] for k, v in self.layers.items()},
            self.width,
            self.height,
        )

    def map_points(self, fn, layers=None) -> Sheet:
        out = self.copy()
        for k, v in out.layers.items():
            if layers is None or k in layers:
                out.layers[k] = [(fn(p), c) for p, c in v]
        return out


@dataclass
class Base:
    """One real cut folder: the sheet, its manifest, the design tiles on the sheet."""

    folder: Path
    fmt: str
    pattern: object
    manifest: dict
    sheet: Sheet
    tiles: (
        np.ndarray
    )  # (T, 4, 2) design tiles where the manifest puts them (in place: the cut region)
    extra: dict = field(default_factory=dict)

    @property
    def hinge(self) -> str:
        return self.manifest["hinge"]


def load_base(folder: Path, fmt: str, pattern) -> Base:
    from fabkiri.exchange.dxf.reader import read_dxf

    man = json.loads((folder / "manifest.json").read_text())
    row = man["sheets"][0]
    doc, _, layers, _ = read_dxf((folder / row["dxf"]).read_bytes())
    sheet = Sheet(
        {k: [(np.asarray(p, float), bool(c)) for p, c in v] for k, v in layers.items()},
        float(row["width_mm"]),
        float(row["height_mm"]),
    )
    state = int(man["state"])
    Y = pattern.contracted.get(state)
    Y = contract(pattern, state).corners if Y is None else Y
    src = Y * float(man["scale"])  # sheet xy = Rot(rotation) (scaled closed-state xy) + shift
    tiles = np.zeros_like(src)
    for t in man["tiles"]:
        th = float(t["rotation_rad"])
        R = np.array([[math.cos(th), -math.sin(th)], [math.sin(th), math.cos(th)]])
        k = int(t["tile"])
        tiles[k] = src[k] @ R.T + np.asarray(t["shift_mm"])
    b = Base(folder, fmt, pattern, man, sheet, tiles)
    b.extra["mirror_symmetric"] = _mirror_symmetric(tiles)
    return b


def _mirror_symmetric(tiles: np.ndarray, tol: float = 0.05) -> bool:
    """Whether the sheet's tiles mirrored are the same tiles after a rigid motion (a mirror is then no breakage)."""
    from fabkiri.verify.matching import match_in_place

    M = tiles.copy()
    M[..., 0] *= -1
    M = M[:, ::-1]
    a, res, _, _, _ = match_in_place(tiles, M)
    return bool((a >= 0).all() and np.max(res) <= tol)


# ------------------------------------------------------------------ writers


def _dxf_doc(version: str = "R2010", units: int = 4):
    doc = ezdxf.new(version, units=units)
    for name, color in ACI.items():
        if name not in doc.layers:
            doc.layers.add(name, color=color)
    return doc


def write_dxf(sheet: Sheet, path: Path, style: str = "lw") -> None:
    """``style``: lw | lines | poly2d | block | block-moved | ocs | layer0 | r2018 | inch | cm | unitless |
    inch-for-mm (breakage) | ocs-mirror (breakage) | lower."""
    version = "R2018" if style == "r2018" else "R2010"
    units = {"inch": 1, "cm": 5, "unitless": 0, "inch-for-mm": 1}.get(style, 4)
    f = {"inch": 1 / 25.4, "cm": 0.1}.get(style, 1.0)
    doc = _dxf_doc(version, units)
    msp = doc.modelspace()
    target = msp
    if style in ("block", "block-moved"):
        target = doc.blocks.new("SHEET")
    for layer, items in sheet.layers.items():
        name = {"layer0": "0", "lower": layer.lower()}.get(style, layer)
        if style == "lower" and name not in doc.layers:
            doc.layers.add(name)
        attrs = {"layer": name}
        if style == "layer0":
            attrs["color"] = ACI.get(layer, 7)
        for pts, closed in items:
            q = np.asarray(pts, float) * f
            if style == "lines":
                segs = list(zip(q, np.roll(q, -1, 0))) if closed else list(zip(q[:-1], q[1:]))
                for a, b in segs:
                    target.add_line(tuple(a), tuple(b), dxfattribs=attrs)
            elif style == "poly2d":
                target.add_polyline2d([tuple(p) for p in q], close=closed, dxfattribs=attrs)
            elif style in ("ocs", "ocs-mirror"):
                from ezdxf.math import OCS

                ocs = OCS((0, 0, -1))
                pts_o = (
                    [tuple(v)[:2] for v in ocs.points_from_wcs([(x, y, 0) for x, y in q])]
                    if style == "ocs"
                    else [tuple(p) for p in q]
                )
                e = target.add_lwpolyline(pts_o, close=closed, dxfattribs=attrs)
                e.dxf.extrusion = (0, 0, -1)
            else:
                target.add_lwpolyline([tuple(p) for p in q], close=closed, dxfattribs=attrs)
    if style == "block":
        msp.add_blockref("SHEET", (0, 0))
    elif style == "block-moved":
        msp.add_blockref("SHEET", (37.5, -12.25), dxfattribs={"rotation": 30.0})
    doc.saveas(path)


def _d(pts: np.ndarray, closed: bool, relative: bool = False) -> str:
    if relative:
        steps = np.diff(pts, axis=0)
        s = f"m {pts[0, 0]:.12g},{pts[0, 1]:.12g} " + " ".join(
            f"l {dx:.12g},{dy:.12g}" for dx, dy in steps
        )
    else:
        s = "M " + " L ".join(f"{x:.12g},{y:.12g}" for x, y in pts)
    return s + (" Z" if closed else "")


def write_svg(sheet: Sheet, path: Path, style: str = "groups") -> None:
    """``style``: groups | labels | colour | polyline | relative | lines | transform | px | cm | inch |
    viewbox-scaled (breakage) | mirror (breakage) | inch-for-mm (breakage)."""
    W, H = sheet.width, sheet.height
    k = {"px": 96 / 25.4}.get(style, 1.0)  # user units per mm
    size = {
        "cm": (f"{W / 10:.12g}cm", f"{H / 10:.12g}cm"),
        "inch": (f"{W / 25.4:.12g}in", f"{H / 25.4:.12g}in"),
        "inch-for-mm": (f"{W:.12g}in", f"{H:.12g}in"),
    }.get(style, (f"{W:.12g}mm", f"{H:.12g}mm"))
    vb = (
        f"0 0 {W * k:.12g} {H * k:.12g}"
        if style != "viewbox-scaled"
        else f"0 0 {W * 1.01:.12g} {H * 1.01:.12g}"
    )
    out = [
        '<?xml version="1.0" encoding="UTF-8"?>',
        f'<svg xmlns="http://www.w3.org/2000/svg" xmlns:inkscape="http://www.inkscape.org/namespaces/inkscape" '
        f'width="{size[0]}" height="{size[1]}" viewBox="{vb}">',
    ]
    outer = {
        "transform": f'<g transform="translate(41.5 -17.25) rotate(23 {W / 2} {H / 2})">',
        "mirror": f'<g transform="translate({W} 0) scale(-1 1)">',
    }.get(style)
    if outer:
        out.append(outer)
    n = 0
    for layer, items in sheet.layers.items():
        col = HEX.get(layer, "#000000")
        if style == "colour":
            head = None
        elif style == "labels":
            head = f'<g inkscape:groupmode="layer" id="layer{n + 1}" inkscape:label="{layer}" style="stroke:{col};fill:none">'
        else:
            head = f'<g id="{layer}" inkscape:label="{layer}" inkscape:groupmode="layer" stroke="{col}" fill="none">'
        n += 1
        if head:
            out.append(head)
        for pts, closed in items:
            q = np.column_stack([pts[:, 0], H - pts[:, 1]]) * k
            st = f' style="fill:none;stroke:{col};stroke-width:0.01"' if style == "colour" else ""
            if style == "polyline":
                tag = "polygon" if closed else "polyline"
                out.append(
                    f'<{tag} points="' + " ".join(f"{x:.12g},{y:.12g}" for x, y in q) + f'"{st}/>'
                )
            elif style == "lines":
                segs = list(zip(q, np.roll(q, -1, 0))) if closed else list(zip(q[:-1], q[1:]))
                for a, b in segs:
                    out.append(
                        f'<line x1="{a[0]:.12g}" y1="{a[1]:.12g}" x2="{b[0]:.12g}" y2="{b[1]:.12g}"{st}/>'
                    )
            else:
                out.append(f'<path d="{_d(q, closed, style == "relative")}"{st}/>')
        if head:
            out.append("</g>")
    if outer:
        out.append("</g>")
    out.append("</svg>")
    path.write_text("\n".join(out) + "\n")


# ------------------------------------------------------------------ geometry changes


def rigid(theta: float, shift) -> Callable:
    c, s = math.cos(theta), math.sin(theta)
    R = np.array([[c, -s], [s, c]])
    return lambda p: p @ R.T + np.asarray(shift, float)


def _split_closed(sheet: Sheet, layers=("CUT",)) -> Sheet:
    """Every closed polyline as two open pieces that join end to end."""
    out = sheet.copy()
    for k in layers:
        items = []
        for p, c in out.layers.get(k, []):
            if c and len(p) >= 3:
                m = len(p) // 2
                ring = np.vstack([p, p[:1]])
                items += [(ring[: m + 1], False), (ring[m:], False)]
            else:
                items.append((p, c))
        out.layers[k] = items
    return out


def _explode(sheet: Sheet, layers=("CUT",)) -> Sheet:
    """Every segment its own open two-point polyline."""
    out = sheet.copy()
    for k in layers:
        items = []
        for p, c in out.layers.get(k, []):
            q = np.vstack([p, p[:1]]) if c else p
            items += [(q[i : i + 2], False) for i in range(len(q) - 1)]
        out.layers[k] = items
    return out


def _reverse(sheet: Sheet) -> Sheet:
    out = sheet.copy()
    out.layers = {k: [(p[::-1].copy(), c) for p, c in v] for k, v in out.layers.items()}
    return out


def _shuffle(sheet: Sheet, seed: int = 0) -> Sheet:
    rng = np.random.default_rng(seed)
    out = sheet.copy()
    out.layers = {k: [v[i] for i in rng.permutation(len(v))] for k, v in out.layers.items()}
    return out


def _round(decimals: int) -> Callable[[Sheet], Sheet]:
    return lambda s: s.map_points(lambda p: np.round(p, decimals))


def _drop_layers(*names) -> Callable[[Sheet], Sheet]:
    def f(s: Sheet) -> Sheet:
        out = s.copy()
        for n in names:
            out.layers.pop(n, None)
        return out

    return f


def _cut_points(sheet: Sheet) -> np.ndarray:
    return np.concatenate([p for p, _ in sheet.layers["CUT"]])


def _near_tile(b: Base, t: int, grow: float) -> shapely.Polygon:
    return shapely.Polygon(b.tiles[t]).buffer(grow, join_style="mitre")


def move_vertices_of_tile(b: Base, t: int, fn, grow: float = 0.3) -> Sheet:
    """Apply ``fn`` to every CUT vertex within ``grow`` of tile ``t`` (shared corners move too)."""
    region = shapely.prepared.prep(_near_tile(b, t, grow)) if hasattr(shapely, "prepared") else None
    poly = _near_tile(b, t, grow)
    out = b.sheet.copy()
    items = []
    for p, c in out.layers["CUT"]:
        inside = shapely.contains_xy(poly, p[:, 0], p[:, 1])
        if inside.any():
            p = p.copy()
            p[inside] = fn(p[inside])
        items.append((p, c))
    out.layers["CUT"] = items
    del region
    return out


def _interior_tile(b: Base, rng) -> int:
    T = len(b.tiles)
    c = b.tiles.mean(axis=1)
    return int(np.argsort(np.linalg.norm(c - c.mean(0), axis=1))[rng.integers(0, max(1, T // 4))])


def _about(centre, fn):
    return lambda p: fn(p - centre) + centre


def tile_scaled(f: float):
    def m(b: Base, rng) -> tuple[Sheet, str]:
        t = _interior_tile(b, rng)
        c = b.tiles[t].mean(0)
        return move_vertices_of_tile(b, t, _about(c, lambda q: q * f)), f"tile {t}"

    return m


def tile_turned(deg: float):
    def m(b: Base, rng) -> tuple[Sheet, str]:
        t = _interior_tile(b, rng)
        c = b.tiles[t].mean(0)
        return move_vertices_of_tile(b, t, _about(c, rigid(math.radians(deg), (0, 0)))), f"tile {t}"

    return m


def tile_moved(d: float):
    def m(b: Base, rng) -> tuple[Sheet, str]:
        t = _interior_tile(b, rng)
        a = rng.uniform(0, 2 * np.pi)
        return move_vertices_of_tile(
            b, t, lambda q: q + d * np.array([math.cos(a), math.sin(a)])
        ), f"tile {t}"

    return m


def corner_moved(d: float):
    def m(b: Base, rng) -> tuple[Sheet, str]:
        t = _interior_tile(b, rng)
        k = int(rng.integers(4))
        a = rng.uniform(0, 2 * np.pi)
        shift = d * np.array([math.cos(a), math.sin(a)])
        out = b.sheet.copy()
        P = b.tiles[t, k]
        items = []
        # the cut lines around a tile corner: offset by the kerf (and, in a ligament sheet, the tile shrink)
        r = (
            1e-3
            if b.hinge == "tape"
            else 0.3 + b.manifest["kerf_offset_mm"] + b.manifest["tile_shrink_mm"]
        )
        for p, c in out.layers["CUT"]:
            near = np.linalg.norm(p - P, axis=1) <= r
            if near.any():
                p = p.copy()
                p[near] += shift
            items.append((p, c))
        out.layers["CUT"] = items
        return out, f"tile {t}"

    return m


def _congruent(P: np.ndarray, Q: np.ndarray, tol: float = 0.05) -> bool:
    """Whether quads P and Q are properly congruent (any corner shift) within ``tol``."""
    from fabkiri.pattern import geometry

    return min(geometry.aligned_distance(np.roll(Q, k, 0), P) for k in range(4)) <= tol


def _mirror_quad(Q: np.ndarray) -> np.ndarray:
    M = Q.copy()
    M[:, 0] *= -1
    return M[::-1]


def tile_mirrored(b: Base, rng) -> tuple[Sheet, str]:
    t = _interior_tile(b, rng)
    if _congruent(b.tiles[t], _mirror_quad(b.tiles[t])):
        return None, ""  # a mirror-symmetric tile: mirroring changes nothing
    c = b.tiles[t].mean(0)
    e = b.tiles[t, 1] - b.tiles[t, 0]
    u = e / np.linalg.norm(e)

    def refl(q):
        d = q - c
        along = (d @ u)[:, None] * u
        return c + 2 * along - d  # reflect across the line through c along u

    return move_vertices_of_tile(b, t, refl), f"tile {t}"


def tile_missing(b: Base, rng) -> tuple[Sheet, str]:
    """Separate: one outline left out; in place: every cut line on a boundary tile's free edges removed."""
    out = b.sheet.copy()
    cut = out.layers["CUT"]
    if b.hinge == "separate":
        t = int(rng.integers(len(b.tiles)))
        c = b.tiles[t].mean(0)
        k = next(
            i for i, (p, cl) in enumerate(cut) if cl and shapely.contains_xy(shapely.Polygon(p), *c)
        )
        out.layers["CUT"] = cut[:k] + cut[k + 1 :]
        return out, f"tile {t}"
    return None, ""


def tiles_swapped(b: Base, rng) -> tuple[Sheet, str]:
    """Separate: one outline replaced by a copy of another tile's (the count stays, a shape is missing)."""
    if b.hinge != "separate":
        return None, ""
    out = b.sheet.copy()
    cut = out.layers["CUT"]
    T = len(b.tiles)
    i, j = rng.choice(T, 2, replace=False)
    if _congruent(b.tiles[i], b.tiles[j]):
        return None, ""  # congruent tiles: the copy is the same part
    ki = next(
        k
        for k, (p, cl) in enumerate(cut)
        if cl and shapely.contains_xy(shapely.Polygon(p), *b.tiles[i].mean(0))
    )
    kj = next(
        k
        for k, (p, cl) in enumerate(cut)
        if cl and shapely.contains_xy(shapely.Polygon(p), *b.tiles[j].mean(0))
    )
    pj = cut[kj][0]
    cut[ki] = (pj - pj.mean(0) + cut[ki][0].mean(0), True)
    return out, f"tile {int(i)}"


def _segments_of(sheet: Sheet) -> list[tuple[int, int]]:
    """(polyline, vertex) of every CUT segment start."""
    out = []
    for i, (p, c) in enumerate(sheet.layers["CUT"]):
        n = len(p) if c else len(p) - 1
        out += [(i, k) for k in range(n)]
    return out


def _slit(b: Base, rng) -> tuple[int, int]:
    """A slit between two tiles (tape): (polyline, segment) of a CUT segment inside the sheet, not on its outline."""
    cut = b.sheet.layers["CUT"]
    outline = shapely.union_all(shapely.polygons(b.tiles)).buffer(0.01, join_style="mitre").exterior
    centre = b.tiles.reshape(-1, 2).mean(0)
    cands = []
    for i, (p, c) in enumerate(cut):
        if c:
            continue
        for k in range(len(p) - 1):
            mid = 0.5 * (p[k] + p[k + 1])
            if (
                shapely.distance(shapely.Point(mid), outline) > 1.0
                and np.linalg.norm(p[k + 1] - p[k]) > 0.5
            ):
                cands.append((float(np.linalg.norm(mid - centre)), i, k))
    cands.sort()
    _, i, k = cands[int(rng.integers(0, max(1, len(cands) // 3)))]
    return i, k


def _cut_slit(b: Base, rng, end_of) -> Sheet:
    """Split the slit's polyline at the chosen segment; the segment now ends at ``end_of(a, b)`` (None: dropped)."""
    out = b.sheet.copy()
    i, k = _slit(b, rng)
    p = out.layers["CUT"][i][0]
    a, e = p[k], p[k + 1]
    first = p[: k + 1]
    stop = end_of(a, e)
    if stop is not None:
        first = np.vstack([first, stop])
    pieces = [q for q in (first, p[k + 1 :]) if len(q) >= 2]
    out.layers["CUT"][i : i + 1] = [(q, False) for q in pieces]
    return out


def slit_shortened(d: float):
    def m(b: Base, rng):
        if b.hinge != "tape":
            return None, ""
        return _cut_slit(b, rng, lambda a, e: e - d * (e - a) / np.linalg.norm(e - a)), "slit"

    return m


def slit_halfway(b: Base, rng):
    if b.hinge != "tape":
        return None, ""
    return _cut_slit(b, rng, lambda a, e: 0.5 * (a + e)), "slit"


def slit_removed(b: Base, rng):
    if b.hinge != "tape":
        return None, ""
    return _cut_slit(b, rng, lambda a, e: None), "slit"


def extra_cut(frac: float):
    """A straight cut across (frac=1) or into (frac<1) an interior tile."""

    def m(b: Base, rng):
        t = _interior_tile(b, rng)
        Q = b.tiles[t]
        if b.hinge == "separate":  # the outline on the sheet: find it by centroid
            c = Q.mean(0)
            poly = next(
                shapely.Polygon(p)
                for p, cl in b.sheet.layers["CUT"]
                if cl and shapely.contains_xy(shapely.Polygon(p), *c)
            )
            Q = np.asarray(poly.exterior.coords)[:4]
            Q = (
                np.asarray(shapely.Polygon(poly).minimum_rotated_rectangle.exterior.coords)[:4]
                if len(poly.exterior.coords) != 5
                else Q
            )
        a, bb = 0.5 * (Q[0] + Q[1]), 0.5 * (Q[2] + Q[3])
        end = a + frac * (bb - a) if frac < 1 else bb + 0.0 * (bb - a)
        out = b.sheet.copy()
        out.layers["CUT"].append((np.array([a, end]), False))
        return out, f"tile {t}"

    return m


def ligament_severed(every: bool):
    def m(b: Base, rng):
        if b.hinge != "ligament":
            return None, ""
        feats = b.manifest["hinge_features"]
        picks = feats if every else [feats[int(rng.integers(len(feats)))]]
        out = b.sheet.copy()
        for f in picks:
            poly = shapely.Polygon(f["polygon"])
            r = poly.minimum_rotated_rectangle
            c = np.asarray(r.exterior.coords)[:4]
            e = np.linalg.norm(np.roll(c, -1, 0) - c, axis=1)
            k = int(
                np.argmax(e)
            )  # cut across the strip: through the middle, along its short side, reaching out
            a, bb = 0.5 * (c[k] + c[(k + 1) % 4]), 0.5 * (c[(k + 2) % 4] + c[(k + 3) % 4])
            mid = 0.5 * (a + bb)
            short = c[(k + 1) % 4] - c[k]
            short = np.asarray(c[(k + 2) % 4] - c[(k + 1) % 4])
            u = short / np.linalg.norm(short)
            w = float(e.min())
            out.layers["CUT"].append(
                (np.array([mid - u * (0.5 * w + 0.3), mid + u * (0.5 * w + 0.3)]), False)
            )
        return out, f"hinge {picks[0]['hinge']}"

    return m


def tile_copied_beside(b: Base, rng):
    """An extra piece: a copy of a tile's outline (its own closed outline where it has one, else the
    design tile) cut beside the sheet's other parts."""
    t = _interior_tile(b, rng)
    c = shapely.Point(b.tiles[t].mean(0))
    area = shapely.Polygon(b.tiles[t]).area
    own = [
        p
        for p, cl in b.sheet.layers["CUT"]
        if cl
        and len(p) >= 4
        and shapely.Polygon(p).contains(c)
        and shapely.Polygon(p).area < 2 * area
    ]
    q = own[0] if own else b.tiles[t]
    x1 = _cut_points(b.sheet)[:, 0].max()
    out = b.sheet.copy()
    out.layers["CUT"].append((q + np.array([x1 + 20.0 - q[:, 0].min(), 0.0]), True))
    return out, f"tile {t}"


def ligaments_cut_away(b: Base, rng):
    """Every ligament cut away: each tile's core cut out on its own, in place (the line the writer draws
    round a core: the tile shrunk by the tile shrink, grown by the kerf offset), the reference square
    kept. Without the manifest they read as separate tiles, each smaller than its design tile."""
    if b.hinge != "ligament":
        return None, ""
    man = b.manifest
    grow = float(man.get("kerf_offset_mm", 0.0)) - float(man.get("tile_shrink_mm", 0.0))
    cores = shapely.buffer(
        shapely.polygons(b.tiles),
        grow,
        join_style="mitre",
        mitre_limit=man.get("mitre_limit", 10.0),
    )
    out = b.sheet.copy()
    out.layers["CUT"] = [(np.asarray(c.exterior.coords)[:-1], True) for c in cores]
    if man.get("reference_square"):
        out.layers["CUT"].append((np.asarray(man["reference_square"]["corners"], float), True))
    return out, f"hinge {man['hinge_features'][0]['hinge']}"


def _mark_items(b: Base, h: int) -> list[int]:
    """ENGRAVE items of the tape mark at hinge ``h``: two-point strokes of 2.5 mm or more inside tile B
    within 12 mm of the hinge (fabkiri puts the face letter on tile A and this chord on tile B)."""
    row = b.manifest["hinges"][h]
    poly = shapely.Polygon(b.tiles[int(row["tiles"][1])]).buffer(1e-6)
    pos = np.asarray(row["position_b"], float)
    out = []
    for i, (p, c) in enumerate(b.sheet.layers.get("ENGRAVE", [])):
        if (
            len(p) == 2
            and not c
            and np.linalg.norm(p[1] - p[0]) >= 2.5
            and shapely.contains_xy(poly, p[:, 0], p[:, 1]).all()
            and np.linalg.norm(p - pos, axis=1).max() < 12
        ):
            out.append(i)
    return out


def _marked_hinges(b: Base) -> list[int]:
    return [h for h in range(len(b.manifest.get("hinges", []))) if _mark_items(b, h)]


def tape_mark_missing(b: Base, rng):
    if b.hinge != "tape" or not (hs := _marked_hinges(b)):
        return None, ""
    h = hs[int(rng.integers(len(hs)))]
    out = b.sheet.copy()
    drop = set(_mark_items(b, h))
    out.layers["ENGRAVE"] = [it for i, it in enumerate(out.layers["ENGRAVE"]) if i not in drop]
    return out, f"hinge {h}"


def tape_mark_moved(b: Base, rng):
    """The chord moved 3 mm towards its tile's centre: it no longer spans the corner."""
    if b.hinge != "tape" or not (hs := _marked_hinges(b)):
        return None, ""
    h = hs[int(rng.integers(len(hs)))]
    out = b.sheet.copy()
    c = b.tiles[int(b.manifest["hinges"][h]["tiles"][1])].mean(0)
    for i in _mark_items(b, h):
        p, cl = out.layers["ENGRAVE"][i]
        u = c - p.mean(0)
        out.layers["ENGRAVE"][i] = (p + 3.0 * u / np.linalg.norm(u), cl)
    return out, f"hinge {h}"


def tape_marks_removed(b: Base, rng):
    if b.hinge != "tape" or not (hs := _marked_hinges(b)):
        return None, ""
    drop = {i for h in hs for i in _mark_items(b, h)}
    out = b.sheet.copy()
    out.layers["ENGRAVE"] = [it for i, it in enumerate(out.layers["ENGRAVE"]) if i not in drop]
    return out, f"hinge {hs[0]}"


def ligament_cut_into(b: Base, rng):
    """A cut from one side of a ligament to its middle (the ligament is weakened, not severed)."""
    if b.hinge != "ligament":
        return None, ""
    feats = b.manifest["hinge_features"]
    f = feats[int(rng.integers(len(feats)))]
    r = shapely.Polygon(f["polygon"]).minimum_rotated_rectangle
    c = np.asarray(r.exterior.coords)[:4]
    e = np.linalg.norm(np.roll(c, -1, 0) - c, axis=1)
    k = int(np.argmax(e))
    mid = c.mean(0)
    short = c[(k + 2) % 4] - c[(k + 1) % 4]
    u = short / np.linalg.norm(short)
    w = float(e.min())
    out = b.sheet.copy()
    out.layers["CUT"].append((np.array([mid - u * (0.5 * w + 0.3), mid]), False))
    return out, f"hinge {f['hinge']}"


def sheet(fn) -> Callable:
    return lambda b, rng: (b.sheet.map_points(fn), "sheet")


def sheet_mirrored(b: Base, rng):
    W = b.sheet.width
    return b.sheet.map_points(lambda p: np.column_stack([W - p[:, 0], p[:, 1]])), "sheet"


# ------------------------------------------------------------------ the catalogue


@dataclass(frozen=True)
class Kind:
    name: str
    valid: bool
    fmt: str  # dxf | svg | any
    change: Callable | None  # (Base, rng) -> (Sheet | None, what) ; None: the sheet as is
    style: str = ""  # writer style
    manifest: str = "keep"  # keep | kerf0 (undeclared kerf) | needs-manifest (only the manifest tells it broken)
    hinges: tuple = ("tape", "separate", "ligament")
    chiral: bool = (
        False  # a mirror of the whole sheet: a breakage only for a sheet without mirror symmetry
    )


def then(change, after):
    """``change``, then the sheet-wide ``after`` (when ``change`` applies)."""

    def m(b, rng):
        sh, what = change(b, rng)
        return (None, "") if sh is None else (after(sh), what)

    return m


def _keep(b, rng):
    return b.sheet, ""


def _g(fn):
    return lambda b, rng: (fn(b.sheet), "")


VALID = [
    Kind("re-save (ezdxf LWPOLYLINE)", True, "dxf", _keep, "lw"),
    Kind("re-save R2018", True, "dxf", _keep, "r2018"),
    Kind("LINE segments", True, "dxf", _keep, "lines"),
    Kind("old-style POLYLINE", True, "dxf", _keep, "poly2d"),
    Kind("in a block, INSERT at origin", True, "dxf", _keep, "block"),
    Kind("in a block, INSERT moved and turned 30°", True, "dxf", _keep, "block-moved"),
    Kind("flipped OCS (extrusion -Z)", True, "dxf", _keep, "ocs"),
    Kind("colour only, all on layer 0", True, "dxf", _keep, "layer0"),
    Kind("declared inches", True, "dxf", _keep, "inch"),
    Kind("declared cm", True, "dxf", _keep, "cm"),
    Kind("unitless ($INSUNITS 0)", True, "dxf", _keep, "unitless"),
    Kind("lower-case layer names", True, "dxf", _keep, "lower"),
    Kind("re-save (paths in groups)", True, "svg", _keep, "groups"),
    Kind("Inkscape layers (inkscape:label only)", True, "svg", _keep, "labels"),
    Kind("colour only, no groups", True, "svg", _keep, "colour"),
    Kind("polyline/polygon elements", True, "svg", _keep, "polyline"),
    Kind("relative path commands", True, "svg", _keep, "relative"),
    Kind("line elements", True, "svg", _keep, "lines"),
    Kind("group transform (rigid)", True, "svg", _keep, "transform"),
    Kind("px user units", True, "svg", _keep, "px"),
    Kind("size in cm", True, "svg", _keep, "cm"),
    Kind("size in inches", True, "svg", _keep, "inch"),
    Kind("translated", True, "any", sheet(rigid(0.0, (123.4, -56.7)))),
    Kind("turned 90°", True, "any", sheet(rigid(math.pi / 2, (400, 0)))),
    Kind("turned 180°", True, "any", sheet(rigid(math.pi, (600, 400)))),
    Kind("turned 33°", True, "any", sheet(rigid(math.radians(33), (100, -50)))),
    Kind("turned 271.5° and moved", True, "any", sheet(rigid(math.radians(271.5), (-80, 700)))),
    Kind("turned 0.7°", True, "any", sheet(rigid(math.radians(0.7), (0, 0)))),
    Kind("closed outlines split in two open pieces", True, "any", _g(_split_closed)),
    Kind("every segment a separate piece", True, "any", _g(_explode)),
    Kind("reversed directions", True, "any", _g(_reverse)),
    Kind("shuffled entity order", True, "any", _g(_shuffle)),
    Kind("rounded to 0.001 mm", True, "any", _g(_round(3))),
    Kind("rounded to 0.0001 mm", True, "any", _g(_round(4))),
    Kind("NOTES layer removed", True, "any", _g(_drop_layers("NOTES"))),
    Kind("ENGRAVE layer removed", True, "any", _g(_drop_layers("ENGRAVE"))),
    Kind(
        "split pieces, shuffled, turned 12°",
        True,
        "any",
        lambda b, rng: (
            _shuffle(_split_closed(b.sheet.map_points(rigid(math.radians(12), (5, 5))))),
            "",
        ),
    ),
    Kind(
        "LINEs of a turned sheet", True, "dxf", sheet(rigid(math.radians(57), (300, -100))), "lines"
    ),
    Kind("rounded 0.001 mm, colour only", True, "svg", _g(_round(3)), "colour"),
    Kind("block of a rounded sheet", True, "dxf", _g(_round(3)), "block-moved"),
    Kind("OCS of a turned sheet", True, "dxf", sheet(rigid(math.radians(-20), (0, 200))), "ocs"),
    Kind("Inkscape layers of exploded segments", True, "svg", _g(_explode), "labels"),
]

BROKEN = [
    Kind("corner moved 0.1 mm", False, "any", corner_moved(0.1), hinges=("tape", "separate")),
    Kind("corner moved 0.06 mm", False, "any", corner_moved(0.06), hinges=("tape", "separate")),
    Kind("tile scaled 1%", False, "any", tile_scaled(1.01)),
    Kind("tile scaled 0.99", False, "any", tile_scaled(0.99)),
    Kind("tile turned 0.5°", False, "any", tile_turned(0.5), hinges=("tape", "ligament")),
    Kind("tile turned 2°", False, "any", tile_turned(2.0), hinges=("tape", "ligament")),
    Kind("tile moved 0.2 mm", False, "any", tile_moved(0.2), hinges=("tape", "ligament")),
    Kind("tile mirrored", False, "any", tile_mirrored),
    Kind("tile missing", False, "any", tile_missing, hinges=("separate",)),
    Kind("tile replaced by a copy of another", False, "any", tiles_swapped, hinges=("separate",)),
    Kind("sheet scaled 1%", False, "any", sheet(lambda p: p * 1.01)),
    Kind("sheet scaled 0.995", False, "any", sheet(lambda p: p * 0.995)),
    Kind("sheet stretched 1% in x", False, "any", sheet(lambda p: p * np.array([1.01, 1.0]))),
    Kind(
        "sheet sheared 1%",
        False,
        "any",
        sheet(lambda p: p + np.column_stack([0.01 * p[:, 1], 0 * p[:, 0]])),
    ),
    Kind("sheet mirrored", False, "any", sheet_mirrored, chiral=True),
    Kind("mirrored through the OCS", False, "dxf", _keep, "ocs-mirror", chiral=True),
    Kind("inch-for-mm", False, "dxf", _keep, "inch-for-mm"),
    Kind("inch-for-mm (SVG size)", False, "svg", _keep, "inch-for-mm"),
    Kind("viewBox 1% off", False, "svg", _keep, "viewbox-scaled"),
    Kind("mirror transform", False, "svg", _keep, "mirror", chiral=True),
    Kind("slit shortened 10 µm", False, "any", slit_shortened(0.01), hinges=("tape",)),
    Kind("slit shortened 0.1 mm", False, "any", slit_shortened(0.1), hinges=("tape",)),
    Kind("slit cut halfway", False, "any", slit_halfway, hinges=("tape",)),
    Kind("slit missing", False, "any", slit_removed, hinges=("tape",)),
    Kind("extra cut through a tile", False, "any", extra_cut(1.0)),
    Kind("extra cut halfway into a tile", False, "any", extra_cut(0.5)),
    Kind("extra cut 10% into a tile", False, "any", extra_cut(0.1)),
    Kind("a ligament severed", False, "any", ligament_severed(False), hinges=("ligament",)),
    Kind("every ligament severed", False, "any", ligament_severed(True), hinges=("ligament",)),
    Kind(
        "every ligament cut away",
        False,
        "any",
        ligaments_cut_away,
        hinges=("ligament",),
    ),
    Kind("a copy of a tile beside the parts", False, "any", tile_copied_beside),
    Kind("undeclared kerf", False, "any", _keep, manifest="kerf0", hinges=("separate", "ligament")),
    Kind(
        "sheet scaled 1%, turned 40°",
        False,
        "any",
        sheet(lambda p: rigid(math.radians(40), (0, 0))(p) * 1.01),
    ),
    Kind("tile scaled 1% in LINEs", False, "dxf", tile_scaled(1.01), "lines"),
    Kind("tile mirrored, colour only", False, "svg", tile_mirrored, "colour"),
    Kind(
        "corner moved 0.1 mm, Inkscape layers",
        False,
        "svg",
        corner_moved(0.1),
        "labels",
        hinges=("tape", "separate"),
    ),
    Kind(
        "tile turned 1° in a block",
        False,
        "dxf",
        tile_turned(1.0),
        "block-moved",
        hinges=("tape", "ligament"),
    ),
    Kind(
        "slit shortened 10 µm, LINEs", False, "dxf", slit_shortened(0.01), "lines", hinges=("tape",)
    ),
    Kind("extra cut, polyline elements", False, "svg", extra_cut(1.0), "polyline"),
    Kind("sheet mirrored, R2018", False, "dxf", sheet_mirrored, "r2018", chiral=True),
    Kind("tile scaled 1%, split pieces", False, "any", then(tile_scaled(1.01), _split_closed)),
    Kind(
        "corner moved 0.1 mm, rounded 0.001",
        False,
        "any",
        then(corner_moved(0.1), _round(3)),
        hinges=("tape", "separate"),
    ),
    Kind(
        "tile mirrored in a turned sheet",
        False,
        "any",
        then(tile_mirrored, lambda s: s.map_points(rigid(math.radians(75), (0, 0)))),
    ),
    Kind(
        "a ligament severed, LINEs",
        False,
        "dxf",
        ligament_severed(False),
        "lines",
        hinges=("ligament",),
    ),
    Kind("a ligament cut halfway", False, "any", ligament_cut_into, hinges=("ligament",)),
    Kind("a tape mark missing", False, "any", tape_mark_missing, hinges=("tape",)),
    Kind("a tape mark moved off its corner", False, "any", tape_mark_moved, hinges=("tape",)),
    Kind(
        "every tape mark removed (labels kept)",
        False,
        "any",
        tape_marks_removed,
        manifest="needs-manifest",
        hinges=("tape",),
    ),
]


def default_style(fmt: str) -> str:
    return "lw" if fmt == "dxf" else "groups"


def make_case(b: Base, kind: Kind, out: Path, with_manifest: bool, seed: int = 0) -> Path | None:
    """Write the variant ``kind`` of ``b`` into folder ``out``; None when the kind does not apply."""
    if b.hinge not in kind.hinges or kind.fmt not in ("any", b.fmt):
        return None
    if kind.manifest in ("kerf0", "needs-manifest") and not with_manifest:
        return None  # a breakage only the manifest can tell (it declares the kerf, or that marks are cut)
    if kind.chiral and b.extra.get("mirror_symmetric"):
        return None
    rng = np.random.default_rng(seed)
    sh, _ = kind.change(b, rng)
    if sh is None:
        return None
    out.mkdir(parents=True, exist_ok=True)
    name = b.manifest["sheets"][0][b.fmt]
    path = out / name
    style = kind.style or default_style(b.fmt)
    (write_dxf if b.fmt == "dxf" else write_svg)(sh, path, style)
    if with_manifest:
        man = json.loads(json.dumps(b.manifest))
        if kind.manifest == "kerf0":
            man["kerf_offset_mm"] = 0.0
        (out / "manifest.json").write_text(json.dumps(man))
    return path


def copy_folder(src: Path, dst: Path) -> None:
    shutil.copytree(src, dst)
