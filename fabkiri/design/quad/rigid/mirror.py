"""Mirror-symmetric members of the rigid family: the reduced solver over half the seeds.

A ``--symmetry`` design asks ``x_m(v) = M x_v`` for every node ``v`` and its mirror image ``m(v)``
(``M`` flips x for ``y``, y for ``x``). In the rigid family (``family.py``) the deployed nodes are linear
in the seed points ``S`` for each ψ, and the family's linear rows (a hole's merge vertex is the midpoint
of its fold vertices) map onto themselves under a mirror that keeps the fold states (an even number of
columns for ``y``, rows for ``x``; ``constraints.symmetry`` refuses the rest). So a member is symmetric
when its seeds are:

    p = P q,   S[m(k)] = M S[k],  an on-axis seed's flipped coordinate 0,  ψ shared,

with ``P`` a sparse ``(2 nf + 1, nq)`` matrix of ±1 (one column per seed pair and coordinate, disjoint
supports), about half as many unknowns. The translation gauge must be symmetric too: ``family.py`` fixes
it by tile 0 (τ_0 = 0), which the mirror moves, so the symmetric family fixes it by the nodes' mean
(``centred``: ``Y`` minus its column means, a translation of every member, so still a member). Then the
mean of the nodes is ``cos ψ · mean(Zn) S``, on the axis for mirrored seeds, and the member is its own
mirror image exactly.

The reduced solver runs unchanged on ``p = P q``: ``MirroredMerit`` wraps its merit, chaining every
Jacobian through ``P`` (``J P``; the normal matrix ``Pᵀ H P``, the gradient ``Pᵀ g``), each formed over q's
columns rather than p's: ``mirror_dense.py`` on the dense path (small lattices, the regulariser's
corner features of half the tiles), ``mirror_normal.py`` on the block path. The caller still
checks the full pattern's families, the symmetry rows among them.
"""

from __future__ import annotations

import copy
from dataclasses import dataclass, replace
from typing import Any

import numpy as np
from scipy import sparse

from ....errors import SolveError
from ....kdtree import KDTree
from .family import RigidFamily
from .mirror_dense import halved
from .mirror_normal import HalfBlocks, half_normal

FLIPPED = {"x": 1, "y": 0}  # the coordinate the mirror negates: "x" is y -> -y, "y" is x -> -x


def centred(fam: RigidFamily) -> RigidFamily:
    """The same family with the translation gauge at the nodes' mean (symmetric under a mirror)."""
    return replace(fam, given_Y=np.ascontiguousarray(fam.Y - fam.Y.mean(0)))


def standard_grid(rows: int, cols: int) -> np.ndarray:
    """The standard pattern's closed-state-1 grid ``(G, 2)`` (unit cells, centred): ``Z`` of its seeds is it."""
    gi, gj = np.divmod(np.arange((rows + 1) * (cols + 1)), cols + 1)
    return np.stack([gj - cols / 2, gi - rows / 2], -1).astype(float)


def seed_partners(fam: RigidFamily, rows: int, cols: int, axis: str) -> np.ndarray:
    """``(nf,)`` index of each seed's mirror image among the seeds; SolveError if the seeds do not map onto
    themselves. The grid is the standard lattice's (vertex ``i (N+1) + j``), mirrored about its centre."""
    pts = standard_grid(rows, cols)
    mirrored = pts.copy()
    mirrored[:, FLIPPED[axis]] *= -1.0
    seeds = pts[fam.seeds]
    d, k = KDTree(seeds).query(mirrored[fam.seeds])
    if (d > 1e-9).any():
        raise SolveError(f"rigid family: the seeds have no mirror image about the {axis} axis")
    return np.asarray(k, dtype=np.int64)


