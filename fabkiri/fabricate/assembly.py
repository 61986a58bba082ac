"""Assembly map and bill of materials for ``fabkiri cut`` and ``fabkiri print``.

Every join (a tape piece for tape hinges and for separate tiles, a printed
strip for ``print --style strips``) gets a number in the order to make it:
top face first, then the bottom face (turn the piece over); on each face the
joins of a breadth-first spanning tree from tile 0 first, so every new piece
attaches a tile to the part already joined, then the joins that close loops.
A tape piece covers the two corner triangles the cut engraves (face letter on
tile A, chord across tile B): its length is that region's extent along the
line between the two triangles' centres.

The map is a PNG (one panel per face, as seen from above: the bottom panel
looks through the sheet) with the numbers drawn in the engraving font; the
data goes into the manifest under new keys (``assembly``,
``assembly_pieces``, ``bill_of_materials``).
"""

from __future__ import annotations

from typing import Any

import numpy as np
import shapely

from ..pattern.model import Pattern
from .cut.hingekinds import HingeKind
from .cut.text import text_strokes_many, text_width
from .map_labels import LabelLayout, place_labels
from .pngcanvas import DPI, Axes, Canvas, rgb
from .print.job import print_style

MAP_MAX_PIECES = (
    3000  # above this the numbers are not legible on one picture; the manifest still lists them
)
FILAMENT_DIAMETER_MM = 1.75
DENSITY_G_CM3 = {
    "PLA": 1.24,
    "PETG": 1.27,
    "TPU": 1.21,
    "ABS": 1.04,
    "ASA": 1.07,
}  # typical datasheet values


def join_order(pattern: Pattern, hinges: np.ndarray, top: np.ndarray) -> np.ndarray:
    """The order to make the joins ``hinges`` (top face first, spanning-tree joins first on each face)."""
    tree = pattern.topology.spanning_tree(0)
    rank = np.full(
        pattern.topology.n_hinges, len(tree.hinges) + pattern.topology.n_hinges, dtype=np.int64
    )
    rank[tree.hinges] = np.arange(len(tree.hinges))
    loops = np.setdiff1d(np.arange(pattern.topology.n_hinges), tree.hinges)
    rank[loops] = len(tree.hinges) + np.arange(len(loops))
    h = np.asarray(hinges)
    return h[np.lexsort((rank[h], ~np.asarray(top)[h]))]


def _corner_triangles(
    Q: np.ndarray, tiles: np.ndarray, ks: np.ndarray, frac: float, reach_mm: float
) -> np.ndarray:
    q = Q[tiles, ks]
    n = Q.shape[1]  # the tile arity
    q1, q0 = Q[tiles, (ks + 1) % n], Q[tiles, (ks - 1) % n]

    def reach(a, b):
        return np.minimum(frac, reach_mm / np.maximum(np.linalg.norm(b - a, axis=1), 1e-300))[
            :, None
        ]

    return np.stack([q, q + reach(q, q1) * (q1 - q), q + reach(q, q0) * (q0 - q)], 1)


def tape_pieces(
    pattern: Pattern,
    Q: np.ndarray,
    sheet_of: np.ndarray,
    letters: list[str],
    kind: HingeKind,
    frac: float,
    reach_mm: float,
) -> list[dict[str, Any]]:
    """One row per tape piece, numbered in join order (``Q``: placed tile corners on the sheets)."""
    top_ = pattern.topology
    A, B = top_.hinge_tiles.T
    cA, cB = top_.hinge_corner.T
    if kind.one_piece or top_.n_hinges == 0:
        return []
    face_top = np.array([f == "T" for f in letters])
    order = join_order(pattern, np.arange(top_.n_hinges), face_top)
    ta = _corner_triangles(Q, A, cA, frac, reach_mm)
    tb = _corner_triangles(Q, B, cB, frac, reach_mm)
    # tiles apart on the sheet (separate tiles, split sheets): the piece spans one corner pair, twice A's reach
    apart = (sheet_of[A] != sheet_of[B]) | kind.cut_apart
    u = ta.mean(1) - tb.mean(1)
    u = u / np.maximum(np.linalg.norm(u, axis=1), 1e-12)[:, None]
    s = np.einsum("hkd,hd->hk", np.concatenate([ta, tb], 1), u)
    length = np.where(
        apart, 2.0 * np.linalg.norm(ta - ta[:, :1], axis=2).max(1), s.max(1) - s.min(1)
    )
    where = np.where(apart[:, None], ta[:, 0], 0.5 * (ta[:, 0] + tb[:, 0]))
    where, length = np.round(where, 3).tolist(), np.round(length, 3).tolist()
    sheet = (sheet_of[A] + 1).tolist()
    A, B = A.tolist(), B.tolist()
    return [
        {
            "piece": n,
            "hinge": h,
            "tiles": [A[h], B[h]],
            "face": letters[h],
            "sheet": sheet[h],
            "at_mm": where[h],
            "length_mm": length[h],
        }
        for n, h in enumerate(order.tolist(), 1)
    ]


