"""A bent strip for an outline the square lattice cannot follow (a U, a horseshoe: a hollow between two
arms), given N x N tiles.

On a U the own split and the pocket split (``pocket_split.py``) leave the lattice's side to dive into the
gap and come back out; one lattice corner cannot start on both of the gap's inner corners, and every guess
ran the side across the gap. A U is a strip bent twice: with the lattice's corners at the arms' ends, one
long side runs round the outside, the other round the gap, and the fold-free start of ``inverse_map.py``
(the ``conformal`` guess on a re-split target) bends the lattice along it. The strip has about as many tiles
as the N x N asked, in rows and columns of the aspect its start is least distorted at.

``corner_split.bent_strip`` (make's) splits at sharp polyline vertices only; here the corners are where the
outline turns convexly by :data:`CORNER_DEG` within :data:`CORNER_SPAN` of its size, rounded or sharp.
"""

from __future__ import annotations

from itertools import combinations

import numpy as np
from scipy import sparse
from scipy.sparse.linalg import spsolve

from ..targets.curve import Target
from .corner_split import MAX_CANDIDATES, MIN_ACROSS, default_folds, distortion
from .inverse_map import TargetMesh, with_corners

SAMPLES = 4096  # curve samples the turning is summed over
# of the size: the stretch of outline a corner turns within (a rounded corner's arc)
CORNER_SPAN = 0.15
CORNER_DEG = 60.0  # a stretch turning convexly by this much holds a corner
PROBE_TILES = 256  # the candidates are scored on lattices of about this many tiles (16x16)
# aspects (columns over rows) scored: quarter octaves from 1 to 16 (the other turn of each split swaps them)
ASPECTS = 2.0 ** (np.arange(17) / 4.0)
# a triangle this small a share of the mesh's median triangle is flat (round-off of a collinear three)
FLAT = 1e-9


def turn_corners(target: Target) -> np.ndarray:
    """Curve parameters of the outline's convex corners: the middle of the turning in each stretch of
    :data:`CORNER_SPAN` of the size that turns convexly by at least :data:`CORNER_DEG`, strongest first,
    stretches apart by a span."""
    u = np.linspace(0.0, 1.0, SAMPLES, endpoint=False)
    p = target.point(u)
    a, b = p - np.roll(p, 1, 0), np.roll(p, -1, 0) - p
    turn = np.arctan2(a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0], (a * b).sum(1))  # CCW: convex > 0
    s = np.concatenate([[0.0], np.cumsum(np.linalg.norm(b, axis=1))])
    perimeter, half = s[-1], 0.5 * CORNER_SPAN * target.size
    s = s[:-1]
    # turning within +-half of each sample, the curve taken three times over so windows wrap
    s3 = np.concatenate([s - perimeter, s, s + perimeter])
    c3 = np.concatenate([[0.0], np.cumsum(np.tile(turn, 3))])
    lo, hi = np.searchsorted(s3, s - half), np.searchsorted(s3, s + half, "right")
    window = c3[hi] - c3[lo]
    found: list[float] = []
    left = window.copy()
    while len(found) < MAX_CANDIDATES and left.max() >= np.radians(CORNER_DEG):
        i = int(np.argmax(left))
        k = np.arange(lo[i], hi[i])  # the window's samples (indices into the tripled curve)
        run = np.cumsum(turn[k % SAMPLES])
        at = [
            k[min(int(np.searchsorted(run, f * run[-1])), len(k) - 1)] % SAMPLES
            for f in (0.25, 0.5, 0.75)
        ]
        # a stretch turning enough for two corners (a strip's rounded end, a crescent's tip) holds two
        # (a sharp vertex turns all at one sample: its two quarter points are one corner)
        found.extend(
            float(u[j]) for j in set(at[::2] if left[i] >= np.radians(2 * CORNER_DEG) else at[1:2])
        )
        mid = at[1]
        near = np.abs(np.mod(s - s[mid] + 0.5 * perimeter, perimeter) - 0.5 * perimeter) < 2 * half
        left[near] = -np.inf
    return np.sort(np.asarray(found))