def mirror_map(partner: np.ndarray, axis: str) -> sparse.csr_matrix:
    """``P`` with ``p = (S[:, 0], S[:, 1], ψ) = P q`` for the symmetric seeds (module docstring)."""
    nf = len(partner)
    k = np.arange(nf)
    rep = k[k <= partner]  # one seed of each pair, and every on-axis seed
    pair, on_axis = rep[partner[rep] != rep], rep[partner[rep] == rep]
    r: list[np.ndarray] = []  # rows of P (entries of p), columns (entries of q), values
    c: list[np.ndarray] = []
    v: list[np.ndarray] = []
    nq = 0
    for d in (0, 1):
        sign = -1.0 if d == FLIPPED[axis] else 1.0
        col = nq + np.arange(len(pair))
        r += [d * nf + pair, d * nf + partner[pair]]
        c += [col, col]
        v += [np.ones(len(pair)), np.full(len(pair), sign)]
        nq += len(pair)
        if sign > 0:  # the flipped coordinate of an on-axis seed is 0: no column
            r.append(d * nf + on_axis)
            c.append(nq + np.arange(len(on_axis)))
            v.append(np.ones(len(on_axis)))
            nq += len(on_axis)
    r.append(np.array([2 * nf]))
    c.append(np.array([nq]))
    v.append(np.ones(1))
    return sparse.csr_matrix(
        (np.concatenate(v), (np.concatenate(r), np.concatenate(c))), shape=(2 * nf + 1, nq + 1)
    )


@dataclass
class Mirror:
    """What the reduced solver needs of a mirror: the map ``p = P q`` and the closed states' axis rows."""

    P: sparse.csr_matrix
    axis_rows: AxisRows | None = None

    @classmethod
    def build(cls, fam: RigidFamily, rows: int, cols: int, axis: str) -> Mirror:
        """The mirror about ``axis`` of the (``centred``) family of ``rows`` x ``cols`` tiles."""
        S = standard_grid(rows, cols)[fam.seeds]  # the standard pattern's seeds
        return cls(mirror_map(seed_partners(fam, rows, cols, axis), axis), AxisRows(fam, S, axis))


def symmetric_member(P: sparse.csr_matrix, p: np.ndarray) -> np.ndarray:
    """``q`` of the symmetric member nearest ``p`` (least squares: ``P`` has orthogonal columns)."""
    return (P.T @ p) / np.asarray(P.multiply(P).sum(0)).ravel()


# tile units: how far off the axis a closed state keeps each off-axis vertex. At 0.01 (the contact rows'
# margin) the 32x32 heart's notch met itself across the axis 0.04 mm apart in state 1, inside the verifier's
# 0.05 mm, and enclosed a 1.7 mm² gap (verify: "state 1: no interior gaps" failed); at 0.1 it stays open
AXIS_MARGIN = 0.1
AXIS_NAMES = ("closed_axis_1", "closed_axis_2")