def cut_bom(
    manifest: dict, pieces: list[dict], tile_area_mm2: float, n_hinges: int, kind: HingeKind
) -> dict[str, Any]:
    sheets = manifest["sheets"]
    mat = manifest["material"]
    return {
        "material": mat["name"],
        "thickness_mm": mat["thickness_mm"],
        "hinge": manifest["hinge"],
        "sheets": len(sheets),
        "sheet_mm": [[s["width_mm"], s["height_mm"]] for s in sheets],
        "sheet_area_mm2": round(sum(s["width_mm"] * s["height_mm"] for s in sheets), 3),
        "parts_area_mm2": round(tile_area_mm2, 3),
        "tiles": len(manifest["tiles"]),
        "tape_pieces": len(pieces),
        "tape_length_mm": round(sum(p["length_mm"] for p in pieces), 3),
        "tape_top": sum(p["face"] == "T" for p in pieces),
        "tape_bottom": sum(p["face"] == "B" for p in pieces),
        "ligaments": n_hinges if kind.one_piece else 0,
        "cut_length_mm": round(sum(s["cut_length_mm"] for s in sheets), 3),
        "cut_time_s": round(sum(s["cut_time_s"] for s in sheets), 1),
    }


def _numbers(ax: Axes, texts: list[str], at: LabelLayout) -> None:
    """The numbers where ``at`` placed them; a grey leader line to each one that had to move."""
    if not texts:
        return
    lead = [np.array([a, c]) for a, c in zip(at.anchors[at.moved], at.centres[at.moved])]
    if lead:
        ax.lines(lead, rgb("0.35"), 0.5)
        ax.dots(at.anchors[at.moved], rgb("0.35"), 1.5)
    xy, counts, _ = text_strokes_many(texts, at.heights, at.centres)
    ax.lines(np.split(xy, np.cumsum(counts)[:-1]), rgb("k"), 0.9)


def map_labels(
    corners_by_sheet: list[np.ndarray],
    pieces: list[dict],
    shapes: dict[int, np.ndarray],
    faces: tuple[str, ...] = ("T", "B"),
) -> dict[str, tuple[list[str], LabelLayout]]:
    """Per face drawn: the pieces' numbers and where they go on the map (mm, sheets side by side)."""
    offs = _sheet_offsets(corners_by_sheet)
    size = _piece_size(shapes)
    out = {}
    for face in faces:
        mine = [p for p in pieces if p["face"] == face]
        if not mine:
            continue
        cen = np.array([(shapes[p["piece"]] + offs[p["sheet"] - 1]).mean(0) for p in mine])
        texts = [str(p["piece"]) for p in mine]
        h = np.array([min(0.45 * size, 0.9 * size / max(text_width(t), 1e-9)) for t in texts])
        out[face] = (texts, place_labels(cen, texts, float(np.median(h))))
    return out


def _sheet_offsets(corners_by_sheet: list[np.ndarray], gap: float = 20.0) -> list[np.ndarray]:
    """Where each sheet goes on the map: side by side, ``gap`` mm apart, bottoms at y = 0."""
    offs, x = [], 0.0
    for c in corners_by_sheet:
        a, b = c.reshape(-1, 2).min(0), c.reshape(-1, 2).max(0)
        offs.append(np.array([x - a[0], -a[1]]))
        x += b[0] - a[0] + gap
    return offs


