"""Inverse design of a reconfigurable tube: a periodic sheet whose closed states roll into cylinders.

The sheet is the standard lattice of ``rows x (cols + 1)`` tiles with the seam copy column
(:mod:`fabkiri.pattern.kinds.periodic.sheet`). The unknowns are its deployed nodes in normalised units (initial
tile edge 1). Equalities: reconfigurability of both closed states (edge pairs and rings, or hinge
sums when rigid deployability is asked), the deployed seam map fixed by the target, and a pure
translation seam in both closed states (:mod:`fabkiri.design.tube.periodic`). The target's two ends are
fitted in least squares with the smooth-shape regulariser; non-overlap at every hinge and tile
convexity are penalties.

Two stages: a sparse least-squares solve of the penalised problem (scipy ``trf`` with ``lsmr``),
then Gauss-Newton minimum-norm steps on the equalities alone until their largest residual is at or
below ``tol``; a run that stops above ``tol`` says so with its figures (``converged`` False).
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field, replace

import numpy as np
from scipy import sparse
from scipy.optimize import least_squares
from scipy.sparse.linalg import lsqr

from ...errors import InputError
from ...pattern.kinds.periodic.sheet import check_tube_size, lattice_seam, with_seam
from ...pattern.kinds.quad.lattice import standard_pattern
from ...pattern.model import Pattern
from ..core.lm import halving_gauss_newton
from ..quad import constraints as C
from ..quad.objective import regularizer
from . import periodic as P

EQ_WEIGHT = (
    30.0  # equalities against the fit in the first stage (the second stage makes them exact)
)
GAP_MARGIN = 0.005  # as the planar solver: gap angles and tile corners kept off 0 and π
CONVEX_MARGIN = 0.02
CONE_STEP_RAD = (
    0.02  # continuation from the cylinder: the sector angle grows by at most this a step
)


@dataclass
class TubeRequest:
    """What tube to design: ``rows`` x ``cols`` tiles around (``cols`` even) and a target (mm)."""

    rows: int
    cols: int
    target: P.TubeTarget
    rigid: bool = False
    closed: str = "cylinder"  # "cone": closed seams free, hinge sums instead (docs/tubes.md, cone in every state)
    tol: float = 1e-10
    reg_weight: float = 1e-2
    max_iter: int = 200
    name: str = ""

    def validate(self) -> None:
        if int(self.rows) != self.rows or int(self.cols) != self.cols:
            raise InputError(f"--tiles must be whole numbers, got {self.rows}x{self.cols}")
        check_tube_size(self.rows, self.cols)
        if self.closed not in ("cylinder", "cone"):
            raise InputError(f"--closed must be cylinder or cone, got {self.closed!r}")
        if self.closed == "cone" and self.target.kind != "cone":
            raise InputError(
                "--closed cone needs a cone target (--tube cone:R_BOTTOM,R_TOP,LENGTH)"
            )
        if not (np.isfinite(self.tol) and 0 < self.tol < 1e-2):
            raise InputError(f"--tol must lie in (0, 1e-2), got {self.tol}")


@dataclass
class TubeResult:
    pattern: (
        Pattern  # the deployed sheet in mm, seam recorded (no closed states: the caller contracts)
    )
    converged: bool
    report: dict = field(default_factory=dict)

    @property
    def max_equality_residual(self) -> float:
        """The largest equality residual the solve ended at (the report's ``equality_max``)."""
        return float(self.report["equality_max"])


class _TubeProblem:
    """The families of one request over the sheet's deployed nodes."""

    def __init__(self, req: TubeRequest, start: np.ndarray | None = None):
        self.req = req
        self.std = standard_pattern(req.rows, req.cols + 1, tile_size=1.0)
        self.st = st = C.Stencils.from_pattern(self.std)
        cone_closed = req.closed == "cone"
        self.seam = lattice_seam(
            req.rows,
            req.cols,
            req.target.kind,
            req.closed if req.target.kind == "cone" else "cylinder",
        )
        self.geo = geo = P.unit_geometry(req.target, req.cols * np.sqrt(2.0))
        nv = st.n_nodes
        fam = [C.edge_pairs(st, 1, nv), C.edge_pairs(st, 2, nv)]
        # closed cones: hinge sums make every state's seam turn alike (a rigid tube), so no closed-seam rows
        rigid = req.rigid or cone_closed
        fam += [C.hinge_sums(st, nv)] if rigid else [C.rings(st, 1, nv), C.rings(st, 2, nv)]
        fam += [P.deployed_seam(self.seam, st, geo, nv)]
        fam += [] if cone_closed else [P.closed_seam(self.seam, st, s, nv) for s in (1, 2)]
        self.eq = fam
        self.fit = P.tube_fit(st, geo, nv)
        self.reg = regularizer(st, nv)
        self.ineq = [(C.non_overlap(st, nv), GAP_MARGIN), (C.convexity(st, nv), CONVEX_MARGIN)]
        self.X0 = self._initial() if start is None else start

    def _initial(self) -> np.ndarray:
        """The standard sheet (period ``cols √2``) laid on the target's unrolled surface."""
        x = self.std.nodes.copy()
        x[:, 0] -= x[:, 0].min() + 0.5 * self.req.cols * np.sqrt(2.0) + 0.5 * np.sqrt(2.0)
        geo = self.geo
        lo, hi = x[:, 1].min(), x[:, 1].max()
        t = (x[:, 1] - lo) / (hi - lo)
        if geo.apex is None:
            return np.stack([x[:, 0], geo.bottom + t * (geo.top - geo.bottom)], -1)
        rho = geo.bottom + t * (geo.top - geo.bottom)
        phi = x[:, 0] * geo.alpha / (self.req.cols * np.sqrt(2.0))
        return geo.apex + np.stack([rho * np.sin(phi), -rho * np.cos(phi)], -1)

    def eq_residual(self, x: np.ndarray):
        parts = [f(x) for f in self.eq]
        return np.concatenate([r for r, _ in parts]), sparse.vstack([J for _, J in parts]).tocsr()

    def stacked(self, flat: np.ndarray):
        """Residuals and Jacobian of the first stage (weighted equalities, fit, regulariser, penalties)."""
        x = flat.reshape(-1, 2)
        r_eq, J_eq = self.eq_residual(x)
        r_fit, J_fit = self.fit(x)
        r_reg, J_reg = self.reg(x)
        w = np.sqrt(self.req.reg_weight)
        rs, Js = [EQ_WEIGHT * r_eq, r_fit, w * r_reg], [EQ_WEIGHT * J_eq, J_fit, w * J_reg]
        for fam, margin in self.ineq:
            g, J = fam(x)
            active = (g < margin).astype(float)
            rs.append(EQ_WEIGHT * active * (g - margin))
            Js.append(EQ_WEIGHT * sparse.diags(active) @ J)
        return np.concatenate(rs), sparse.vstack(Js).tocsr()


def _project(prob: _TubeProblem, x: np.ndarray, tol: float, max_iter: int = 30):
    """Gauss-Newton minimum-norm steps onto the equalities, halved until the residual norm drops;
    returns (x, max |r|, steps). It stops where no halving helps (the figures then say so)."""

    def step(y, state):
        r, J = state
        return lsqr(J, -r, atol=1e-15, btol=1e-15, iter_lim=20 * J.shape[1])[0].reshape(-1, 2)

    x, (r, _), steps = halving_gauss_newton(
        x, prob.eq_residual(x), step, prob.eq_residual, tol, max_iter, 12
    )
    return x, float(np.abs(r).max()), steps


def homotopy(target: P.TubeTarget) -> list[P.TubeTarget]:
    """Targets from the cylinder of the same mean radius to ``target``: a cone opens in small steps from
    the solved cylinder (a direct start on the cone, even a narrow one, ends on collapsed tiles)."""
    if target.kind == "cylinder":
        return [target]
    n = int(np.ceil(target.sector()[2] / CONE_STEP_RAD))
    mid, half = 0.5 * (target.r_bottom + target.r_top), 0.5 * (target.r_bottom - target.r_top)
    cylinder = replace(target, kind="cylinder", r_bottom=mid, r_top=mid)
    return [cylinder] + [
        replace(target, r_bottom=mid + lam * half, r_top=mid - lam * half)
        for lam in np.linspace(1.0 / n, 1.0, n)
    ]


def _stage(prob: _TubeProblem, req: TubeRequest) -> tuple[np.ndarray, dict]:
    """Both stages from ``prob.X0``: the penalised least squares, then the projection."""
    sol = least_squares(
        lambda f: prob.stacked(f)[0],
        prob.X0.ravel(),
        jac=lambda f: prob.stacked(f)[1],
        method="trf",
        tr_solver="lsmr",
        x_scale=1.0,
        ftol=1e-12,
        xtol=1e-12,
        gtol=1e-12,
        max_nfev=req.max_iter,
    )
    x1 = sol.x.reshape(-1, 2)
    stage1 = float(np.abs(prob.eq_residual(x1)[0]).max())
    x, eq_max, steps = _project(prob, x1, req.tol)
    return x, {
        "equality_max": eq_max,
        "stage1_equality_max": stage1,
        "stage1_evaluations": int(sol.nfev),
        "projection_steps": steps,
    }


def design_tube(req: TubeRequest) -> TubeResult:
    """Design the sheet of a reconfigurable tube (see the module docstring)."""
    req.validate()
    t0, c0 = time.perf_counter(), time.process_time()
    x, steps = None, list[dict]()
    for tgt in homotopy(req.target):
        prob = _TubeProblem(replace(req, target=tgt), start=x)
        x, figures = _stage(prob, req)
        steps.append(figures)
        if (
            figures["equality_max"] > req.tol
        ):  # a continuation step that did not converge ends the run
            break
    assert x is not None, "the homotopy ends on the target itself, so it has a step"
    eq_max = steps[-1]["equality_max"]
    fams = {f.name: float(np.abs(f(x)[0]).max(initial=0.0)) for f in prob.eq}
    fit = prob.fit(x)[0] * prob.geo.scale
    converged = bool(eq_max <= req.tol and len(steps) == len(homotopy(req.target)))
    geo = prob.geo
    report = {
        "status": "converged" if converged else "not converged",
        **steps[-1],
        "tol": req.tol,
        "continuation_steps": len(steps),
        "families": fams,
        "fit_max_mm": float(np.abs(fit).max()),
        "fit_rms_mm": float(np.sqrt(np.mean(fit**2))),
        "ineq_min": {f.name: float(f(x)[0].min()) for f, _ in prob.ineq},
        "scale_mm_per_unit": geo.scale,
        "target": req.target.to_dict(),
        "rigid": req.rigid or req.closed == "cone",
        "closed": req.closed,
        "wall_s": time.perf_counter() - t0,
        "cpu_s": time.process_time() - c0,
    }
    sheet = Pattern(
        nodes=x * geo.scale,
        tiles=prob.std.tiles,
        name=req.name or f"tube {req.rows}x{req.cols} {req.target.kind}",
        lattice={**(prob.std.lattice or {}), "tile_size": geo.scale},
        design={
            "kind": "tube",
            "tube_target": req.target.to_dict(),
            "rigid": report["rigid"],
            "report": report,
        },
    )
    return TubeResult(pattern=with_seam(sheet, prob.seam), converged=converged, report=report)
