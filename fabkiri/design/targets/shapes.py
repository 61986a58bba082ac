"""Built-in target shapes (circle, ellipse, rectangle, superellipse, polygon, star, heart) by name."""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from ...errors import InputError
from .curve import Target


def _param_samples(n: int) -> np.ndarray:
    return np.linspace(0.0, 2 * np.pi, n, endpoint=False)


def circle(n: int = 1024) -> Target:
    t = _param_samples(n)
    return Target("circle", "spline", np.stack([np.cos(t), np.sin(t)], -1))


def ellipse(aspect: float = 2.0, n: int = 1024) -> Target:
    _positive(aspect, "ellipse aspect")
    t = _param_samples(n)
    return Target(f"ellipse {aspect:g}:1", "spline", np.stack([aspect * np.cos(t), np.sin(t)], -1))


def rectangle(aspect: float = 1.0) -> Target:
    _positive(aspect, "rectangle aspect")
    a = aspect
    pts = np.array([[-a, -1], [a, -1], [a, 1], [-a, 1]], float)
    name = "square" if aspect == 1 else f"rectangle {aspect:g}:1"
    return Target(name, "polyline", pts, corners=np.array([0.0, a, a + 1, 2 * a + 1]) / (2 * a + 2))


def superellipse(p: float = 4.0, aspect: float = 1.0, n: int = 2048) -> Target:
    _positive(p, "superellipse exponent")
    t = _param_samples(n)
    c, s = np.cos(t), np.sin(t)
    x = np.sign(c) * np.abs(c) ** (2.0 / p)
    y = np.sign(s) * np.abs(s) ** (2.0 / p)
    return Target(f"superellipse p={p:g}", "spline", np.stack([aspect * x, y], -1))


def polygon(sides: int = 6, rotation_deg: float | None = None) -> Target:
    if int(sides) != sides or sides < 3:
        raise InputError(f"a regular polygon needs at least 3 sides, got {sides}")
    rot = np.radians(rotation_deg) if rotation_deg is not None else -np.pi / 2 + np.pi / sides
    t = rot + 2 * np.pi * np.arange(sides) / sides
    return Target(f"{sides}-gon", "polyline", np.stack([np.cos(t), np.sin(t)], -1))


def star(points: int = 5, inner: float = 0.5) -> Target:
    if int(points) != points or points < 3:
        raise InputError(f"a star needs at least 3 points, got {points}")
    if not 0 < inner < 1:
        raise InputError(f"star inner radius ratio must lie in (0, 1), got {inner}")
    t = np.pi / 2 + np.pi * np.arange(2 * points) / points
    r = np.where(np.arange(2 * points) % 2 == 0, 1.0, inner)
    return Target(f"{points}-point star", "polyline", np.stack([r * np.cos(t), r * np.sin(t)], -1))


def heart(n: int = 2048) -> Target:
    """The classic heart curve with its top cusp rounded off so it is a smooth spline."""
    t = _param_samples(n) + np.pi  # start at the bottom tip
    x = 16 * np.sin(t) ** 3
    y = 13 * np.cos(t) - 5 * np.cos(2 * t) - 2 * np.cos(3 * t) - np.cos(4 * t)
    pts = np.stack([x, y], -1) / 17.0
    # the top notch is a cusp: a polyline keeps it exact where a spline would loop
    return Target("heart", "polyline", pts)


SHAPES: dict[str, Callable[..., Target]] = {
    "circle": circle,
    "ellipse": ellipse,
    "square": lambda **kw: rectangle(1.0),
    "rectangle": rectangle,
    "superellipse": superellipse,
    "polygon": polygon,
    "star": star,
    "heart": heart,
}


def _positive(v, what):
    if not (isinstance(v, (int, float)) and math.isfinite(v) and v > 0):
        raise InputError(f"{what} must be a positive number, got {v!r}")