def strip_shape(n: int, aspect: float) -> tuple[int, int]:
    """Rows and columns of about ``n`` tiles at ``aspect`` (columns over rows), at least :data:`MIN_ACROSS`
    either way: at most ``n`` unless that floor binds (a 6x6 asked on a long strip gets 12x4)."""
    rows = max(MIN_ACROSS, round(float(np.sqrt(n / aspect))))
    return rows, max(MIN_ACROSS, n // rows)


def _cotan_laplacian(nodes: np.ndarray, tri: np.ndarray) -> sparse.csr_matrix:
    """The cotangent Laplacian of a triangulation: its quadratic form is a piecewise linear function's
    Dirichlet energy."""
    i = np.concatenate([tri[:, (k + 1) % 3] for k in range(3)])
    j = np.concatenate([tri[:, (k + 2) % 3] for k in range(3)])
    o = np.concatenate([tri[:, k] for k in range(3)])
    a, b = nodes[i] - nodes[o], nodes[j] - nodes[o]
    w = 0.5 * (a * b).sum(1) / np.abs(a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0])
    n = len(nodes)
    W = sparse.csr_matrix(
        (np.concatenate([w, w]), (np.concatenate([i, j]), np.concatenate([j, i]))), (n, n)
    )
    return (sparse.diags(np.asarray(W.sum(1)).ravel()) - W).tocsr()


def _proper(nodes: np.ndarray, tri: np.ndarray) -> np.ndarray:
    """``tri`` without its flat triangles (a forked tail's mesh has some): their cotangent weights are
    infinite, and they hold no area for the energy."""
    a, b = nodes[tri[:, 1]] - nodes[tri[:, 0]], nodes[tri[:, 2]] - nodes[tri[:, 0]]
    area = np.abs(a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0])
    return tri[area > FLAT * np.median(area)]


def modulus(mesh: TargetMesh, corners: np.ndarray) -> float:
    """Rows over columns of the rectangle the outline split at ``corners`` (BL, BR, TR, TL) maps onto
    conformally: the Dirichlet energy of the harmonic function 0 on the left arc, 1 on the right, free on
    the bottom and top (a W x H rectangle: H / W)."""
    tri = _proper(mesh.nodes, mesh.tri)
    L = _cotan_laplacian(mesh.nodes, tri)
    nb, u = len(mesh.u), mesh.u

    def arc(a: float, b: float) -> np.ndarray:
        return np.mod(u - a, 1.0) <= np.mod(b - a, 1.0)

    fixed = np.zeros(len(mesh.nodes), bool)
    fixed[:nb] = arc(corners[1], corners[2]) | arc(corners[3], corners[0])
    used = np.zeros(len(mesh.nodes), bool)
    used[tri.ravel()] = True
    fixed |= ~used
    phi = np.zeros(len(mesh.nodes))
    phi[:nb][arc(corners[1], corners[2])] = 1.0
    free = np.flatnonzero(~fixed)
    phi[free] = spsolve(L[free][:, free].tocsc(), -(L[free][:, fixed] @ phi[fixed]))
    return float(phi @ (L @ phi))


def conformal_shape(mesh: TargetMesh, corners: np.ndarray, n: int) -> tuple[int, int]:
    """Rows and columns of about ``n`` tiles at the split's conformal :func:`modulus`: a rotating-squares
    pattern deploys about conformally, so its strip is as long for its width as the outline's."""
    return strip_shape(n, 1.0 / modulus(mesh, corners))


def strip_splits(
    target: Target, rows: int, cols: int, tries: int = 1
) -> list[tuple[Target, tuple[int, int]]]:
    """Where the pattern's harmonic map onto ``target``'s own split folds tiles at ``rows`` x ``cols``: the
    target re-split at four of its convex corners (:func:`turn_corners`), each with the rows x columns of
    about ``rows * cols`` tiles its fold-free start is least distorted at (``corner_split.distortion``,
    scored at :data:`PROBE_TILES`), least distorted first; else none. Every split is kept, not only those
    less distorted than the own split: a crescent's strip, its ends narrowing to the tips, scores a hair
    above the own split's folding start, and meets where every guess misses. Where fewer than ``tries``
    fours are found, each is offered again at its :func:`conformal_shape` (where that differs): on an S
    the least distorted start (by arc length along both sides, its inner side changing sides) is 42x6 for
    16x16 asked, where the conformal strip is about 60x4."""
    corners = turn_corners(target)
    if len(corners) < 4 or not default_folds(target, rows, cols):
        return []
    mesh = TargetMesh(target)
    shapes = [strip_shape(PROBE_TILES, a) for a in ASPECTS]
    shapes += [(c, r) for r, c in shapes]
    scored = []
    for quad in list(combinations(corners, 4))[:MAX_CANDIDATES]:
        d, rc = min((distortion(mesh, np.asarray(quad), *rc), rc) for rc in shapes)
        scored.append((d, quad, strip_shape(rows * cols, rc[1] / rc[0])))
    scored.sort(key=lambda x: x[0])
    found = [(np.asarray(q), rc) for _, q, rc in scored]
    for q, rc in found[: max(0, tries - len(found))]:
        again = conformal_shape(mesh, q, rows * cols)
        if again != rc:
            found.append((q, again))
    return [(with_corners(target, q), rc) for q, rc in found]
