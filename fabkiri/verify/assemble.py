"""The best rigid assembly of cut tiles into a closed state: one rotation and shift per tile.

A breadth-first placement (each child laid along its parent's folded edge) closes
every loop exactly when the shapes are exact, but with real cut shapes its error
grows along the tree: a 1 µm corner offset on a 1 mm folded edge turns the child
by 1 mrad, which is 0.1 mm a hundred millimetres on. The tiles of a sheet are not
assembled along a tree; every hinge pins two of them. So the closure is measured
on the assembly that fits every hinge at once: least squares over all tile motions
of the hinge splits and of the folded-gap offsets (each fold end's distance from
the other tile's folded edge line), started from the tree placement. Its largest
residual is what the tiles, as cut, fail to close by.
"""

from __future__ import annotations

import numpy as np
from scipy import sparse

from ..pattern import geometry
from ..pattern.model import Pattern

MAX_ITER = 20


def _perp(v: np.ndarray) -> np.ndarray:
    """``v`` turned by +90° (the derivative of a rotation, applied)."""
    return np.stack([-v[..., 1], v[..., 0]], -1)


class Assembly:
    """Residuals and their sparse Jacobian for tile motions ``x = (phi, tx, ty)`` per tile.

    ``C`` (T, 4, 2): the cut shapes in any frame; tile t sits at ``rotate(C[t] - c_t, phi_t) + (tx, ty)_t``.
    Residuals per hinge: the split of its two corner copies (2), and the distance of each tile's
    fold end from the other tile's folded edge line (2). All in mm.
    """

    def __init__(self, pattern: Pattern, C: np.ndarray, state: int):
        top = pattern.topology
        fold = top.fold(state)
        self.T = len(C)
        self.centre = C.mean(axis=1)
        self.local = C - self.centre[:, None, :]
        self.A, self.B = top.hinge_tiles.T
        self.cA, self.cB = top.hinge_corner.T
        self.eA, self.eB = fold.fold_corner_ends.T
        H = len(self.A)
        wa = self.local[self.A, self.eA] - self.local[self.A, self.cA]
        wb = self.local[self.B, self.eB] - self.local[self.B, self.cB]
        self.ua = (
            wa / np.maximum(np.linalg.norm(wa, axis=1), 1e-300)[:, None]
        )  # unit folded edges, local
        self.ub = wb / np.maximum(np.linalg.norm(wb, axis=1), 1e-300)[:, None]
        self.H = H

    def corners(self, x: np.ndarray) -> np.ndarray:
        phi, t = x[: self.T], x[self.T :].reshape(2, self.T).T
        return geometry.rotate(self.local, phi[:, None]) + t[:, None, :]

    def residuals(self, x: np.ndarray) -> np.ndarray:
        Y = self.corners(x)
        hA, hB = Y[self.A, self.cA], Y[self.B, self.cB]
        phi = x[: self.T]
        ua, ub = geometry.rotate(self.ua, phi[self.A]), geometry.rotate(self.ub, phi[self.B])
        da = geometry.cross2(ua, Y[self.B, self.eB] - hA)  # B's fold end off A's folded edge line
        db = geometry.cross2(ub, Y[self.A, self.eA] - hB)
        return np.concatenate([(hA - hB)[:, 0], (hA - hB)[:, 1], da, db])

    def jacobian(self, x: np.ndarray) -> sparse.csr_matrix:
        T, H = self.T, self.H
        phi = x[:T]
        Y = self.corners(x)
        A, B = self.A, self.B
        # d(corner)/d(phi) = perp(rotated local corner); d/d(tx, ty) = identity
        gA = _perp(geometry.rotate(self.local[A, self.cA], phi[A]))
        gB = _perp(geometry.rotate(self.local[B, self.cB], phi[B]))
        geA = _perp(geometry.rotate(self.local[A, self.eA], phi[A]))
        geB = _perp(geometry.rotate(self.local[B, self.eB], phi[B]))
        ua, ub = geometry.rotate(self.ua, phi[A]), geometry.rotate(self.ub, phi[B])
        va = Y[B, self.eB] - Y[A, self.cA]
        vb = Y[A, self.eA] - Y[B, self.cB]
        h = np.arange(H)
        rows, cols, vals = [], [], []

        def put(r, c, v):
            rows.append(r)
            cols.append(c)
            vals.append(v)

        tx, ty = T + np.arange(T), 2 * T + np.arange(T)
        for k in range(2):  # split components: hA - hB
            r = k * H + h
            put(r, A, gA[:, k])
            put(r, B, -gB[:, k])
            put(r, (tx, ty)[k][A], np.ones(H))
            put(r, (tx, ty)[k][B], -np.ones(H))
        # da = cross(ua, va): d/dphi_A = cross(perp ua, va) + cross(ua, -gA); d/dphi_B = cross(ua, geB)
        r = 2 * H + h
        put(r, A, geometry.cross2(_perp(ua), va) - geometry.cross2(ua, gA))
        put(r, B, geometry.cross2(ua, geB))
        put(r, tx[A], ua[:, 1])  # cross(ua, -e_x) = ua_y
        put(r, ty[A], -ua[:, 0])
        put(r, tx[B], -ua[:, 1])
        put(r, ty[B], ua[:, 0])
        r = 3 * H + h
        put(r, B, geometry.cross2(_perp(ub), vb) - geometry.cross2(ub, gB))
        put(r, A, geometry.cross2(ub, geA))
        put(r, tx[B], ub[:, 1])
        put(r, ty[B], -ub[:, 0])
        put(r, tx[A], -ub[:, 1])
        put(r, ty[A], ub[:, 0])
        J = sparse.coo_matrix(
            (np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
            shape=(4 * H, 3 * T),
        )
        return J.tocsr()

    def x_of(self, Y: np.ndarray) -> np.ndarray:
        """Tile motions that put the cut shapes where ``Y`` (T, 4, 2) has them (a proper fit per tile)."""
        phi = geometry.kabsch_angles(self.local, Y)
        t = Y.mean(axis=1)
        return np.concatenate([phi, t[:, 0], t[:, 1]])


def fit_assembly(pattern: Pattern, C: np.ndarray, state: int, Y0: np.ndarray) -> np.ndarray:
    """Corners (T, 4, 2) of the least-squares assembly of shapes ``C`` in ``state``, from ``Y0``.

    Gauss-Newton on the sparse Jacobian, each step a direct solve of the normal equations (tile 0's
    motion fixed: the gauge), stopped when a step
    moves no corner by more than 1 nm or after MAX_ITER steps.
    """
    from scipy.sparse.linalg import spsolve

    asm = Assembly(pattern, C, state)
    if asm.H == 0:
        return Y0
    x = asm.x_of(Y0)
    T = asm.T
    free = np.setdiff1d(np.arange(3 * T), [0, T, 2 * T])
    scale = max(float(np.abs(asm.local).max()), 1e-300)  # rotations in mm at the tile's reach
    best, best_cost = x.copy(), float(np.sum(asm.residuals(x) ** 2))
    for _ in range(MAX_ITER):
        r = asm.residuals(x)
        J = asm.jacobian(x)[:, free]
        D = np.where(free < T, scale, 1.0)
        Js = (J @ sparse.diags(1.0 / D)).tocsc()
        N = (Js.T @ Js).tocsc()  # normal equations: sparse, banded by the hinges; a direct solve
        N = N + sparse.diags(np.full(N.shape[0], 1e-12 * max(float(N.diagonal().max()), 1e-300)))
        step = spsolve(N, -(Js.T @ r)) / D
        x = x.copy()
        x[free] += step
        cost = float(np.sum(asm.residuals(x) ** 2))
        if cost < best_cost:
            best, best_cost = x.copy(), cost
        if np.max(np.abs(step * np.where(free < T, scale, 1.0)), initial=0.0) < 1e-6:
            break
    return asm.corners(best)
