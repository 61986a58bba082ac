"""The ``homotopy`` driver: every tile's rigid motion interpolated between the three states.

Kind-agnostic (it assumes no mechanism): each tile ``T`` reaches closed state ``s`` from the
deployed state by a rigid motion, a rotation ``θˢ_T`` (the Kabsch angle of its corners) and a
move of its centroid. On each half of the path, with λ running from 0 (deployed) to 1 (closed
state ``s``), the driver holds every tile's Kabsch angle at ``λ θˢ_T`` and the node centroid on
the straight line between the states (:func:`.drivers.angle_drivers`); the spring energy is
minimised over the nodes with these held. At λ = 0 and 1 the one zero-energy configuration with
those angles is the state itself (tiles joined at hinges are placed by their angles up to a
translation), so E = 0 exactly there and the path has no special end segments.

The minimised energy is the springs' plus an orientation term (:mod:`.orientation`: each tile's
signed area held to its design, weight 1), zero at every state: without it triangles, whose edge
springs do not tell a tile from its mirror image, turned over on designed patterns and the
continuation ended in a mirrored branch 8-48 mm from the closed states. It also carries a contact
term (:mod:`.contact`: every gap at a hinge held above half its rigid value, weight 0.1), zero at
every state: without it the relaxed springs let a gap that folds flat in a closed state overshoot
through zero, and hinged tiles passed through each other (the designed ellipse 5x19 and hearts,
up to 1.17 mm deep). The energy reported along the path, E(t), is the springs' alone; the two
terms' largest values, and the narrowest gap against its rigid value, are figures of the path's
solver summary. A third term (:func:`.contact.corner_term`, weight 0.1) keeps every tile convex:
every corner under 135° held above half its design. With convex tiles the gap term alone keeps
hinged tiles apart; without it a thin quad of the designed heart 16x16 (``--solver full``) folded
into a bow-tie across its neighbour (7 overlaps, 0.3 mm deep).

The minimiser is continued outward from the deployed state on each half, so the deployed frame
is exact and the closed ends are what the continuation reaches: a miss there is measured and
reported by the path, never hidden. The predictor at each sub-step is the previous solution moved
by the change of the *rigid blend*: each tile placed rigidly by its interpolated angle and
centroid, and every node at the mean of its tiles' copies (which coincide at the three states).

For the standard kagome the interpolated angles are its exact counter-rotating mechanism (E = 0
along the whole path); for a quad the driver works too (``--driver homotopy``) but the
``rotations`` driver, which follows the quad mechanism, is the quad default.
"""

from __future__ import annotations

import numpy as np

from ...pattern import geometry
from ...pattern.model import Pattern
from ..contact import contact_figures, corner_term, gap_term, hinge_gaps
from ..elastic import MinimiseStats, minimise
from ..energy import Springs, WithTerm
from ..orientation import area_term
from ..path import piecewise, tile_angles
from .registry import PathDriver, angle_drivers, node_centroids, register_driver


def homotopy_targets(pattern: Pattern, states: dict[int, np.ndarray], t: np.ndarray) -> np.ndarray:
    """``(F, T)`` every tile's Kabsch angle from its deployed shape, linear in λ on each half.

    The closed-state angles are taken in (-π, π], the shorter way round."""
    deployed = pattern.corners()
    th = {s: tile_angles(deployed, states[s]) for s in (1, 2)}
    return piecewise(np.atleast_1d(t), th[1], np.zeros(pattern.n_tiles), th[2])


def rigid_blend(pattern: Pattern, states: dict[int, np.ndarray], t: np.ndarray) -> np.ndarray:
    """``(F, n, 2)`` nodes of the rigid blend: each tile turned by its interpolated angle about
    its interpolated centroid, every node at the mean of its copies (exact at the three states)."""
    t = np.atleast_1d(t)
    deployed = pattern.corners()
    cen = {0: deployed.mean(axis=1), **{s: states[s].mean(axis=1) for s in (1, 2)}}
    shape = deployed - cen[0][:, None]
    theta = homotopy_targets(pattern, states, t)  # (F, T)
    c = piecewise(t, cen[1], cen[0], cen[2])  # (F, T, 2)
    corners = geometry.rotate(shape[None], theta[..., None]) + c[:, :, None]
    flat = pattern.tiles.ravel()
    count = np.bincount(flat, minlength=len(pattern.nodes)).astype(float)
    out = np.zeros((len(pattern.nodes), len(t), 2))  # node first: one np.add.at over all frames
    np.add.at(out, flat, corners.reshape(len(t), -1, 2).transpose(1, 0, 2))
    return out.transpose(1, 0, 2) / count[None, :, None]


