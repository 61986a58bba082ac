"""What the inverse-design solvers are asked and what they answer (``solve.design``).

``DesignRequest`` says what to design; ``DesignResult`` carries the deployed
design and its report. The ``*_applies`` predicates say which route a request
takes (``solve._design`` follows them in order).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ...errors import InputError, Param
from ...pattern.model import Pattern
from ..quad.fabrication import FabricationLimits
from ..quad.rigid import offset_outline
from ..targets.lookup import Target

SOLVERS = ("auto", "reduced", "full")
# from this many tiles a non-rigid rhombus design (no closed-state target) is solved as the rigid
# one, coarse to fine: a rigid member satisfies every non-rigid equality, and there the full solver over all
# nodes was slower and mostly worse (API, rescaled, 100 mm: 32x32 heart Hausdorff 7.1 % of the target's
# diagonal; 32x32 ellipse unconverged, 11.8 %; rigid family: 7.5 %, 1.2 %, in a tenth of the time)
VIA_RIGID_TILES = 32 * 32
# below that, the CLI's last guess for a non-rigid design that missed: answered by the rigid family as well
# (leaf SVG 16x16: conformal unconverged, rescaled overlapping, standard 22.6 % off; the rigid family 1 %)
VIA_RIGID_INIT = "rigid"
# from this many tiles (below VIA_RIGID_TILES) a non-rigid rhombus design tries the rigid family first, from
# each of RIGID_FIRST_INITS, reduced only, and keeps the member with the closest outline if it is within the
# shape tolerance; otherwise the full solver runs as before. Measured (design(), 16x16, 100 mm): heart
# full Hausdorff 8.3 % -> rigid family 1.4 %; ellipse 2:1 full 0.77 % -> rigid family from coarse 0.18 %,
# each faster too. A member meeting RIGID_FIRST_GOOD ends the search early.
VIA_RIGID_FIRST_TILES = 16 * 16


# a target this close to mirror-symmetric (share of its size, Target.mirror_error) may be designed mirrored
MIRROR_TOL = 1e-3
# the minimax finish's gate (``api/design_minimax.gate``) scales down to this share of the size and no further:
# below it the finish's 2-6 designs bought at most about 0.1 % of the size, and the 64x64 and 128x128 rigid
# circles (0.21 %, 0.22 %) would pay them dearly. Here because the rigid route's kept grid block reads it too
# (``routes.keeps_block``)
FINISH_FLOOR = 0.0025


@dataclass
class DesignRequest:
    """What to design. Targets are in mm."""

    rows: int
    cols: int
    target: Target | None = None
    rigid: bool = False
    symmetry: str | None = None  # "x": y -> -y, "y": x -> -x
    holes: str = "rhombus"  # or "parallelogram"
    contracted: dict = field(default_factory=dict)  # state -> Target | ("rect", ratio or None)
    init: str = "rescaled"
    solver: str = (
        "auto"  # "reduced": closed-form rigid family only; "full": all nodes; "auto": see _design
    )
    tol: float = 1e-10
    reg_weight: float = 1e-3
    max_iter: int = 300
    name: str = ""
    outline: bool = (
        True  # also fit the tip polygon's chords and the target's samples (``C.outline_match``)
    )
    fabrication: FabricationLimits | None = (
        None  # mm limits at the target's size (design/quad/fabrication.py)
    )
    fabrication_intent: dict = field(
        default_factory=dict
    )  # material/printer names: stored for cut and print
    seed: int | None = (
        None  # jitter the initial nodes (2 % of a tile edge) to explore other local minima
    )
    second_opinion: bool = (
        True  # auto: also run the full solver when the rigid family's fit is least-squares
    )
    # ... up to 16x16 tiles only when its outline misses by more than this share of the target's size (the
    # CLI passes its --shape-tol): where the rigid design already meets the tolerance the full solver is skipped
    second_opinion_above: float = 0.02
    start: np.ndarray | None = (
        None  # deployed nodes (mm) to start from instead of ``init`` (a warm start)
    )
    rigid_first: bool = (
        True  # a mid-size non-rigid design tries the rigid family first (VIA_RIGID_FIRST_TILES)
    )
    coarse_solver: str | None = None  # --init coarse: the coarse levels' solver (None: ``solver``)
    # --init coarse: the guess the chain's bottom level starts from; a bent strip's is its fold-free start,
    # conformal (``api/design_strip.py``): from rescaled the strip's bottom level starts straight
    coarse_bottom: str = "rescaled"
    # --init coarse: refit a coarse level whose tips-only outline misses ``second_opinion_above`` with the outline
    # rows (``DesignProblem._coarse_level``); ``solve._design`` sets it when the design from the tips-only levels misses
    coarse_refit: bool = False
    # ... and whether ``solve._design`` does so on its own (False: the caller asks the refit where it needs it,
    # as the rigid-first route does after its other start, ``routes._solve_rigid_first``)
    coarse_refit_on_miss: bool = True
    # with ``coarse_refit``: refit the levels that miss by more than this share instead (None: the shape tolerance;
    # the minimax finish asks its own, smaller, threshold)
    coarse_refit_above: float | None = None
    min_opening: float | None = None  # floor on the deployed hole fraction (``opening_rows.py``)
    fit_weights: dict | None = (
        None  # fit family name -> row weights (``refine.py``: towards the minimax fit)
    )
    # a minimax finish's cheaper step (``api/design_minimax.py``), warm-started from a converged rigid design: the
    # reduced solver's first LM scaling only and no stiffer second stage after a feasible first (``routes._solve_reduced``)
    finish_step: bool = False
    # a minimax finish's step (``api/design_minimax.py``): the least tile-edge rows (``constraints.least_edges``) in
    # its solve. Off elsewhere: a solve's trial steps pass edges through zero on the way, and the rows moved cells
    # whose designs never come near the floor (docs/design-solver.md, "edge57, Session 57", "fx57, Session 57")
    least_edge: bool = False
    # the rigid sub-solve's guess for a non-rigid request (None: rescaled below VIA_RIGID_TILES, coarse from
    # it); the pocket split's attempt (``api/design_pocket.py``) asks coarse, the bent strip's conformal
    via_rigid_init: str | None = None
    # a coarse level of a larger design (``DesignProblem._coarse_guess``), not the lattice asked for: the reduced
    # solver's stiffer-stage attempt is for the top level only (``routes.MEMBER_STAGE_TILES``)
    coarse_level: bool = False
    # a coarse level's: the tile count of the lattice asked for, the chain's top (``routes.KEEP_BLOCK_TILES``)
    chain_tiles: int = 0

    def validate(self) -> None:
        if (
            int(self.rows) != self.rows
            or int(self.cols) != self.cols
            or self.rows < 2
            or self.cols < 2
        ):
            raise InputError(
                f"inverse design needs at least 2x2 tiles, got {self.rows}x{self.cols}"
            )
        if self.holes not in ("rhombus", "parallelogram"):
            raise InputError(
                Param("holes"), f" must be rhombus or parallelogram, not {self.holes!r}"
            )
        if self.solver not in SOLVERS:
            raise InputError(
                Param("solver"), f" must be one of {', '.join(SOLVERS)}, not {self.solver!r}"
            )
        if self.solver == "reduced" and not reduced_applies(self):
            raise InputError(
                Param("solver", "reduced"),
                " needs ",
                Param("rigid", True),
                ", rhombus holes, a ",
                Param("target"),
                ", and no ",
                Param("contracted_target"),
                " (the closed-form rigid family covers only that)",
            )
        if self.symmetry not in (None, "x", "y"):
            raise InputError(Param("symmetry"), f" must be x or y, not {self.symmetry!r}")
        if not (np.isfinite(self.tol) and 0 < self.tol < 1e-2):
            raise InputError(Param("tol"), f" must lie in (0, 1e-2), got {self.tol}")
        self._check_targets()

    def _check_targets(self) -> None:
        """The closed states named, something to fit, and each target symmetric where ``symmetry`` says."""
        for s, spec in self.contracted.items():
            if s not in (1, 2):
                raise InputError(f"closed states are 1 and 2, not {s}")
            if (
                isinstance(spec, Target)
                and self.holes == "parallelogram"
                and not offset_outline.covers(self)
            ):
                raise InputError(
                    "a closed-state target curve needs rhombus holes (parallelogram holes leave "
                    "T-junctions, so the closed state is not a grid)"
                )
        if self.target is None and not any(isinstance(v, Target) for v in self.contracted.values()):
            raise InputError(
                "nothing to fit: give ",
                Param("target"),
                " or a ",
                Param("contracted_target"),
                " curve",
            )
        if self.symmetry:
            for tgt in [
                self.target,
                *[v for v in self.contracted.values() if isinstance(v, Target)],
            ]:
                if tgt is not None and tgt.mirror_error(self.symmetry) > MIRROR_TOL:
                    raise InputError(
                        f"target {tgt.name!r} is not symmetric about the {self.symmetry} axis, so ",
                        Param("symmetry", self.symmetry),
                        " contradicts it",
                    )


@dataclass
class DesignResult:
    pattern: Pattern  # deployed design in mm (no closed states: the caller contracts)
    report: dict
    converged: bool
    closed_grids: dict  # state -> (V, 2) closed-state pattern vertices in mm
    closed_targets: (
        dict  # state -> Target (mm) the closed grid was fitted to, scaled to the tiles' area
    )

    @property
    def max_equality_residual(self) -> float:
        """The largest equality residual the solve ended at (the same name as the tube's result)."""
        return float(self.report["max_equality_residual"])


def reduced_applies(req: DesignRequest) -> bool:
    """The closed-form rigid family covers the request (see ``quad/rigid/family.py``)."""
    return req.rigid and req.holes == "rhombus" and not req.contracted and req.target is not None


def via_rigid_applies(req: DesignRequest) -> bool:
    """A non-rigid request answered by the rigid family (``VIA_RIGID_TILES``)."""
    return (
        req.solver == "auto"
        and not req.rigid
        and req.holes == "rhombus"
        and not req.contracted
        and req.target is not None
        and (req.rows * req.cols >= VIA_RIGID_TILES or req.init == VIA_RIGID_INIT)
    )


def coarse_refit_applies(req: DesignRequest, coarse: dict | None) -> bool:
    """Whether a design of ``req`` whose start was ``coarse`` (its report's ``coarse``: None without coarse levels)
    can be designed again with its coarse levels refitted with the outline rows (``coarse_refit``): not a refit
    already, the outline rows asked, and not a level that had them (a mirrored level)."""
    return (
        not req.coarse_refit
        and req.outline
        and coarse is not None
        and req.target is not None
        and coarse.get("fit") != "outline"
    )


def rigid_first_applies(req: DesignRequest) -> bool:
    """A non-rigid request that tries the rigid family before the full solver (``VIA_RIGID_FIRST_TILES``)."""
    return (
        req.rigid_first
        and req.start is None
        and req.seed is None
        and not via_rigid_applies(req)
        and req.solver == "auto"
        and not req.rigid
        and req.holes == "rhombus"
        and not req.contracted
        and req.target is not None
        and req.rows * req.cols >= VIA_RIGID_FIRST_TILES
    )
