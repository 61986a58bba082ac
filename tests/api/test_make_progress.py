"""make says which step each of its lines belongs to from its own loop over MAKE_STEPS, not by
reading its lines back: a step's line that looks like another step's end moves nothing."""

from __future__ import annotations

import fabkiri
import pytest
from fabkiri.api import maker
from fabkiri.api.maker_design import StepRun


@pytest.fixture
def quick_steps(monkeypatch):
    """make's steps without a design: each says a line that reads like a later step's end."""

    def step(name):
        def run(result, plan, say):
            if name == "design":
                result.pattern = fabkiri.standard("6x6")
            say(f"make: report ok (a line of the {name} step)")
            return StepRun(True, 0, f"{name} figures", {}, [])

        return run

    for name in ("design", "cut", "deploy", "report"):
        monkeypatch.setattr(maker, f"_{name}", step(name))


def test_make_reports_each_line_with_its_step_and_share(quick_steps):
    heard: list = []
    result = fabkiri.make(
        "circle", 120, material="acrylic-3", tiles="6x6", progress=lambda *a: heard.append(a)
    )
    assert result.ok and [s.name for s in result.steps] == ["design", "cut", "deploy", "report"]
    assert heard[0][:2] == ("make", 0.0) and heard[0][2].startswith("make: circle at 120 mm")
    inside = [(s, f) for s, f, text in heard if "a line of the" in text]
    assert inside == [("design", 0.0), ("cut", 0.25), ("deploy", 0.5), ("report", 0.75)]
    ends = [(s, f) for s, f, text in heard if text.startswith(f"make: {s} ok in")]
    assert ends == [("design", 0.25), ("cut", 0.5), ("deploy", 0.75), ("report", 1.0)]
    lines: list[str] = []  # a one-argument callback hears the same lines
    fabkiri.make("circle", 120, material="acrylic-3", tiles="6x6", progress=lines.append)
    assert [t.split(" in ")[0] for t in lines] == [t.split(" in ")[0] for _, _, t in heard]