def _piece_size(shapes: dict[int, np.ndarray]) -> float:
    return (
        float(np.median([np.linalg.norm(s[1] - s[0]) for s in shapes.values()])) if shapes else 5.0
    )


def map_png(
    corners_by_sheet: list[np.ndarray],
    pieces: list[dict],
    shapes: dict[int, np.ndarray],
    title: str,
    faces=("T", "B"),
    face_names=("top face", "bottom face, seen from above through the sheet"),
    max_px: int = 3000,
) -> bytes:
    """Numbered map: one panel per face; tiles in grey, each join's region coloured with its number.

    ``corners_by_sheet[s]``: (T_s, 4, 2) tiles on sheet s (drawn side by side); ``shapes[piece]``: its
    outline (n, 2) on its sheet; ``pieces`` rows need ``piece``, ``face``, ``sheet`` (1-based).
    """
    gap = 20.0
    lo = [c.reshape(-1, 2).min(0) for c in corners_by_sheet]
    hi = [c.reshape(-1, 2).max(0) for c in corners_by_sheet]
    offs = _sheet_offsets(corners_by_sheet, gap)
    W = sum(b[0] - a[0] for a, b in zip(lo, hi)) + gap * (len(lo) - 1)
    H = max(b[1] - a[1] for a, b in zip(lo, hi))
    shown = [f for f in faces if any(p["face"] == f for p in pieces)] or [faces[0]]
    n = len(shown)
    size = _piece_size(shapes)
    labels = map_labels(corners_by_sheet, pieces, shapes, faces)
    px_mm = min(max(2.0, 60.0 / max(size, 1e-6)), max_px / max(W, n * H))
    # the figure's height as before: the panels plus 0.8 inch for the titles
    cv = Canvas(W * px_mm, (n * H + (n - 1) * gap) * px_mm + 0.8 * DPI)
    for k, face in enumerate(shown):
        ax = cv.axes(
            (0, 1 - (k + 1) / n, 1, 1 / n - 0.25 / (n * H * px_mm / DPI + 0.8)),
            (-2, W + 2),
            (-2, H + 2),
        )
        ax.title(f"{title}: {face_names[faces.index(face)]}", max(11.0, 1.1 * W * px_mm / DPI))
        for s, c in enumerate(corners_by_sheet):
            ax.polygons(c + offs[s], rgb("0.93"), rgb("0.55"), 0.4)
        mine = [p for p in pieces if p["face"] == face]
        col = "#1f77b4" if face == faces[0] else "#d62728"
        polys = [shapes[p["piece"]] + offs[p["sheet"] - 1] for p in mine]
        if polys:
            ax.polygons(polys, rgb(col, 0.35), rgb(col, 0.35), 0.6)
            _numbers(ax, *labels[face])
    return cv.png()


def tape_shapes(
    pattern: Pattern, Q: np.ndarray, pieces: list[dict], frac: float, reach_mm: float
) -> dict[int, np.ndarray]:
    """Each tape piece's outline: the convex hull of its two corner triangles (A's only, for tiles apart)."""
    top_ = pattern.topology
    h = np.array([p["hinge"] for p in pieces], dtype=np.int64)
    A, B = top_.hinge_tiles[h].T
    cA, cB = top_.hinge_corner[h].T
    ta = _corner_triangles(Q, A, cA, frac, reach_mm)
    tb = _corner_triangles(Q, B, cB, frac, reach_mm)
    together = np.linalg.norm(Q[A, cA] - Q[B, cB], axis=1) < 1e-6
    pts = np.concatenate([ta, np.where(together[:, None, None], tb, ta)], 1)  # (N, 6, 2)
    hulls = shapely.convex_hull(
        shapely.multipoints(pts.reshape(-1, 2), indices=np.repeat(np.arange(len(h)), 6))
    )
    rings = shapely.get_exterior_ring(hulls)
    return {p["piece"]: shapely.get_coordinates(r)[:-1] for p, r in zip(pieces, rings)}


