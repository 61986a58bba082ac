"""``--min-opening F``: a floor on the deployed hole fraction, one inequality row of the design problem.

The hole fraction is the figure :mod:`fabkiri.pattern.opening` reports, Σ holes / (Σ tiles + Σ holes) of
the deployed sheet. With both sums positive, ``fraction >= F`` is the same as the row

    g(x) = ((1 - F) Σ_holes A_h(x) - F Σ_tiles A_t(x)) / T >= 0

(T tiles: the row is in tile areas per tile, the scale of the other area-like rows). Every area is a
shoelace sum, so the gradient is exact and sparse: ∂A/∂x_i = ½ (y_{i+1} - y_{i-1}), ∂A/∂y_i = ½ (x_{i-1}
- x_{i+1}) over the polygon's corners in counter-clockwise order (holes ordered as they wind in the
standard pattern, so a hole turned inside out counts negative). Checked against finite differences in
``tests/design/test_opening.py``.
"""

from __future__ import annotations

import numpy as np

from ..core.stencils import Family, Stencils
from .fabrication import ccw_polygons

FAMILY = "min_opening"


def _area_terms(x: np.ndarray, polys: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Signed areas of ``polys`` (node indices, CCW) in ``x`` and their gradients ``(P, k, 2)``."""
    p = x[polys]
    nxt, prv = np.roll(p, -1, axis=1), np.roll(p, 1, axis=1)
    area = 0.5 * (p[:, :, 0] * nxt[:, :, 1] - nxt[:, :, 0] * p[:, :, 1]).sum(1)
    grad = 0.5 * np.stack([nxt[:, :, 1] - prv[:, :, 1], prv[:, :, 0] - nxt[:, :, 0]], -1)
    return area, grad


def opening_row(x: np.ndarray, tiles: np.ndarray, holes: np.ndarray, floor: float):
    """The row's value ``(1,)``, its nodes ``(1, k)`` and gradients ``(1, k, 2)`` (see the module docstring)."""
    at, gt = _area_terms(x, tiles)
    ah, gh = _area_terms(x, holes)
    n = len(tiles)
    value = ((1.0 - floor) * ah.sum() - floor * at.sum()) / n
    nodes = np.concatenate([tiles.ravel(), holes.ravel()])[None, :]
    grads = np.concatenate([-floor * gt.reshape(-1, 2), (1.0 - floor) * gh.reshape(-1, 2)]) / n
    return np.array([value]), nodes, grads[None, :, :]


def opening_families(st: Stencils, nv: int, floor: float | None, base: np.ndarray) -> list[Family]:
    """The ``--min-opening`` row over the deployed nodes (none without a floor or holes); ``base`` (the
    standard pattern's nodes) orients the holes."""
    if not floor or not len(st.hole_nodes):
        return []
    tiles = st.tiles
    holes = ccw_polygons(st.hole_nodes, base)

    def fn(x):
        r, nodes, g = opening_row(x, tiles, holes, floor)
        return r, (nodes, g)

    return [
        Family(
            FAMILY,
            "ineq",
            fn,
            2,
            meta={"floor": float(floor)},
            nv=nv,
            res=lambda x: opening_row(x, tiles, holes, floor)[0],
        )
    ]
