"""Forward-mode differentiation of the fabrication rows: a value per row and its gradient in the coordinates of
the row's polygon corners (:class:`Dual`), or the value alone (:func:`values_only`)."""

from __future__ import annotations

import numpy as np


class Dual:
    """A value per row with its gradient in the coordinates of the row's corners (forward-mode
    differentiation; the kagome rows use it too). ``g`` is None on a row evaluated for its value only
    (:func:`values_only`): the same arithmetic without the gradient arrays, which cost most of the time."""

    __slots__ = ("v", "g")

    def __init__(self, v, g):
        self.v, self.g = v, g

    @staticmethod
    def lift(o, like: Dual) -> Dual:
        if isinstance(o, Dual):
            return o
        v = np.broadcast_to(o, like.v.shape)
        return Dual(v, None if like.g is None else np.zeros_like(like.g))

    def __add__(self, o):
        if not isinstance(o, Dual):
            return Dual(self.v + o, self.g)
        return Dual(self.v + o.v, None if self.g is None else self.g + o.g)

    __radd__ = __add__

    def __neg__(self):
        return Dual(-self.v, None if self.g is None else -self.g)

    def __sub__(self, o):
        if not isinstance(o, Dual):
            return Dual(self.v - o, self.g)
        return Dual(self.v - o.v, None if self.g is None else self.g - o.g)

    def __rsub__(self, o):
        return Dual(o - self.v, None if self.g is None else -self.g)

    def __mul__(self, o):
        if not isinstance(o, Dual):
            if self.g is None:
                return Dual(self.v * o, None)
            return Dual(self.v * o, self.g * np.asarray(o)[..., None] if np.ndim(o) else self.g * o)
        if self.g is None:
            return Dual(self.v * o.v, None)
        return Dual(self.v * o.v, self.g * o.v[..., None] + o.g * self.v[..., None])

    __rmul__ = __mul__

    def __truediv__(self, o):
        if not isinstance(o, Dual):
            return self * (1.0 / o)
        if self.g is None:
            return Dual(self.v / o.v, None)
        return Dual(
            self.v / o.v,
            (self.g * o.v[..., None] - o.g * self.v[..., None]) / (o.v * o.v)[..., None],
        )

    def sqrt(self):
        r = np.sqrt(self.v)
        return Dual(r, None if self.g is None else self.g / (2.0 * r)[..., None])

    def take(self, k) -> Dual:
        """Column ``k`` of a row-by-column value (an index or a slice; the gradient's last axis stays)."""
        return Dual(self.v[:, k], None if self.g is None else self.g[:, k])


def stack(ds: list[Dual]) -> Dual:
    """Values of one shape side by side in a new column axis (the gradient's last axis stays last)."""
    g = None if ds[0].g is None else np.stack([d.g for d in ds], 1)
    return Dual(np.stack([d.v for d in ds], 1), g)


def roll(d: Dual, shift: int) -> Dual:
    """The columns of a row-by-column value rotated by ``shift`` (``np.roll`` along axis 1)."""
    return Dual(np.roll(d.v, shift, 1), None if d.g is None else np.roll(d.g, shift, 1))


class _Values(np.ndarray):
    """Node coordinates whose rows are wanted without their gradients (:func:`values_only`)."""


def values_only(x: np.ndarray) -> np.ndarray:
    """``x`` marked so that :func:`dual_corner` seeds no gradients: a row function evaluated on it returns
    :class:`Dual` values with ``g`` None (a residual-only call: the solvers check inequalities at every trial
    step and need their gradients only where one is active)."""
    return np.asarray(x).view(_Values)


def is_values_only(x: np.ndarray) -> bool:
    """Whether ``x`` was marked by :func:`values_only` (a row function may then take a plain-array path)."""
    return isinstance(x, _Values)


def dual_corner(x: np.ndarray, quads: np.ndarray, rows: np.ndarray, k: np.ndarray):
    """Corner ``k`` (per row) of quad ``rows`` as a 2-vector of :class:`Dual` seeded on its 2n coordinates
    (n = ``quads.shape[1]``: any polygon arity, the kagome's triangles and hexagonal holes too); values only
    on :func:`values_only` coordinates."""
    m = len(rows)
    p = np.asarray(x)[quads[rows, k]]
    if isinstance(x, _Values):
        return Dual(p[:, 0], None), Dual(p[:, 1], None)
    gx = np.zeros((m, 2 * quads.shape[1]))
    gy = np.zeros((m, 2 * quads.shape[1]))
    gx[np.arange(m), 2 * k] = 1.0
    gy[np.arange(m), 2 * k + 1] = 1.0
    return Dual(p[:, 0], gx), Dual(p[:, 1], gy)


def vec_sub(a, b):
    """``a - b`` for 2-vectors of :class:`Dual` (or of arrays)."""
    return a[0] - b[0], a[1] - b[1]


def vec_dot(a, b):
    """The dot product of two 2-vectors of :class:`Dual` (or of arrays)."""
    return a[0] * b[0] + a[1] * b[1]


def inward_normal(a, b):
    """Inward unit normal of the CCW edge a -> b."""
    e = vec_sub(b, a)
    ln = vec_dot(e, e).sqrt()
    return -e[1] / ln, e[0] / ln