# ----------------------------------------------------------------------- print


def print_assembly(r) -> dict[str, Any]:
    """BOM of a print job: bodies, strips, filament per material (volume, mass, length of 1.75 mm filament)."""
    job = r.job
    plan = job.plan
    per: dict[str, float] = {}
    bodies = []
    for bed, tms in zip(job.beds, r.meshes):
        for b, tm in zip(bed, tms):
            mat = b.material or job.printer.tile_material
            v = float(tm.volume)
            per[mat] = per.get(mat, 0.0) + v
            bodies.append(
                {"name": b.name, "kind": b.kind, "material": mat, "volume_mm3": round(v, 3)}
            )
    area = np.pi * (FILAMENT_DIAMETER_MM / 2) ** 2
    filament = {
        m: {
            "volume_mm3": round(v, 3),
            "length_m": round(v / area / 1000, 3),
            "mass_g": round(v / 1000 * DENSITY_G_CM3.get(m.upper(), 1.24), 2),
            "density_g_cm3": DENSITY_G_CM3.get(m.upper(), 1.24),
        }
        for m, v in per.items()
    }
    n_top = int(plan.top.sum())
    strips = print_style(job.style).strip_hinges
    out = {
        "style": job.style,
        "tiles": len(plan.tiles),
        "hinges": plan.n_hinges,
        "strips": plan.n_hinges if strips else 0,
        "strips_top": n_top if strips else 0,
        "strips_bottom": plan.n_hinges - n_top if strips else 0,
        "beds": len(job.beds),
        "bodies": bodies,
        "filament": filament,
        "filament_note": f"{FILAMENT_DIAMETER_MM} mm filament, typical densities; solid volumes (the "
        "slicer's infill and supports change them)",
    }
    return out


def print_pieces(pattern: Pattern, r) -> tuple[list[dict], dict[int, np.ndarray]]:
    """Strips numbered in join order (strips style: glued by hand) with their outlines on the plan."""
    job = r.job
    plan = job.plan
    if (
        not print_style(job.style).loose_strips or job.strips is None
    ):  # other styles print their hinges in place
        return [], {}
    H = plan.n_hinges
    order = join_order(pattern, np.arange(H), plan.top)
    rows, shapes = [], {}
    for n, h in enumerate(order.tolist(), 1):
        poly = job.strips.outline[h]
        g = (
            max(shapely.get_parts(poly), key=lambda p: p.area)
            if poly.geom_type != "Polygon"
            else poly
        )
        pts = np.asarray(g.exterior.coords)[:-1]
        rows.append(
            {
                "piece": n,
                "hinge": int(h),
                "tiles": plan.hinge_tiles[h].tolist(),
                "face": "T" if plan.top[h] else "B",
                "sheet": 1,
                "at_mm": np.round(plan.hinge_xy[h], 3).tolist(),
                "length_mm": round(_long_side(g), 3),
            }
        )
        shapes[n] = pts
    return rows, shapes


def _long_side(poly) -> float:
    """The longer side of a polygon's minimum rotated rectangle."""
    r = np.asarray(shapely.minimum_rotated_rectangle(poly).exterior.coords)
    sides = np.linalg.norm(np.diff(r[:3], axis=0), axis=1)
    return float(sides.max())


def add_to_print(
    manifest_text: str, pattern: Pattern, r, title: str
) -> tuple[str, dict[str, bytes]]:
    """The print manifest with ``bill_of_materials`` (and, for hand-glued strips, ``assembly_pieces`` and
    ``assembly.png``) added; the other keys stay as they are."""
    from ..verify.printmanifest import PrintManifest

    m = PrintManifest.from_json(manifest_text)
    pieces, shapes = print_pieces(pattern, r)
    files: dict[str, bytes] = {}
    if pieces:
        files["assembly.png"] = map_png(
            [r.job.plan.corners],
            pieces,
            shapes,
            title,
            face_names=("top-face strips", "bottom-face strips, seen from above"),
        )
        m.files = sorted(set(m.files) | set(files))
    m.assembly_pieces = pieces
    m.bill_of_materials = print_assembly(r)
    return m.to_json(), files