class AxisRows:
    """Each half of a symmetric member's closed states on its own side of the axis.

    A member's closed states are mirror images of themselves (state 1, the grid ``Z S``, about the same
    axis; state 2 turned back a quarter, ``Y S``, about the other), so a tile overlaps its mirror image
    exactly when it crosses the axis: the symmetric 32x32 heart's notch closed over itself in state 1, the
    top row's tiles 11 and 20 on each other. Rows ``g = side · (flipped coordinate) ≥ AXIS_MARGIN``, linear
    in ``S``, one per vertex off the axis on the standard member (the mirrored closed-state contact: a tile
    against its mirror image). The same interface as ``contact.ClosedContact`` (``barrier``,
    ``values``, ``active``), and with it, when the contact rows join (``with_contact``).
    """

    barrier = True

    def __init__(self, fam: RigidFamily, S: np.ndarray, axis: str, contact: Any = None):
        """``S``: the seeds of a symmetric member with no tile across the axis (the standard pattern's)."""
        self.nf, self.contact = fam.n_seeds, contact
        # per state: (vertices, coordinate, side, basis of every vertex)
        self.rows: list[tuple[np.ndarray, int, np.ndarray, np.ndarray]] = []
        for B, d in ((fam.Z, FLIPPED[axis]), (fam.Y, 1 - FLIPPED[axis])):
            w = (B @ S)[:, d]
            off = np.flatnonzero(np.abs(w) > 0.25)  # the standard tiles' edge is 1: on the axis, 0
            self.rows.append((off, d, np.sign(w[off]), B))

    def joined(self, contact: Any) -> AxisRows:
        """The same rows with the closed-state contact rows (``contact.ClosedContact``) after them."""
        new = copy.copy(self)
        new.contact = contact
        return new

    def values(self, xs) -> dict:
        """Every row's value per state on ``(Z S, Y S)`` (and the contact rows' when they count as barriers)."""
        own = {n: side * x[v, d] for n, x, (v, d, side, _) in zip(AXIS_NAMES, xs, self.rows)}
        if self.contact is not None and self.contact.barrier:
            own.update(self.contact.values(xs))
        return own

    def active(self, xs, margin_scale: float, scale: float) -> tuple[np.ndarray, np.ndarray]:
        """Rows below ``margin_scale · AXIS_MARGIN``, times ``scale``: ``(r, ∂r/∂p)``; then the contact rows'."""
        rs, Js = [np.zeros(0)], [np.zeros((0, 2 * self.nf + 1))]
        for x, (v, d, side, B) in zip(xs, self.rows):
            g = side * x[v, d] - margin_scale * AXIS_MARGIN
            act = np.flatnonzero(g < 0)
            J = np.zeros((len(act), 2 * self.nf + 1))
            J[:, d * self.nf : (d + 1) * self.nf] = side[act, None] * B[v[act]]
            rs.append(scale * g[act])
            Js.append(scale * J)
        if self.contact is not None:
            r, J = self.contact.active(xs, margin_scale, scale)
            rs.append(r)
            Js.append(J)
        return np.concatenate(rs), np.vstack(Js)


class MirroredMerit:
    """A reduced merit (``reduced._Merit``) over ``q``, with ``p = P q``, and the closed states' axis rows
    (``AxisRows``); everything else is the merit's."""

    def __init__(
        self,
        merit: Any,
        P: sparse.csr_matrix,
        axis: AxisRows | None = None,
        halves: HalfBlocks | None = None,
    ):
        self.P, self.axis = P, axis
        self.halves = HalfBlocks(P, merit.nf) if halves is None else halves
        merit = halved(merit, P, self.halves)  # the dense path over q's columns
        self.inner = merit if axis is None or merit.contact is axis else merit.with_contact(axis)

    def __getattr__(self, name: str):  # fits, scaling, sq, ineq_violation ...
        return getattr(self.inner, name)

    def staged(self, rho: float, scaling: str) -> MirroredMerit:
        return MirroredMerit(self.inner.staged(rho, scaling), self.P, self.axis, self.halves)

    def state(self, q: np.ndarray):
        return self.inner.state(self.P @ q)

    def with_contact(self, contact) -> MirroredMerit:
        if self.axis is None:
            return MirroredMerit(self.inner.with_contact(contact), self.P, None, self.halves)
        axis = self.axis.joined(contact)
        return MirroredMerit(self.inner.with_contact(axis), self.P, axis, self.halves)

    def evaluate(self, q: np.ndarray, hard: bool = False) -> _MirroredEvaluation:
        return _MirroredEvaluation(self.inner.evaluate(self.P @ q, hard), self, q)


class _MirroredEvaluation:
    """One evaluation over ``p = P q`` seen from ``q``: the rows are the same, the Jacobian ``J P``."""

    def __init__(self, ev: Any, merit: MirroredMerit, q: np.ndarray):
        self.ev, self.P, self.p, self.halves = ev, merit.P, q, merit.halves
        self.gviol, self.Xc = ev.gviol, ev.Xc

    @property
    def X(self) -> np.ndarray:
        return self.ev.X

    @property
    def r(self) -> np.ndarray:
        return self.ev.r

    def normal(self):
        """``(J P)ᵀ (J P)`` and ``(J P)ᵀ r`` formed over q's columns (``half_normal``), never ``JᵀJ`` over p's."""
        return half_normal(self.ev, self.P, self.halves)

    def jacobian(self) -> np.ndarray:
        J = self.ev.jacobian()
        return J if self.ev.merit._half is not None else np.asarray((self.P.T @ J.T).T)
