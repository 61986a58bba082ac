"""A target's mirror axis at any angle, and the target turned about its centre.

``Target.mirror_error`` asks about the x and y axes only (``--symmetry``). An outline a user drew turned (a heart
whose axis leans 20 degrees) has its mirror axis off both, and a quad lattice laid on the drawing's axes fits it
worse than one laid along its axis (docs/design-solver.md, "Session 53 (rot53)"). :func:`mirror_axis_deg` finds
that axis: a mirror axis passes through the area centroid, so the search is over its angle alone, a coarse scan
then a finer one about the best angle (the same KD-tree distance as ``mirror_error``).
"""

from __future__ import annotations

import numpy as np
from shapely.geometry import Polygon

from ...kdtree import KDTree
from .curve import Target

SCAN_STEP_DEG = 1.0  # the coarse scan's step over [0, 180)
FINE_STEP_DEG = 0.01  # the fine scan's, about the coarse scan's best angle (0.01 mm off at 50 mm)
SAMPLES = 512  # curve points reflected per angle (the KD-tree holds the dense curve)


def centroid(target: Target) -> np.ndarray:
    """The area centroid of the curve (a mirror axis passes through it)."""
    c = Polygon(target.dense).centroid
    return np.array([c.x, c.y])


def axis_distances(target: Target, degrees) -> tuple[np.ndarray, np.ndarray]:
    """``(rms, error)`` at each angle: the distances from ``SAMPLES`` curve points, reflected about the line through
    the centroid at that angle, to the dense curve; ``rms`` their root mean square, ``error`` as
    ``Target.mirror_error`` (the largest less the dense spacing), both over the size."""
    c0 = centroid(target)
    dense = target.dense - c0
    tree = KDTree(dense)
    spacing = np.linalg.norm(np.diff(dense, axis=0), axis=1).max()
    pts = target.sample(SAMPLES) - c0
    rms, err = [], []
    for deg in np.atleast_1d(np.asarray(degrees, float)):
        c, s = np.cos(np.radians(2 * deg)), np.sin(np.radians(2 * deg))
        # the reflection about the line at ``deg``
        dist, _ = tree.query(pts @ np.array([[c, s], [s, -c]]))
        rms.append(float(np.sqrt(np.mean(dist**2))))
        err.append(max(0.0, float(dist.max()) - spacing))
    return np.array(rms) / target.size, np.array(err) / target.size


def mirror_axis_deg(target: Target) -> tuple[float, float]:
    """``(angle, error)``: the angle in [0, 180) degrees of the line through the centroid closest to a mirror
    axis of ``target`` (the least root mean square distance: the largest one is flat within the sample spacing),
    to ``FINE_STEP_DEG``, and its mirror error."""
    scan = np.arange(0.0, 180.0, SCAN_STEP_DEG)
    best = float(scan[int(np.argmin(axis_distances(target, scan)[0]))])
    fine = best + np.arange(-SCAN_STEP_DEG, SCAN_STEP_DEG + FINE_STEP_DEG / 2, FINE_STEP_DEG)
    rms, error = axis_distances(target, fine)
    i = int(np.argmin(rms))
    return float(fine[i] % 180.0), float(error[i])


def rotation(degrees: float) -> np.ndarray:
    """The matrix that turns points (rows, ``points @ rotation(a)``) by ``degrees`` counter-clockwise."""
    c, s = np.cos(np.radians(degrees)), np.sin(np.radians(degrees))
    return np.array([[c, s], [-s, c]])


def turned(target: Target, degrees: float) -> tuple[Target, np.ndarray]:
    """``(turned, shift)``: ``target`` turned by ``degrees`` counter-clockwise and shifted so that its bounding box
    is centred on the origin (as ``load_target`` centres every target), ``turned = points @ rotation(degrees) +
    shift``; its corner split is the turned curve's own."""
    pts = target.points @ rotation(degrees)
    shift = -0.5 * (pts.min(0) + pts.max(0))  # the polyline's box; the curve's own below
    tgt = Target(target.name, target.kind, pts + shift, source=dict(target.source))
    lo, hi = tgt.bbox
    return tgt.transformed(shift=-0.5 * (lo + hi)), shift - 0.5 * (lo + hi)
