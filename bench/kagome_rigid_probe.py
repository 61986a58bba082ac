"""Probe for a path of rigid tiles between a kagome pattern's deployed state and a closed state.

The tiles are rigid bodies (pose: angle, centroid) and every hinge is an exact constraint (its two
corners meet). Two probes, each a sequence of constrained least-squares projections (KKT steps with
a sparse analytic Jacobian):

- ``blend``: the pose closest to the homotopy driver's rigid blend at λ, continued in λ from 0
  (deployed) to 1 (the closed state), the λ step halved while a projection fails or jumps;
- ``descent``: steps toward the closed state's poses, accepted only while the distance falls.

A probe that reaches the closed state found a rigid path (``print --style pinned`` sweeps a path of
rigid tiles); one that stalls found none near its route, which does not show there is none.
Run: ``python3 bench/kagome_rigid_probe.py PATTERN.json`` (the docs' figures: docs/kagome.md,
"Pinned kagome prints"). Prints, per closed state and probe, how far it got and the CPU time.
"""

from __future__ import annotations

import argparse
import time

import numpy as np
from fabkiri.exchange.pattern_json import read_pattern
from fabkiri.mechanics.path import closed_states
from fabkiri.pattern import geometry
from scipy import sparse
from scipy.sparse.linalg import splu


class Linkage:
    """The pattern's tiles as rigid bodies pinned at their hinges."""

    def __init__(self, pattern):
        D = pattern.corners()
        self.T = len(D)
        self.local = D - D.mean(axis=1, keepdims=True)
        top = pattern.topology
        self.A, self.B = top.hinge_tiles.T
        self.cA, self.cB = top.hinge_corner.T
        self.H = len(self.A)
        r2 = float((self.local**2).sum(-1).mean())  # angles weighted by the mean squared radius
        self.w = np.concatenate([np.full(self.T, r2), np.ones(2 * self.T)])

    def poses(self, corners: np.ndarray) -> np.ndarray:
        th = geometry.kabsch_angles(self.local, corners - corners.mean(1, keepdims=True))
        return np.concatenate([th, corners.mean(1).ravel()])

    def corners(self, q: np.ndarray) -> np.ndarray:
        T = self.T
        return geometry.rotate(self.local, q[:T, None]) + q[T:].reshape(T, 1, 2)

    def residual(self, q: np.ndarray) -> np.ndarray:
        C = self.corners(q)
        return (C[self.A, self.cA] - C[self.B, self.cB]).ravel()

    def jacobian(self, q: np.ndarray) -> sparse.csr_matrix:
        T, H = self.T, self.H
        rows, cols, vals = [], [], []
        for tiles, ks, sgn in ((self.A, self.cA, 1.0), (self.B, self.cB, -1.0)):
            lx, ly = self.local[tiles, ks].T
            c, s = np.cos(q[tiles]), np.sin(q[tiles])
            r = np.arange(H)
            rows += [2 * r, 2 * r + 1, 2 * r, 2 * r + 1]
            cols += [tiles, tiles, T + 2 * tiles, T + 2 * tiles + 1]
            one = np.full(H, sgn)
            vals += [sgn * (-s * lx - c * ly), sgn * (c * lx - s * ly), one, one]
        return sparse.csr_matrix(
            (np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))), (2 * H, 3 * T)
        )

    def project(self, q: np.ndarray, target: np.ndarray, iters: int = 15):
        """The pose nearest ``target`` (weighted) on the constraint set, from ``q``; None if
        ``iters`` Newton-KKT steps do not meet the hinges to 1e-10 mm (near a singular configuration
        of the linkage they converge only linearly; where a probe stalls depends on this test)."""
        n = 3 * self.T
        for _ in range(iters):
            J = self.jacobian(q)
            K = sparse.bmat(
                [[sparse.diags(self.w), J.T], [J, -1e-14 * sparse.identity(2 * self.H)]]
            ).tocsc()
            step = splu(K).solve(np.concatenate([self.w * (target - q), -self.residual(q)]))[:n]
            q = q + step
            if np.abs(self.residual(q)).max() <= 1e-10 and np.abs(step).max() < 1e-6:
                return q
        return None


def blend_probe(L: Linkage, q0: np.ndarray, goal: np.ndarray, steps: int = 100) -> str:
    lam, h, q = 0.0, 1.0 / steps, q0.copy()
    while lam < 1 - 1e-12 and h > 1e-4:
        l1 = min(1.0, lam + h)
        qn = L.project(q, q0 + l1 * (goal - q0))
        if qn is None or np.linalg.norm(L.corners(qn) - L.corners(q), axis=-1).max() > 0.5:
            h *= 0.5
            continue
        q, lam, h = qn, l1, min(2 * h, 1.0 / steps)
    end = np.linalg.norm(L.corners(q) - L.corners(goal), axis=-1).max()
    return f"blend: reached λ = {lam:.4f}, largest corner distance to the state {end:.3g} mm"


def descent_probe(L: Linkage, q0: np.ndarray, goal: np.ndarray) -> str:
    dist = lambda q: float(np.sqrt(L.w @ (q - goal) ** 2))  # noqa: E731
    q, alpha, n = q0.copy(), 0.02, 0
    while alpha > 1e-5 and n < 3000 and dist(q) > 1e-9:
        n += 1
        qn = L.project(q, q + alpha * (goal - q))
        if qn is None or dist(qn) >= dist(q) - 1e-12:
            alpha *= 0.5
            continue
        q, alpha = qn, min(1.5 * alpha, 0.2)
    return f"descent: weighted distance {dist(q):.3g} of {dist(q0):.3g} at the start ({n} steps)"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("pattern")
    args = ap.parse_args()
    p = read_pattern(args.pattern)
    L = Linkage(p)
    q0 = L.poses(p.corners())
    for s, c in closed_states(p).items():
        qs = L.poses(c)
        goal = np.concatenate(
            [q0[: L.T] + np.angle(np.exp(1j * (qs[: L.T] - q0[: L.T]))), qs[L.T :]]
        )
        for probe in (blend_probe, descent_probe):
            t0 = time.process_time()
            said = probe(L, q0, goal)
            print(f"state {s}: {said}; {time.process_time() - t0:.1f} CPU s")


if __name__ == "__main__":
    main()
