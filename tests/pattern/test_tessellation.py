"""The tessellation seam: kinds are looked up by name and own arity, holes and fold rules."""

from __future__ import annotations

import json
from dataclasses import replace

import numpy as np
import pytest
from fabkiri.errors import PatternError
from fabkiri.exchange import pattern_json as io
from fabkiri.mechanics.contract import contract
from fabkiri.pattern.kinds import tessellation as tess_module
from fabkiri.pattern.kinds.quad.lattice import standard_pattern
from fabkiri.pattern.kinds.quad.rules import quad_fold_rule
from fabkiri.pattern.kinds.tessellation import Tessellation, kinds, register, tessellation
from fabkiri.pattern.model import Pattern
from fabkiri.pattern.topology import derive_topology


def test_quad_is_the_default_kind_and_owns_the_quad_rules():
    q = tessellation()
    assert (q.kind, q.arity, q.hole_arity, q.states) == ("quad", 4, 4, (1, 2))
    assert q.boundary_sides == ("B", "R", "T", "L") and q.rigid_family
    p = standard_pattern(3, 4)
    assert p.kind == "quad" and p.topology.kind == "quad" and p.topology.arity == 4
    assert "quad" in kinds()


def test_unknown_kind_is_a_one_line_error_naming_the_known_kinds(tmp_path, run_cli):
    with pytest.raises(PatternError, match=r"unknown tessellation kind 'hexagons' \(known: .*quad"):
        tessellation("hexagons")
    p = standard_pattern(2, 2)
    with pytest.raises(PatternError, match="unknown tessellation kind"):
        replace(p, kind="hexagons")
    data = json.loads(io.dumps(p))
    data["kind"] = "hexagons"
    src = tmp_path / "p.json"
    src.write_text(json.dumps(data))
    code, _, err = run_cli(
        "info", src
    )  # in-process: tests/e2e/test_bad_input.py runs the real process's exit path
    assert code == 2 and "unknown tessellation kind 'hexagons'" in err
    assert len(err.strip().splitlines()) == 1


def test_quad_files_do_not_carry_a_kind_and_read_back_as_quad():
    p = standard_pattern(2, 3)
    text = io.dumps(p)
    assert '"kind"' not in text.split('"lattice"')[0]  # the lattice's own "kind" is metadata
    assert io.loads(text).kind == "quad"


def test_tile_arity_comes_from_the_kind():
    p = standard_pattern(2, 2)
    with pytest.raises(PatternError, match="quads \\(4 node indices each\\)"):
        derive_topology(p.tiles[:, :3], len(p.nodes))
    data = json.loads(io.dumps(p))
    data["tiles"][1] = data["tiles"][1][:3]
    with pytest.raises(PatternError, match="tiles/1: .* is not a quad of 4 node indices"):
        io.pattern_from_dict(data)


def _swapped_rule(top, state):
    """The quad rule with the two closed states exchanged: a kind that differs only in its rules."""
    r = quad_fold_rule(top, 3 - state)
    return replace(r, state=state)


@pytest.fixture
def test_kind(monkeypatch):
    """Register a quad-like kind for one test; the registry is restored afterwards."""

    def make(kind: str, **changes) -> Tessellation:
        monkeypatch.setitem(tess_module._KINDS.members, kind, None)  # restored on teardown
        return register(replace(tessellation("quad"), kind=kind, **changes))

    return make


def test_the_topology_and_contraction_use_the_registered_kinds_fold_rule(test_kind):
    test_kind("quad-swapped-test", fold_rule=_swapped_rule)
    p = standard_pattern(4, 5, angle_deg=30.0)
    s = replace(p, kind="quad-swapped-test")
    assert s.topology is not p.topology  # topology is cached per kind
    for state in (1, 2):
        np.testing.assert_array_equal(
            s.topology.fold(state).fold_gap, p.topology.fold(3 - state).fold_gap
        )
        assert np.abs(contract(s, state).corners - contract(p, 3 - state).corners).max() <= 1e-12
    # a non-default kind is written and read
    assert io.loads(io.dumps(s)).kind == "quad-swapped-test"
    with pytest.raises(ValueError, match="state must be 1 or 2"):
        s.topology.fold(3)


def test_a_kind_with_another_arity_is_checked_against_it(test_kind):
    test_kind("triangles-test", arity=3, hole_arity=6, boundary_sides=())
    p = standard_pattern(2, 2)
    with pytest.raises(
        PatternError, match="every tile must be a triangles-test tile of 3 node indices"
    ):
        Pattern(nodes=p.nodes, tiles=p.tiles, kind="triangles-test")
