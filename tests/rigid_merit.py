"""The rigid family's merit of a design problem, as the reduced solver builds it (tests' shared set-up)."""

from __future__ import annotations

from fabkiri.design.quad.rigid import reduced as R


def rigid_merit(prob, reg_weight: float = 1e-3) -> R._Merit:
    """``reduced._Merit`` of ``prob`` (a ``solve.DesignProblem`` with a rigid family), its grid families on."""
    fam = prob.rigid_family
    return R._Merit(
        fam,
        prob.families,
        prob.margin,
        reg_weight,
        grid_families=R.grid_families(fam, prob.st, prob.families),
    )