class Homotopy(PathDriver):
    """Each tile's rotation and centroid interpolated between the states, springs relaxed."""

    name = "homotopy"
    help = "each tile's rigid motion interpolated between the states (any kind; kagome default)"
    orientation_weight = 1.0  # of the area term against the springs (both relative strains²)
    contact_weight = 0.1  # of the gap term (relative shortfall³ of a gap below its clearance)
    contact_kappa = 0.5  # clearance: this fraction of the rigid blend's gap
    convex_weight = 0.1  # of the corner term: every tile's corners above half their design
    max_iter = 200  # Newton steps per sub-step: next to a closed state the contact term is stiff

    def values(self, pattern, states, t):
        return homotopy_targets(pattern, states, t)

    def constraints(self, pattern, states, t):
        t = np.atleast_1d(t)
        return angle_drivers(
            pattern, t, homotopy_targets(pattern, states, t), node_centroids(pattern, states, t)
        )

    def solve(
        self,
        pattern: Pattern,
        sp: Springs,
        states,
        fine,
        drivers,
        plan,
        tol: float,
        stats: MinimiseStats,
    ):
        """Continue outward from the deployed frame (t = ½) on each half, minimising the springs
        plus the orientation term; the figures are :func:`_figures` and the orientation term's
        weight and largest value."""
        blend = rigid_blend(pattern, states, fine).reshape(len(fine), -1)
        zero = 1e-24 * sp.n_springs  # rms relative strain 1e-12: rounding level
        area = area_term(pattern, self.orientation_weight)
        osp = WithTerm(sp, area)
        if self.convex_weight > 0.0:
            osp = WithTerm(
                osp, corner_term(pattern, weight=self.convex_weight, kappa=self.convex_kappa)
            )
        gaps = hinge_gaps(pattern, states)
        mid = int(np.argmin(np.abs(fine - 0.5)))
        sols: list = [None] * len(fine)
        terms: list = [None] * len(fine)
        for order in (range(mid, -1, -1), range(mid, len(fine))):
            prev = None
            for i in order:
                guess = blend[i] if prev is None else sols[prev] + (blend[i] - blend[prev])
                drv = drivers[i]
                term = terms[i] = gap_term(
                    gaps, float(fine[i]), weight=self.contact_weight, kappa=self.contact_kappa
                )
                sols[i] = minimise(
                    WithTerm(osp, term),
                    guess,
                    drv.A,
                    drv.b,
                    step_tol=tol,
                    stats=stats,
                    zero_energy=zero,
                    max_iter=self.max_iter,
                )
                prev = i
        figures = _figures(pattern, fine, np.stack(sols), blend, mid)
        figures["orientation_weight"] = area.weight
        figures["orientation_energy_max"] = max(area.energy(x) for x in sols)
        figures.update(contact_figures(terms, sols))
        return sols, figures


def _figures(
    pattern: Pattern, fine: np.ndarray, x: np.ndarray, blend: np.ndarray, mid: int
) -> dict:
    """What tells a followed branch from a snap: the largest node move between two sub-steps
    against the rigid blend's (tile sizes), and the most tiles turned over (mirrored: a spring
    tile's edge lengths do not tell it from its mirror image) in any sub-step."""
    size = pattern.tile_size
    move = np.abs(np.diff(x, axis=0)).max(axis=1) / size
    k = int(np.argmax(move))
    corners = x.reshape(len(fine), -1, 2)[:, pattern.tiles]
    designed = np.sign(geometry.signed_areas(pattern.corners()))
    mirrored = (np.sign(geometry.signed_areas(corners)) != designed).sum(axis=1)
    return {
        "continued_from_t": float(fine[mid]),
        "largest_substep_move_tile_sizes": float(move[k]),
        "t_at_largest_substep_move": float(fine[k + 1] if fine[k + 1] > 0.5 else fine[k]),
        "rigid_blend_largest_substep_move_tile_sizes": float(
            np.abs(np.diff(blend, axis=0)).max(initial=0.0) / size
        ),
        "mirrored_tiles_max": int(mirrored.max(initial=0)),
    }


HOMOTOPY = register_driver(Homotopy())
