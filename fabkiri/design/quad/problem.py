"""The full inverse-design problem: families over one node array (deployed nodes, then closed grids).

``DesignProblem`` builds the start (a guess, a warm start or coarse to fine) and
the equality, fit, regulariser and inequality families of a ``DesignRequest``;
``measures.py`` measures a node array against them.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import replace
from typing import Any

import numpy as np
from scipy import sparse

from ... import limits
from ...errors import SolveError
from ...pattern import geometry
from ...pattern.conformance import boundary_tip_order
from ...pattern.kinds.quad.lattice import standard_pattern
from ...pattern.model import Pattern
from ..core.conformance import deployed
from ..core.normal import NormalEquations, nested_dissection
from ..core.request import FINISH_FLOOR, DesignRequest, DesignResult, reduced_applies
from ..targets.lookup import Target
from . import constraints as C
from .chain import CHAIN_BOTTOM, keep_bottom, level_of
from .fabrication import families as fabrication_families
from .initial import coarse_tile_map, initial_guess
from .objective import regularizer, weighted
from .opening_rows import opening_families
from .rigid.contact import CONTACT_MARGIN, ClosedContact
from .rigid.family import EXACT_GRID, RigidFamily, resample_grid
from .rigid.mirror import centred
from .rigid.unfold import convex_member

CONVEX_MARGIN = 0.02  # cross(next - v, prev - v) >= 0.02 l^2: tile angles stay > ~1° from 0 and π
GAP_MARGIN = (
    0.005  # gap angles at hinges: the penalty acts before the hard limit g >= 0 stops a step
)
# in a minimax finish's steps no tile edge shorter than this many of the readers' least length
# (``limits.MIN_LENGTH_MM``): a row per edge (``constraints.least_edges``), inactive above it. A floor in mm, not a
# share of the tile: the drop's point takes a needle tile at every lattice size; twice the least length held the
# 96x96 drop's point tile too wide for the steps to fit it (docs/design-solver.md, "edge57", "fx57, Session 57")
LEAST_EDGE_FLOORS = 1.2
# ... but at most this share of the tile unit: tiles of a few micrometres are not reshaped by a floor of a sizable
# share of them (a target too small for its tile count is refused with its advice, ``limits.check_designed``)
LEAST_EDGE_SHARE = 0.01
COARSE_MIN = 16  # --init coarse: a level with fewer tiles a side than this starts from rescaled
# the largest mirrored level refitted tips only from rescaled where its fine start overlaps (``_tips_level``):
# larger levels so refitted sent the peanut's 64x64 design to a worse fit and a far longer finish, the star's
# 16x16 one is what its 32x32 and 64x64 designs need (docs/design-solver.md, measured there)
TIPS_LEVEL_MAX = 16
# the rigid-first route's outline that ends its search after the coarse start (``routes._solve_rigid_first``); a
# mirrored level up to ``TIPS_LEVEL_MAX`` tiles a side that misses by more tries rescaled too (``_rescaled_level``)
RIGID_FIRST_GOOD = 5e-3

# the designer of a whole request (``solve._design``, with its progress flag): a coarse level and a rigid route
# are whole designs of their own, so the module above hands its designer down instead of being imported here
WholeDesign = Callable[[DesignRequest, bool], DesignResult]


class DesignProblem:
    """Families over one node array (deployed nodes, then closed grids). ``whole_design`` designs the
    coarse level of a coarse-to-fine start and the rigid routes (:func:`.solve.design_problem` gives it)."""

    def __init__(self, req: DesignRequest, whole_design: WholeDesign | None = None):
        self.req = req
        self.whole_design = whole_design
        std = standard_pattern(req.rows, req.cols, tile_size=1.0)
        self.std = std
        st = C.Stencils.from_pattern(std)
        self.st = st
        base = std.nodes.copy()
        self.n = len(base)
        self.coarse: dict[str, Any] | None = None
        # the coarse level of the rigid design that answered a non-rigid request (``routes._solve_via_rigid``)
        self.via_coarse: dict[str, Any] | None = None
        # (seeds in mm, ψ) when the start is a rigid-family member (coarse to fine)
        self.start_member: tuple[np.ndarray, float] | None = None
        self.unfold: dict | None = (
            None  # fold repair of a coarse-to-fine rigid start (``unfold.convex_member``)
        )
        self._rigid: RigidFamily | None = None
        X0, L0 = self._start(base, st)
        curves = {s: v for s, v in req.contracted.items() if isinstance(v, Target)}
        if req.target is None:
            first = curves[min(curves)]
            L0 = float(np.sqrt(abs(first.area) / (req.rows * req.cols)))
        self.L0 = L0
        # a closed state has the area of its tiles: compare outlines by shape, at MN tiles of size L0
        self.curves_mm = {
            s: c.transformed(float(np.sqrt(req.rows * req.cols * L0 * L0 / abs(c.area))))
            for s, c in curves.items()
        }
        self.X0 = self._closed_grids(X0)
        fam = self._families(base)
        self.families = fam
        self._normal: NormalEquations | None = None
        # a family may ask its own margin (``meta["margin"]``, tile units: the fabrication rows of a continuation step)
        self.margin = {
            f.name: f.meta.get("margin", CONVEX_MARGIN if "convexity" in f.name else GAP_MARGIN)
            for f in fam
            if f.kind == "ineq"
        }

    def _start(self, base: np.ndarray, st: C.Stencils) -> tuple[np.ndarray, float]:
        """Initial deployed nodes (tile units) and their tile size L0 (mm): a warm start, coarse or a guess."""
        req = self.req
        if req.start is not None:  # a warm start (continuation): its own tile size is the unit
            L0 = geometry.mean_edge_length(np.asarray(req.start, float)[st.tiles])
            X0 = np.asarray(req.start, float) / L0
        elif req.init == "coarse":
            X0, L0 = self._coarse_guess(base, st)
        else:
            X0, L0 = initial_guess(base, st, req.target, req.init)
        if (
            req.seed is not None
        ):  # a sweep's seeds axis: another start of the same guess (not the rigid family's)
            X0 = X0 + np.random.default_rng(req.seed).normal(0.0, 0.02, X0.shape)
        return X0, L0

    def _closed_grids(self, X0: np.ndarray) -> np.ndarray:
        """Append a closed grid per closed-state curve (``self.grids``) to the nodes; sets ``nv``."""
        req, st = self.req, self.st
        self.grids: dict[int, C.ClosedGrid] = {}
        blocks = [X0]
        nv = self.n
        for s in sorted(self.curves_mm):
            g = C.ClosedGrid.build(st, s, nv)
            self.grids[s] = g
            M, N = req.rows, req.cols
            gx, gy = np.meshgrid(np.arange(N + 1), np.arange(M + 1))
            grid = np.stack([gx.ravel() - N / 2, gy.ravel() - M / 2], -1).astype(float)
            lo, hi = self.curves_mm[s].bbox
            blocks.append(grid + 0.5 * (lo + hi) / self.L0)
            nv += g.n_vertices
        self.nv = nv
        return np.vstack(blocks)

    def _families(self, base: np.ndarray) -> list[C.Family]:
        """The equality, fit, regulariser and inequality families of the request, over ``nv`` nodes."""
        req, st, nv, L0 = self.req, self.st, self.nv, self.L0
        fam: list[C.Family] = []
        if req.holes == "rhombus":
            fam += [C.edge_pairs(st, 1, nv), C.edge_pairs(st, 2, nv)]
        else:
            fam += [
                C.hole_opposite_sides(st, nv),
                C.notch_pairs(st, 1, nv),
                C.notch_pairs(st, 2, nv),
            ]
        if req.rigid or req.holes == "parallelogram":
            fam.append(C.hinge_sums(st, nv))
        else:
            fam += [C.rings(st, 1, nv), C.rings(st, 2, nv)]
        if req.symmetry:
            fam.append(C.symmetry(st, base, req.symmetry, nv))
        fam += self._closed_state_families()
        fam += self._fit_families()
        fam.append(regularizer(st, nv))
        fam += [C.non_overlap(st, nv), C.convexity(st, nv)]
        if req.least_edge:  # a minimax finish's step only (``DesignRequest.least_edge``)
            floor = min(
                LEAST_EDGE_FLOORS * limits.MIN_LENGTH_MM / L0, LEAST_EDGE_SHARE
            )  # tile units
            fam.append(C.least_edges(st, nv, floor))
        fam += fabrication_families(st, nv, req.fabrication, L0, base)
        fam += opening_families(st, nv, req.min_opening, base)
        if req.fit_weights:  # a weighted fit (``refine.py``); reports measure the unweighted rows
            fam = [
                weighted(f, req.fit_weights[f.name]) if f.name in req.fit_weights else f
                for f in fam
            ]
        for g in self.grids.values() if req.holes == "rhombus" else ():
            fam.append(g.orientation(st, nv))
        return fam

    def _closed_state_families(self) -> list[C.Family]:
        """Each closed state's own rows: congruent to its grid, or a rectangle of the given ratio."""
        req, st, nv = self.req, self.st, self.nv
        fam: list[C.Family] = []
        for s, spec in sorted(req.contracted.items()):
            if isinstance(spec, Target):
                # with parallelogram holes only the grid's boundary is a closed state's (T-junctions inside)
                if req.holes == "rhombus":
                    fam.append(self.grids[s].congruence(st, nv))
            else:
                fam.append(C.rectangle_outline(st, s, nv))
                if spec[1] is not None:
                    fam.append(C.outline_ratio(st, s, float(spec[1]), nv))
        return fam

    def _fit_families(self) -> list[C.Family]:
        """The fits of the tips (and the outline) to the deployed target and of each closed grid to its curve."""
        req, st, nv, L0 = self.req, self.st, self.nv, self.L0
        fam: list[C.Family] = []
        if req.target is not None:
            tgt = req.target.transformed(1.0 / L0)
            fam.append(C.shape_match(st.tip_nodes, st.tip_side, tgt, nv, "shape"))
            if req.outline:
                top = self.std.topology
                order = boundary_tip_order(
                    top.tiles, top.hole_nodes, top.hole_tiles, top.free_nodes
                )
                fam.append(C.outline_match(order, tgt, nv))
        for s, g in self.grids.items():
            fam.append(
                C.shape_match(
                    g.boundary,
                    g.boundary_side,
                    self.curves_mm[s].transformed(1.0 / L0),
                    nv,
                    f"closed_shape_{s}",
                )
            )
        return fam

    def _coarse_guess(self, base: np.ndarray, st: C.Stencils) -> tuple[np.ndarray, float]:
        """Coarse-to-fine start: solve at half resolution, map the result onto the standard pattern."""
        req = self.req
        rc, cc = req.rows // 2, req.cols // 2
        # a mirror keeps the fold states only on an even count across its axis (``constraints.symmetry``)
        rc += int(req.symmetry == "x" and rc % 2 == 1)
        cc += int(req.symmetry == "y" and cc % 2 == 1)
        if req.target is None or min(rc, cc) < 4:
            return initial_guess(base, st, req.target, req.coarse_bottom)
        halved = (rc, cc, "coarse" if min(rc, cc) >= COARSE_MIN else req.coarse_bottom)
        # a target with no mirror: the chain's bottom a 32x32 level from rescaled where it fits closer (``chain.py``)
        rc, cc, init, bottom = level_of(req, *halved)
        sub = DesignRequest(
            rc,
            cc,
            req.target,
            rigid=req.rigid,
            symmetry=req.symmetry,
            holes=req.holes,
            contracted=dict(req.contracted),
            init=init,
            tol=req.tol,
            reg_weight=req.reg_weight,
            max_iter=req.max_iter,
            solver=req.coarse_solver or req.solver,
            coarse_refit=req.coarse_refit,
            coarse_refit_above=req.coarse_refit_above,
            coarse_bottom=req.coarse_bottom,
            # the coarse level is only a start: tips-only keeps its grid unfolded when resampled
            # (with the outline rows a rigid 8x8 ellipse's grid folded 4 fine tiles); the rescaled bottom has them
            outline=bottom,
            fabrication=req.fabrication,
            coarse_level=True,
            chain_tiles=req.chain_tiles or req.rows * req.cols,
        )
        sub, res, level, chained = self._guarded_level(sub, bottom, halved)
        rc, cc = sub.rows, sub.cols
        sc = standard_pattern(rc, cc, tile_size=1.0)
        if reduced_applies(req) and req.solver != "full":
            # from a tips-fitted level within FINISH_FLOOR (``routes.keeps_block``: no minimax finish follows, whose
            # stops move with any start) the start's seeds by the cheaper fits of a large lattice, round-off apart
            near = level["fit"] == "tips" and level["hausdorff_rel"] <= FINISH_FLOOR
            xmm = self._rigid_refinement(sc, res.pattern.nodes, near and not chained)
            # (a redesign with ``coarse_refit`` asks the outline rows: this level would be the same design twice)
            redo = req.symmetry and level["fit"] == "outline" and not req.coarse_refit
            # a bottom level starts from rescaled already: refitted tips only it has no other chain to leave
            redo = redo and COARSE_MIN <= min(rc, cc) and max(rc, cc) <= TIPS_LEVEL_MAX
            if redo and self._start_overlaps(xmm):
                res, level, xmm = self._tips_level(sub, sc, (res, level, xmm))
            how = "closed-state grid resampled in the rigid family"
        else:
            xmm = coarse_tile_map(
                sc.nodes, res.pattern.nodes, sc.tiles, cc, base, st.tiles, req.cols
            )
            how = "deployed tiles mapped"
        c = xmm[st.tiles]
        area = geometry.signed_areas(c)
        self.coarse = {
            "rows": rc,
            "cols": cc,
            "map": how,
            "status": res.report["status"],
            "time_s": res.report["time_s"],
            "iterations_total": res.report["iterations_total"],
            "factorisations": res.report["factorisations"],
            "folded_tiles": int((area <= 0).sum()),
            **level,
        }
        if chained:  # the finish reads it (``design_minimax.gate``)
            self.coarse["rescaled_bottom"] = CHAIN_BOTTOM
        if self.unfold is not None:
            self.coarse["unfold"] = self.unfold
        # an unconverged coarse design or a map that folds tiles is no better a start than rescaled
        self.coarse["used"] = bool(res.converged and not (area <= 0).any())
        if not self.coarse["used"]:
            return initial_guess(base, st, req.target, req.coarse_bottom)
        L0 = geometry.mean_edge_length(c)
        return xmm / L0, L0

    def _guarded_level(self, sub: DesignRequest, bottom: bool, halved: tuple[int, int, str]):
        """``(sub, result, how, chained)``: the coarse level ``sub`` asks, where it is the rescaled bottom
        (``bottom``, ``chain.py``) kept only where ``keep_bottom`` says, else the halving chain's level ``halved``
        (rows, cols, init) as main designs it; ``chained`` whether the chain bottomed at the rescaled level (here,
        or in the level's own chain)."""
        res, level = self._coarse_level(sub)
        if not bottom:
            return sub, res, level, bool((res.report.get("coarse") or {}).get("rescaled_bottom"))
        rows, cols, init = halved
        half = replace(sub, rows=rows, cols=cols, init=init, outline=False)
        if res.converged:  # an unconverged bottom is no start: the halving level alone
            h_res, h_level = self._coarse_level(half)
            if keep_bottom(level["hausdorff_rel"], h_res.converged, h_level["hausdorff_rel"]):
                return sub, res, level, True
            return half, h_res, h_level, False
        return (half, *self._coarse_level(half), False)

    def design_whole(self, req: DesignRequest) -> DesignResult:
        """A whole design of ``req`` (a coarse level, a rigid route) by this problem's ``whole_design``."""
        if self.whole_design is None:
            raise ValueError(
                "a whole design needs the designer: build the problem with solve.design_problem"
            )
        return self.whole_design(req, False)

    def _coarse_level(self, sub: DesignRequest):
        """The coarse level's design and how it was fitted: tips only (its grid stays unfolded when resampled);
        with ``coarse_refit``, where that outline misses the target by more than the shape tolerance
        (``second_opinion_above``, or ``coarse_refit_above``), again with the outline rows, keeping the closer converged outline. The
        tips-only fit lets tips bunch on their arcs: the drop's 16x16 and 32x32 levels sat at a Hausdorff distance
        of 40 % of its size (tips on their arcs to 0.47 %), and the 64x64 design they started ended at 22 %.
        A symmetric level is fitted with the outline rows first, tips only where that does not converge; a level
        that asks them (``sub.outline``: the rescaled bottom, ``chain.py``) has them alone."""
        target = sub.target
        assert target is not None, "a coarse level is built only for a deployed target"

        def miss(res) -> float:
            return deployed(res.pattern.nodes, res.pattern.topology, target)["hausdorff_rel"]

        # a mirrored level with the outline rows first: tips only, over half the seeds, its tips bunched further
        # than the free level's (the 96x96 ellipse's 12x12 level at 6.5 % of the size after the mirrored starts,
        # 0.20 % with the rows; the drop's 8x8 level 32.5 %, 2.0 %), and those starts cost more than this one fit
        if sub.symmetry:
            alt = self.design_whole(replace(sub, outline=True))
            if alt.converged:
                return self._rescaled_level(sub, alt, miss)
        res = self.design_whole(sub)
        h = miss(res)
        level = {"fit": "outline" if sub.outline else "tips", "hausdorff_rel": h}
        above = self.req.coarse_refit_above
        if (
            sub.outline
            or not self.req.coarse_refit
            or h <= (self.req.second_opinion_above if above is None else above)
        ):
            return res, level
        alt = self.design_whole(replace(sub, outline=True))
        h_alt = miss(alt)
        level["tips_only_hausdorff_rel"] = h
        if alt.converged and (h_alt < h or not res.converged):
            return alt, {**level, "fit": "outline", "hausdorff_rel": h_alt}
        return res, level

    def _rescaled_level(self, sub: DesignRequest, level, miss) -> tuple:
        """``(result, how)`` of a mirrored level fitted with the outline rows (``level``, measured by ``miss``).
        One up to ``TIPS_LEVEL_MAX`` tiles a side that misses by more than ``RIGID_FIRST_GOOD`` is designed from
        rescaled as well (the rigid-first route's second start for a 16x16 request, ``routes._solve_rigid_first``),
        that one kept where it converges within ``RIGID_FIRST_GOOD``. The peanut's 16x16 level from its 8x8 one
        missed by 0.56 %, from rescaled 0.24 % (its 16x16 design's); its 32x32 and 64x64 designs from the first
        0.31 % and 0.11 %, above its 16x16 and 48x48 designs."""
        h = miss(level)
        how = {"fit": "outline", "hausdorff_rel": h}
        small = sub.init == "coarse" and max(sub.rows, sub.cols) <= TIPS_LEVEL_MAX
        if not small or h <= RIGID_FIRST_GOOD:
            return level, how
        alt = self.design_whole(replace(sub, outline=True, init="rescaled"))
        h_alt = miss(alt)
        # kept only where it reaches the good outline: the star's 16x16 level from rescaled came closer (0.59
        # against 1.70 %) but its 32x32 design further (0.45 against 0.24 %), and the finish then cost 6x its CPU
        if not (alt.converged and h_alt <= RIGID_FIRST_GOOD):
            return level, how
        return alt, {**how, "hausdorff_rel": h_alt, "coarse_start_hausdorff_rel": h}

    def _start_overlaps(self, x_mm: np.ndarray) -> bool:
        """Whether the fine start (``start_member``, nodes ``x_mm``) has tiles of a closed state overlapping by
        more than the contact rows' margin (``contact.py``; the drop's 16x16 start touches, 5e-5 tile deep)."""
        assert self.start_member is not None, "a rigid refinement sets the start member"
        fam, S = self.rigid_family, self.start_member[0]
        gaps = ClosedContact(fam, self.st).values((fam.grid(S), fam.Y @ S)).values()
        unit = geometry.mean_edge_length(x_mm[self.st.tiles])
        return min(float(g.min(initial=np.inf)) for g in gaps) < -CONTACT_MARGIN * unit

    def _tips_level(self, sub: DesignRequest, sc: Pattern, outline_level: tuple) -> tuple:
        """A mirrored level fitted with the outline rows whose resampled fine start has closed-state tiles
        overlapping: the level tips only as well, kept when its fine start is apart. From the overlapping start
        the fine solve ends overlapping and runs the contact rows twice (the star's 32x32 design from its
        outline-fitted 16x16 level, state 2 overlapping by 0.10 tile at the start: 283 iterations; from the
        tips-only level, apart: 41). ``(res, level, x_mm)`` of the one kept."""
        kept = self.start_member, self.unfold
        # from rescaled, not from its own chain: that chain's levels have the outline rows and the same
        # closed states (the star's tips-only 16x16 level from its 8x8 one still started the 32x32 overlapping)
        res = self.design_whole(replace(sub, init="rescaled"))
        if res.converged:
            xmm = self._rigid_refinement(sc, res.pattern.nodes)
            if not self._start_overlaps(xmm):
                assert sub.target is not None, "a coarse level is built only for a deployed target"
                h = deployed(res.pattern.nodes, res.pattern.topology, sub.target)["hausdorff_rel"]
                return res, {"fit": "tips", "hausdorff_rel": h, "outline_start_overlaps": True}, xmm
        self.start_member, self.unfold = kept
        return outline_level

    def _rigid_refinement(
        self, coarse: Pattern, x_mm: np.ndarray, cheap: bool = False
    ) -> np.ndarray:
        """Fine start (mm) from a coarse rigid design: its closed-state-1 grid resampled to this lattice.

        The coarse design is a member of its own rigid family at its deployment angle ψ (every hole opens
        to 2ψ); the fine start is the fine member nearest the resampled grid, deployed to the same ψ. ``cheap``:
        above ``EXACT_GRID``, the coarse seeds by ``member_seeds`` and the fine ones by the normal equations.
        """
        st_c = C.Stencils.from_pattern(coarse)
        fam_c = RigidFamily.of_standard(st_c, lambda: coarse.topology.spanning_tree(0))
        psi = RigidFamily.deployment_angle(x_mm, st_c)
        # a large lattice's coarse level is a reduced solve's member: its seeds from its seed tiles alone
        cheap = cheap and (self.req.rows + 1) * (self.req.cols + 1) > EXACT_GRID
        S_c = fam_c.member_seeds(x_mm, psi) if cheap else None
        if S_c is None:
            S_c, _ = fam_c.fit(x_mm, psi)
        grid = resample_grid(
            fam_c.grid(S_c).reshape(st_c.rows + 1, st_c.cols + 1, 2), self.req.rows, self.req.cols
        )
        fam = self.rigid_family
        # the nearest fine member can fold cells the resampled grid does not: repaired (``unfold.py``)
        S, self.unfold = convex_member(
            fam, fam.node_vertex[self.st.tiles], grid.reshape(-1, 2), normal=cheap
        )
        self.start_member = (
            S,
            psi,
        )  # the start's seeds: the reduced solver need not fit them again
        return fam.nodes(S, psi)

    @property
    def target(self) -> Target:
        """The deployed target; the routes that measure the deployed outline run only when there is one."""
        if self.req.target is None:
            raise SolveError("this design route needs a deployed target")
        return self.req.target

    @property
    def rigid_family(self) -> RigidFamily:
        """The closed-form rigid family of this lattice (``rigid/family.py``), built on first use."""
        if self._rigid is None:
            self._rigid = RigidFamily.of_standard(
                self.st, lambda: self.std.topology.spanning_tree(0)
            )
            if self.req.symmetry:  # a translation gauge the mirror keeps (``rigid/mirror.py``)
                self._rigid = centred(self._rigid)
        return self._rigid

    def _ordering(self) -> np.ndarray | None:
        """Variable order for the normal equations, from the union of all Jacobian patterns."""
        if self.nv < 200:
            return None
        S = None
        for f in self.families:
            _, J = f(self.X0)
            P = abs(J).T @ abs(J)
            S = P if S is None else S + P
        assert S is not None, "every request has its edge-pair or opposite-side families"
        S = S.tocoo()
        node = sparse.csr_matrix(
            (np.ones(S.nnz), (S.row // 2, S.col // 2)), shape=(self.nv, self.nv)
        )
        o = nested_dissection(node, self.X0)
        return np.stack([2 * o, 2 * o + 1], 1).ravel()

    @property
    def normal(self) -> NormalEquations:
        """Normal-equation solver of the full problem, built on first use (its ordering costs a Jacobian)."""
        if self._normal is None:
            self._normal = NormalEquations(self._ordering())
        return self._normal

    def of(self, kind: str) -> list[C.Family]:
        return [f for f in self.families if f.kind == kind]
