"""A contact term for the elastic path: hinged tiles repel before their gap closes past zero.

Two tiles hinged at a corner leave two *gaps* there (a hole corner or a boundary notch on each
side, :func:`.mechanism.gap_angles`). With rigid tiles a gap is linear in the two tiles' rotation
angles, so the homotopy driver, which interpolates every tile's angle linearly, would move every
gap linearly from its deployed value to its closed-state value, never below zero. The path's
tiles are springs, though, and where the closed state folds a gap flat (value 0) the relaxed
tiles distort by a few degrees and the gap overshoots: it goes negative before it comes back to
zero, and the two tiles pass through each other near their hinge (the designed kagome ellipse
5x19: 0.15° at t = 0.05; the heart 6x11: 5.9° at t = 0.2, 1.17 mm deep).

This term penalises a gap ``g`` (the signed angle at the hinge, ``(-π, π]``) that falls below a
clearance ``c``, a fraction ``κ`` of the rigid blend's gap at the same path parameter:

    E_C(x) = w · Σ_gaps φ(g/c),    φ(u) = (1 - u)³ for u < 1, else 0,

so it is zero at the three states (each gap there is its own rigid value, at least ``c``) and
wherever a gap keeps at least ``κ`` of its rigid value; it only acts on gaps that are closing too
early. Relative to ``c``, it grows stiffer as a folding gap's clearance shrinks towards its
closed state, which is what keeps the last sub-steps from overshooting; cubic, so it is C² where
it switches on (a quadratic's jump in curvature there left Newton steps unconverged). Its gradient
and Hessian are exact and sparse (three nodes per gap), checked against finite differences in the
tests. The gap angle is ``θ(v - h) - θ(u - h)`` with ``h`` the hinge node and ``u``, ``v`` the far
corners of the two edges the gap lies between.

Gaps folded flat in a closed state are left out there (:data:`FOLDED`): the homotopy's drivers pin
every closed state exactly, and a clearance of zero would have no scale.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import sparse

from ..pattern import geometry
from ..pattern.model import Pattern
from .drivers.rotations import gap_angles
from .path import tile_angles

OPEN = 0.5 * np.pi  # wider rigid gaps are far from closing (and from the ±π cut of atan2)
CORNER_OPEN = 0.75 * np.pi  # wider corners of a tile are not watched (see corner_term)
FOLDED = 1e-6  # rad: a rigid gap this narrow is folded (a closed state; the drivers pin it)
P_NODES = np.array([-1.0, 1.0, 0.0])  # p = u - h over (h, u, v)
Q_NODES = np.array([-1.0, 0.0, 1.0])  # q = v - h


@dataclass(frozen=True, eq=False)
class Gaps:
    """Every hinge's two gaps as node triples, with their rigid values in the three states.

    Gap ``k`` of hinge ``i`` is row ``2i + k``; its angle turns ``u - h`` onto ``v - h``."""

    h: np.ndarray  # (G,) hinge node
    u: np.ndarray  # (G,) far corner of the edge the gap turns from
    v: np.ndarray  # (G,) far corner of the edge it turns onto
    deployed: np.ndarray  # (G,) gap angles in [0, 2π)
    turn: dict[int, np.ndarray]  # state -> (G,) change of each gap with the homotopy's angles
    n_nodes: int
    hinge_tiles: np.ndarray  # (H, 2) tiles A, B of every hinge

    def turned(self, theta: np.ndarray) -> np.ndarray:
        """``(G,)`` every gap of rigid tiles turned by ``theta`` ``(T,)`` from the deployed state
        (gap 0 opens as B turns and closes as A turns; gap 1 the other way)."""
        return self.deployed + _turn(self.hinge_tiles, np.asarray(theta, dtype=float))

    def angles(self, x: np.ndarray) -> np.ndarray:
        """``(G,)`` the gap angles of flat node coordinates ``x``, in (-π, π]."""
        X = np.asarray(x, dtype=float).reshape(self.n_nodes, 2)
        return geometry.signed_angle(X[self.u] - X[self.h], X[self.v] - X[self.h])

    def rigid(self, t: float) -> np.ndarray:
        """``(G,)`` every gap of rigid tiles turned by the homotopy's angles at ``t`` (linear in
        λ from the deployed state to the closed state of the half ``t`` lies on)."""
        s = 1 if t < 0.5 else 2
        lam = min(1.0, abs(2.0 * t - 1.0))
        return self.deployed + lam * self.turn[s]


def _turn(hinge_tiles: np.ndarray, th: np.ndarray) -> np.ndarray:
    """``(G,)`` the change of every gap as the tiles turn by ``th`` ``(T,)``: gap 0 opens as B turns
    and closes as A turns; gap 1 the other way."""
    A, B = hinge_tiles.T
    return np.stack([th[B] - th[A], th[A] - th[B]], -1).ravel()


def hinge_gaps(pattern: Pattern, states: dict[int, np.ndarray]) -> Gaps:
    """The gaps of ``pattern`` (its hinges in topology order) and their values in the states."""
    top = pattern.topology
    tiles = pattern.tiles
    n = tiles.shape[1]
    A, B = top.hinge_tiles.T
    cA, cB = top.hinge_corner.T
    h = tiles[A, cA]
    deployed = pattern.corners()
    turn = {s: _turn(top.hinge_tiles, tile_angles(deployed, states[s])) for s in (1, 2)}
    # the topology's convention (gap_angles): gap 0 from A's edge to prev_A onto B's edge to
    # next_B, gap 1 from B's edge to prev_B onto A's edge to next_A
    u = np.stack([tiles[A, (cA + n - 1) % n], tiles[B, (cB + n - 1) % n]], -1).ravel()
    v = np.stack([tiles[B, (cB + 1) % n], tiles[A, (cA + 1) % n]], -1).ravel()
    return Gaps(
        h=np.repeat(h, 2),
        u=u,
        v=v,
        deployed=gap_angles(pattern, deployed).ravel(),
        turn=turn,
        n_nodes=len(pattern.nodes),
        hinge_tiles=top.hinge_tiles,
    )


@dataclass(frozen=True, eq=False)
class GapTerm:
    """``w Σ φ(g/c)`` over the gaps ``rows`` of :class:`Gaps`, clearances ``c`` (radians)."""

    gaps: Gaps
    rows: np.ndarray  # (m,) gap rows the term watches
    clearance: np.ndarray  # (m,) c > 0
    weight: float
    kappa: float  # the clearance as a fraction of the rigid gap

    def _short(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Per watched gap its shortfall ``max(c - g, 0)``, and the edge vectors ``p = u - h``,
        ``q = v - h`` it was measured from."""
        X = np.asarray(x, dtype=float).reshape(self.gaps.n_nodes, 2)
        g = self.gaps
        p = X[g.u[self.rows]] - X[g.h[self.rows]]
        q = X[g.v[self.rows]] - X[g.h[self.rows]]
        return np.maximum(self.clearance - geometry.signed_angle(p, q), 0.0), p, q

    def _active(self, x: np.ndarray, hessian: bool):
        """The gaps below their clearance (the rest contribute nothing): their dof ``(a, 6)``,
        ``dE/dg`` and ``d²E/dg²`` (φ = (short/c)³), ``∇g`` ``(a, 6)`` over (h, u, v) and, if asked,
        ``∇²g`` ``(a, 6, 6)``."""
        short, p, q = self._short(x)
        on = np.flatnonzero(short > 0)
        short, p, q, c = short[on], p[on], q[on], self.clearance[on]
        d1 = -3.0 * self.weight * short**2 / c**3
        d2 = 6.0 * self.weight * short / c**3
        dp = np.stack([p[:, 1], -p[:, 0]], -1) / (p * p).sum(-1)[:, None]  # ∂g/∂u = -∂θ(p)/∂p
        dq = np.stack([-q[:, 1], q[:, 0]], -1) / (q * q).sum(-1)[:, None]  # ∂g/∂v = ∂θ(q)/∂q
        grad = np.concatenate([-(dp + dq), dp, dq], axis=1)  # (h, u, v)
        hess = None
        if hessian:
            hess = _sandwich(_theta_hessian(q), Q_NODES) - _sandwich(_theta_hessian(p), P_NODES)
        return self._dof()[on], d1, d2, grad, hess

    def energy(self, x: np.ndarray) -> float:
        short = self._short(x)[0]
        return float(self.weight * ((short / self.clearance) ** 3).sum())

    def gradient(self, x: np.ndarray) -> np.ndarray:
        dof, d1, _, grad, _ = self._active(x, hessian=False)
        out = np.zeros(2 * self.gaps.n_nodes)
        np.add.at(out, dof, d1[:, None] * grad)
        return out

    def hessian(self, x: np.ndarray) -> sparse.csr_matrix:
        """``φ'' ∇g ∇gᵀ + φ' ∇²g`` per gap, scattered onto its three nodes."""
        dof, d1, d2, grad, hess = self._active(x, hessian=True)
        block = d2[:, None, None] * grad[:, :, None] * grad[:, None, :] + d1[:, None, None] * hess
        rows = np.repeat(dof, 6, axis=1).ravel()
        cols = np.tile(dof, (1, 6)).ravel()
        n2 = 2 * self.gaps.n_nodes
        return sparse.csr_matrix((block.ravel(), (rows, cols)), shape=(n2, n2))

    def _dof(self) -> np.ndarray:
        g = self.gaps
        nodes = np.stack([g.h[self.rows], g.u[self.rows], g.v[self.rows]], -1)  # (m, 3)
        return np.stack([2 * nodes, 2 * nodes + 1], -1).reshape(len(self.rows), 6)


