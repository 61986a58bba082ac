"""``fabkiri make``'s progress line: only on a terminal; piped stderr keeps make's lines as they are."""

from __future__ import annotations

import io
import sys

import pytest
from fabkiri.api.progress import three_args
from fabkiri.cli import make_cmd
from fabkiri.design.core import stages

STEPS = [  # (stage, share of the steps done, line) as make reports them
    ("make", 0.0, "make: circle at 60 mm, acrylic-3 living, 6x6 tiles (given)"),
    ("design", 0.0, "make: design ..."),
    ("design", 0.25, "make: design ok in 1.0 s"),
    ("cut", 0.25, "make: cut ..."),
    ("cut", 0.5, "make: cut ok in 0.5 s"),
]
LINES = [line for _, _, line in STEPS]


class _Made:
    exit_code = 0

    def summary(self):
        return ["make: circle at 60 mm", "  design: ok"]

    def option_lines(self):
        return ["fabkiri cut circle.json"]


@pytest.fixture
def quick_make(monkeypatch):
    """make's lines without a minute of making."""

    def fake(*args, progress, **kwargs):
        told = three_args(progress)
        for stage, fraction, line in STEPS:
            told(stage, fraction, line)
        return _Made()

    monkeypatch.setattr(make_cmd, "make", fake)


def _args(tmp_path):
    return ["make", "circle", "--size", "60", "--material", "acrylic-3", "-o", tmp_path / "out"]


def test_piped_stderr_is_make_lines_unchanged(quick_make, tmp_path, run_cli):
    code, out, err = run_cli(*_args(tmp_path))
    assert code == 0 and out == "fabkiri cut circle.json\n"
    assert err == "\n".join([*LINES, "make: circle at 60 mm", "  design: ok"]) + "\n"


class _Terminal(io.StringIO):
    def isatty(self) -> bool:
        return True


def test_a_terminal_gets_a_status_line_with_the_eta(quick_make, tmp_path, monkeypatch):
    from fabkiri.cli.main import main

    screen = _Terminal()
    monkeypatch.setattr(sys, "stderr", screen)
    assert main([str(a) for a in _args(tmp_path)]) == 0
    text = screen.getvalue()
    assert all(f"{line}\n" in text for line in LINES)  # every line still there, whole
    assert "make: cut  [2/4] 50 %" in text and "elapsed, ~" in text
    # the status line is cleared before the summary, so the summary starts a clean line
    assert text.endswith("\r\033[Kmake: circle at 60 mm\n  design: ok\n")


NOTE = "fabkiri: design from the flat guess failed (no fit); retrying"


class _Designed:
    exit_code = 0

    def write(self, path, preview=True):
        pass

    def summary(self, path):
        return [f"wrote {path}"]


@pytest.fixture
def quick_design(monkeypatch):
    """design's retry note without a design."""
    from fabkiri.cli import design_cmd

    def fake(request, notify):
        notify(NOTE)
        for k in range(3):  # a stage whose steps are known reports each
            stages.step("continuation", k, 2)
        return _Designed()

    monkeypatch.setattr(design_cmd, "design_by_kind", fake)


def test_design_piped_stderr_is_unchanged(quick_design, tmp_path, run_cli):
    code, out, err = run_cli("design", "--tiles", "4x4", "-o", tmp_path / "p.json")
    assert code == 0 and out == "" and err == f"{NOTE}\nwrote {tmp_path / 'p.json'}\n"


def test_design_on_a_terminal_says_the_time_so_far(quick_design, tmp_path, monkeypatch):
    from fabkiri.cli.main import main

    screen = _Terminal()
    monkeypatch.setattr(sys, "stderr", screen)
    assert main(["design", "--tiles", "4x4", "-o", str(tmp_path / "p.json")]) == 0
    lines = screen.getvalue().splitlines()
    assert lines[0] == NOTE and lines[-1] == f"wrote {tmp_path / 'p.json'}"
    assert lines[1] == "design: designing  0:00 elapsed"
    assert lines[2].startswith("design: continuation 50 %  0:00 elapsed, ~")
    assert lines[3].startswith("design: continuation 100 %  ") and lines[4].startswith(
        "design: done"
    )
    assert len(lines) == 6  # the stage's start is not a line: only steps done say how long is left
