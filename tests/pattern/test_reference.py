"""Reference patterns from the additive-kirigami repository (docs/algorithm.md#obj-files)."""

from __future__ import annotations

import numpy as np
from fabkiri.exchange.obj import import_obj
from fabkiri.mechanics import adopt_state_labels, contract_both, describe
from fabkiri.pattern import geometry
from fabkiri.pattern.residuals import state_residuals

from ..conftest import ref


def compact_reconfigurable():
    return adopt_state_labels(
        import_obj(
            ref("compact_reconfigurable_design"),
            [ref("compact_reconfigurable_contracted1"), ref("compact_reconfigurable_contracted2")],
        )
    )


def test_compact_reconfigurable_closed_states_match_reference():
    p = compact_reconfigurable()
    both = contract_both(p)
    for s in (1, 2):
        d = geometry.aligned_distance(both[s].corners, p.contracted[s])
        assert d <= 1e-9 * p.tile_size, (s, d)
        # the other labelling must not match: the two closed states really differ
        assert geometry.aligned_distance(both[3 - s].corners, p.contracted[s]) > 0.1 * p.tile_size
        r = state_residuals(p, s)
        assert r.edge_pairs.max() <= 1e-12 * p.tile_size
        assert np.abs(r.rings).max() <= 1e-12
        assert both[s].max_closure <= 1e-12 * p.tile_size * 10


def test_compact_reconfigurable_names_bow_tie_tile():
    info = describe(compact_reconfigurable())
    assert info.self_intersecting_tiles == [2]
    assert info.closes_both and info.supplied_ok
    assert not info.rigid_deployable
    assert 0.08 < info.hinge_sum_max_rad < 0.09
    assert any(2 in s.wrapped_tiles for s in info.states)


def test_non_contractible_fails_in_both_states(run_cli):
    p = adopt_state_labels(import_obj(ref("non-contractible_design")))
    both = contract_both(p)
    for s in (1, 2):
        assert both[s].max_closure > 0.5 * p.tile_size
    code, out, err = run_cli("info", ref("non-contractible_design"), "--check")
    assert code == 1
    assert "does not close in state 1" in err and "does not close in state 2" in err


def test_contractible_closes_in_one_state_only():
    p = adopt_state_labels(import_obj(ref("contractible_design"), [ref("contractible_contracted")]))
    info = describe(p)
    assert [s.closes for s in info.states] == [True, False]
    assert info.states[0].supplied_matches
    assert info.states[1].max_closure_rel > 0.5
