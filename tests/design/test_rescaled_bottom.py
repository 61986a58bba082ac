"""A large rigid-family design of a target with no mirror bottoms its coarse chain at a 32x32 level from rescaled
(with the outline rows) and is finished whatever its miss (``quad/chain.py``, ``design_minimax._rescaled_bottom``;
issue #37: the bean's 48x48, 64x64 and 96x96 designs from the halving chain, 0.238, 0.234 and 0.173 % of the size,
sat above its 32x32 design's 0.148 %). The rule's decision is tested on the request alone, the level stubbed."""

from __future__ import annotations

from types import SimpleNamespace

import pytest
from fabkiri.api.design_minimax import FINISH_ABOVE, FINISH_FLOOR, applies, gate, threshold
from fabkiri.api.design_report import DesignAttempt as Attempt
from fabkiri.design.core.request import DesignRequest
from fabkiri.design.quad.problem import DesignProblem
from fabkiri.design.targets.lookup import load_target

from ..conftest import REPO


class _Level(Exception):
    """Raised by the stubbed coarse level with the sub-request it was asked."""


def _level_asked(monkeypatch, req: DesignRequest) -> DesignRequest:
    """The sub-request ``req``'s coarse-to-fine start asks its coarse level for (the level not designed)."""

    def stub(self, sub):
        raise _Level(sub)

    monkeypatch.setattr(DesignProblem, "_coarse_level", stub)
    with pytest.raises(_Level) as asked:
        DesignProblem(req, whole_design=lambda r, p: None)  # type: ignore[arg-type,return-value]
    return asked.value.args[0]


def _target(name: str):
    path = REPO / "bench" / "data" / f"{name}.csv"
    return load_target(str(path) if path.exists() else name, size=100.0)


@pytest.mark.parametrize(
    ("n", "level", "init"), [(48, 32, "rescaled"), (64, 32, "rescaled"), (96, 48, "coarse")]
)
def test_the_beans_chain_bottoms_at_a_32x32_level_from_rescaled(monkeypatch, n, level, init):
    """The bean has no mirror about either axis: 48 and 64 from a 32x32 level from rescaled with the outline rows,
    96 from a 48x48 level tips only (whose own level is that 32x32 one). A free request answered by the rigid
    family asks the same rigid request."""
    sub = _level_asked(monkeypatch, DesignRequest(n, n, _target("bean"), rigid=True, init="coarse"))
    assert (sub.rows, sub.cols, sub.init, sub.outline) == (level, level, init, init == "rescaled")


@pytest.mark.parametrize(
    ("name", "n", "rigid"),
    [
        ("heart", 48, True),  # one mirror (y)
        ("drop", 64, True),
        ("peanut", 48, True),  # two
        ("circle", 64, True),  # issue #36's rows
        ("bean", 32, True),  # under 48 tiles a side
        ("bean", 48, False),  # the full problem's own chain (not the rigid family's)
    ],
)
def test_a_mirrored_target_or_a_smaller_lattice_keeps_the_halving_chain(
    monkeypatch, name, n, rigid
):
    sub = _level_asked(
        monkeypatch,
        DesignRequest(
            n, n, _target(name), rigid=rigid, init="coarse", solver="auto" if rigid else "full"
        ),
    )
    assert (sub.rows, sub.init, sub.outline) == (
        n // 2,
        "coarse" if n // 2 >= 16 else "rescaled",
        False,
    )


def test_a_rigid_design_from_the_rescaled_bottom_is_finished_whatever_its_miss():
    """A design from that chain under the rigid gate (the bean's 96x96 one from a tips-only bottom: 0.045 %, its
    48x48 level 0.36 %, within the shape tolerance, above its 64x64 design's 0.040 %) is finished (gate 0, the
    cheaper steps), and not redesigned from refitted levels (``_redesigned``, the halving chain's case). The same design from a halving chain keeps the rigid gate
    (issue #36's circles). The free one from that chain gets the cheaper steps, from a halving chain the full ones."""
    from fabkiri.api import design_minimax as dm

    def designed(level: dict) -> Attempt:
        report = {"conformance": {"deployed": {"hausdorff_rel": 0.00045}}, "coarse": level}
        return Attempt(None, report, [], True, {})

    level = {"fit": "tips", "hausdorff_rel": 0.0036, "used": True}
    for n in (48, 64, 96):
        rigid = DesignRequest(n, n, _target("bean"), rigid=True)
        chained = designed({**level, "rescaled_bottom": 32})
        assert gate(rigid, chained.report) == 0.0 and applies(rigid, {}, chained)
        assert not dm._redesigned(rigid, chained.report)
        assert gate(rigid, designed(level).report) == max(
            FINISH_FLOOR, threshold(FINISH_ABOVE, rigid)
        )
    # the free design of that chain takes the cheaper steps too (the full ones stalled at 0.043 % at 96x96)
    free = DesignRequest(96, 96, _target("bean"))
    assert dm._cheap(free, designed({**level, "rescaled_bottom": 32}).report)
    assert not dm._cheap(free, designed(level).report)


class _Mapped(Exception):
    """Raised by the stubbed resampling with the coarse level it was given."""


@pytest.mark.parametrize(
    ("bottom", "halving", "kept"),
    [
        ((True, 0.010), (True, 0.020), 32),  # converged and closer: the rescaled bottom
        ((True, 0.030), (True, 0.020), 24),  # further than the halving level: main's chain
        ((False, 0.010), (True, 0.020), 24),  # unconverged (the rotated heart's case): main's chain
        ((True, 0.030), (False, 0.020), 32),  # the halving level unconverged: the bottom
    ],
)
def test_the_rescaled_bottom_is_kept_only_where_it_converged_and_fits_closer(
    monkeypatch, bottom, halving, kept
):
    """The guard: a 48x48 bean's 32x32 level from rescaled is the start only where it converged and misses the
    target by less than the halving chain's 24x24 level; else the design starts from that level, main's way (a
    heart rotated by 20 degrees lost its 48x48 design from an unconverged bottom). Levels stubbed."""
    asked: list[tuple[int, str, bool]] = []

    def level(self, sub):
        asked.append((sub.rows, sub.init, sub.outline))
        ok, h = bottom if sub.init == "rescaled" else halving
        res = SimpleNamespace(converged=ok, pattern=SimpleNamespace(nodes=sub.rows), report={})
        return res, {"fit": "outline" if sub.outline else "tips", "hausdorff_rel": h}

    def mapped(self, coarse, nodes, cheap=False):
        raise _Mapped(nodes)

    monkeypatch.setattr(DesignProblem, "_coarse_level", level)
    monkeypatch.setattr(DesignProblem, "_rigid_refinement", mapped)
    with pytest.raises(_Mapped) as taken:
        DesignProblem(
            DesignRequest(48, 48, _target("bean"), rigid=True, init="coarse"),
            whole_design=lambda r, p: None,  # type: ignore[arg-type,return-value]
        )
    assert taken.value.args[0] == kept
    # the halving level designed once: beside a converged bottom, or as the start
    assert asked[0] == (32, "rescaled", True)
    assert asked[1:] == [(24, "coarse", False)]
