"""The last guess of a non-rigid design below 32x32 tiles: the rigid family (``VIA_RIGID_INIT``)."""

from __future__ import annotations

import json

import pytest
from fabkiri.design.quad.solve import VIA_RIGID_INIT, DesignRequest, design, via_rigid_applies
from fabkiri.design.targets import lookup as T


def test_a_non_rigid_request_with_the_rigid_guess_is_answered_by_the_rigid_family():
    req = DesignRequest(8, 8, T.load_target("ellipse", 100.0), init=VIA_RIGID_INIT)
    assert via_rigid_applies(req) and not via_rigid_applies(DesignRequest(8, 8, req.target))
    res = design(req)
    assert res.converged and res.report["solver"].endswith("for a non-rigid request")
    assert (
        res.report["max_equality_residual"] <= 1e-10
    )  # every non-rigid equality, checked on the member
    assert (
        res.pattern.design["options"]["rigid"] is False
    )  # stored as the non-rigid request it answers


@pytest.mark.slow
def test_the_cli_tries_the_rigid_family_last_only_when_the_other_guesses_miss(tmp_path, run_cli):
    code, out, _ = run_cli(
        "design",
        "--tiles",
        "6x6",
        "--target",
        "circle",
        "--json",
        "--no-preview",
        "-o",
        tmp_path / "a.json",
    )
    assert code == 0 and VIA_RIGID_INIT not in [a["init"] for a in json.loads(out)["attempts"]]
    # a tolerance no 4x4 design meets: every guess is tried, the rigid family last
    code, out, _ = run_cli(
        "design",
        "--tiles",
        "4x4",
        "--target",
        "circle",
        "--shape-tol",
        "0.1%",
        "--json",
        "--no-preview",
        "-o",
        tmp_path / "b.json",
    )
    assert code == 1 and [a["init"] for a in json.loads(out)["attempts"]][-1] == VIA_RIGID_INIT