def _theta_hessian(p: np.ndarray) -> np.ndarray:
    """``(m, 2, 2)`` Hessian of the direction angle ``atan2(p_y, p_x)`` in ``p``."""
    x, y = p[:, 0], p[:, 1]
    r4 = (x * x + y * y) ** 2
    off = (y * y - x * x) / r4
    return np.stack([np.stack([2 * x * y / r4, off], -1), np.stack([off, -2 * x * y / r4], -1)], -2)


def _sandwich(M: np.ndarray, coef: np.ndarray) -> np.ndarray:
    """``(m, 6, 6)`` ``Dᵀ M D`` for a vector ``D = Σ_k coef_k · node_k`` over the nodes (h, u, v)."""
    cc = np.outer(coef, coef)[None, :, None, :, None]  # (1, 3, 1, 3, 1)
    return (cc * M[:, None, :, None, :]).reshape(len(M), 6, 6)


def gap_term(gaps: Gaps, t: float, *, weight: float, kappa: float) -> GapTerm:
    """The contact term at path parameter ``t``: every gap whose rigid blend there is open but
    narrower than :data:`OPEN` is held above ``kappa`` times that blend."""
    return blend_term(gaps, gaps.rigid(t), weight=weight, kappa=kappa)


def blend_term(gaps: Gaps, blend: np.ndarray, *, weight: float, kappa: float) -> GapTerm:
    """The contact term for the rigid gaps ``blend`` ``(G,)`` (a driver's tiles turned rigidly,
    :meth:`Gaps.turned`): every gap open but narrower than :data:`OPEN` held above ``kappa`` of
    its value there."""
    rows = np.flatnonzero((blend > FOLDED) & (blend < OPEN))
    return GapTerm(gaps, rows, kappa * blend[rows], float(weight), float(kappa))


