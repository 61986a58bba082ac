"""A node array measured against a ``DesignProblem``'s families (tile units: the initial tile edge is 1).

What both solvers and the routes ask of a point: the inequality values, the mean tile edge, each equality's
and hard fit's worst residual, the objective, whether the point is acceptable and, where not, why.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from ...pattern import geometry
from .objective import energy

if TYPE_CHECKING:
    from .problem import DesignProblem


def _ineq_values(prob: DesignProblem, X: np.ndarray) -> np.ndarray:
    return np.concatenate([f.residual(X) for f in prob.of("ineq")])


def _mean_edge(prob: DesignProblem, X: np.ndarray) -> float:
    return geometry.mean_edge_length(X[prob.st.tiles])


def family_residuals(prob: DesignProblem, X: np.ndarray, L: float) -> dict:
    out = {}
    for f in prob.families:
        if f.kind == "eq" or (f.kind == "fit" and not f.meta.get("soft")):
            r = f.residual(X)
            out[f.name] = float(np.abs(r).max(initial=0.0)) / L**f.dim
    return out


def _objective(prob: DesignProblem, X: np.ndarray) -> float:
    """Σ fit² + w E_reg: what both solvers minimise over the feasible set."""
    return sum(energy(f, X) for f in prob.of("fit")) + prob.req.reg_weight * sum(
        energy(f, X) for f in prob.of("reg")
    )


def _acceptable(prob: DesignProblem, X: np.ndarray) -> bool:
    res = family_residuals(prob, X, _mean_edge(prob, X))
    worst = max((res[f.name] for f in prob.of("eq")), default=0.0)
    return worst <= prob.req.tol and float(_ineq_values(prob, X).min(initial=0.0)) >= 0.0


def _why_not(prob: DesignProblem, X: np.ndarray) -> str:
    """The worst equality family and the smallest inequality, for the log."""
    res = family_residuals(prob, X, _mean_edge(prob, X))
    eq = max(((res[f.name], f.name) for f in prob.of("eq")), default=(0.0, "none"))
    g = min(
        ((float(f.residual(X).min(initial=0.0)), f.name) for f in prob.of("ineq")),
        default=(0.0, "none"),
    )
    return f"worst equality {eq[1]} {eq[0]:.1e}, smallest inequality {g[1]} {g[0]:.1e}"
