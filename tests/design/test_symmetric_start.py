"""A mirrored coarse level fitted with the outline rows whose fine start has closed-state tiles overlapping is
fitted tips only, from rescaled, instead (``DesignProblem._tips_level``; issue #37: the symmetric star's 32x32
design from its outline-fitted 16x16 level ran the contact rows twice, 313 iterations against 59)."""

from __future__ import annotations

import pytest
from fabkiri.design.core.request import DesignRequest
from fabkiri.design.quad.rigid.contact import ClosedContact
from fabkiri.design.quad.solve import design_problem
from fabkiri.design.targets.lookup import load_target


@pytest.mark.slow
def test_the_symmetric_stars_fine_start_has_its_closed_states_apart():
    """The star's 32x32 chain (y mirror): main's outline-fitted 16x16 level handed the fine level a start whose
    closed state 2 overlapped by 0.10 tile; here the level is the tips-only one and the start is apart."""
    star = load_target("star", 100.0)
    req = DesignRequest(32, 32, star, rigid=True, symmetry="y", init="coarse", solver="reduced")
    prob = design_problem(req)
    level = prob.coarse
    assert level is not None and level["used"] and level["fit"] == "tips"
    assert level["outline_start_overlaps"]
    assert prob.start_member is not None
    fam, S = prob.rigid_family, prob.start_member[0] / prob.L0
    gaps = ClosedContact(fam, prob.st).values((fam.grid(S), fam.Y @ S))
    assert min(float(g.min()) for g in gaps.values()) > 0.0


def test_a_level_whose_start_is_apart_keeps_the_outline_rows():
    """The drop's 8x8 level of its 16x16 chain: its fine start touches (5e-5 tile deep, inside the contact rows'
    margin), so the outline-fitted level stays."""
    from ..conftest import REPO

    drop = load_target(str(REPO / "bench" / "data" / "drop.csv"), size=100.0)
    req = DesignRequest(16, 16, drop, rigid=True, symmetry="y", init="coarse", solver="reduced")
    level = design_problem(req).coarse
    assert level is not None and level["fit"] == "outline"
    assert "outline_start_overlaps" not in level