def corner_gaps(pattern: Pattern) -> Gaps:
    """Every tile's corners as node triples (corner ``h``, the next corner ``u``, the previous
    ``v``): the angle turning ``u - h`` onto ``v - h`` is the interior angle of a CCW tile, the
    same in every state (a rigid motion keeps it), negative or above π once the tile is no longer
    convex (a dart or a bow-tie)."""
    tiles = pattern.tiles
    deployed = pattern.corners()
    h = tiles.ravel()
    u = np.roll(tiles, -1, axis=1).ravel()
    v = np.roll(tiles, 1, axis=1).ravel()
    angle = geometry.signed_angle(
        np.roll(deployed, -1, axis=1) - deployed, np.roll(deployed, 1, axis=1) - deployed
    ).ravel()
    none = np.zeros_like(angle)
    return Gaps(h, u, v, angle, {1: none, 2: none}, len(pattern.nodes), np.zeros((0, 2), int))


def corner_term(pattern: Pattern, *, weight: float, kappa: float) -> GapTerm:
    """The tiles kept convex: every interior angle held above ``kappa`` of its design, with the
    contact term's penalty. Two convex tiles hinged at a corner overlap only if a gap there is
    negative (each lies in the wedge of its two edges at the hinge), so with this term the gap
    term alone keeps hinged tiles apart; a spring tile, whose six springs strain freely, could
    otherwise fold into a bow-tie across its neighbour (thin tiles next to a boundary do). A tile
    designed non-convex is not watched."""
    corners = corner_gaps(pattern)
    k = pattern.tiles.shape[1]
    convex = (corners.deployed.reshape(-1, k) > FOLDED).all(axis=1)  # a designed dart is left be
    # an obtuse corner is far from folding, and near the ±π cut of atan2 its angle would wrap
    rows = np.flatnonzero(np.repeat(convex, k) & (corners.deployed < CORNER_OPEN))
    return GapTerm(corners, rows, kappa * corners.deployed[rows], float(weight), float(kappa))


def contact_figures(terms: list[GapTerm], sols: list[np.ndarray]) -> dict:
    """The contact term's weight and clearance, its largest value along the path, and the
    narrowest watched gap against its rigid value (below 1: the tiles distort it; 0 or less: they
    touch or pass through each other at the hinge)."""
    ratio, energy = np.inf, 0.0
    for term, x in zip(terms, sols):
        if len(term.rows):
            g = term.gaps.angles(x)[term.rows]
            ratio = min(ratio, float((g * term.kappa / term.clearance).min()))
            energy = max(energy, term.energy(x))
    return {
        "contact_weight": terms[0].weight,
        "contact_clearance_of_rigid_gap": terms[0].kappa,
        "contact_energy_max": energy,
        "narrowest_gap_to_rigid": None if ratio == np.inf else ratio,
    }
