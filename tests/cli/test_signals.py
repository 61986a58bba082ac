"""A killed ``fabkiri`` loses nothing: TERM mid-write undoes the move, Ctrl-C at start-up is one line."""

from __future__ import annotations

import os
import subprocess
import sys

import pytest
from fabkiri.cli import main as cli_main

from ..conftest import REPO

# kill the process right after the writer moved the old output aside (the window a TERM can hit)
KILLED_MID_MOVE = """
import os, signal, sys
real = os.replace
def replace(src, dst):
    real(src, dst)
    if os.path.basename(str(dst)).startswith("old-"):
        os.kill(os.getpid(), signal.SIGTERM)
os.replace = replace
sys.argv = ["fabkiri", "new", "--tiles", "2x2", "-o", "p.json"]
from fabkiri.cli.main import entry
entry()
"""


def test_a_kill_during_the_move_puts_the_old_output_back(tmp_path):
    (tmp_path / "p.json").write_text("the previous output")
    env = {**os.environ, "PYTHONPATH": str(REPO)}
    run = subprocess.run(
        [sys.executable, "-c", KILLED_MID_MOVE],
        cwd=tmp_path,
        env=env,
        capture_output=True,
        text=True,
        timeout=120,
    )
    # was: killed with p.json gone and the old one left in a hidden .fabkiri-*.tmp folder
    assert run.returncode == 130, run.stderr
    assert run.stderr.strip() == "fabkiri: interrupted; nothing was written"
    assert sorted(os.listdir(tmp_path)) == ["p.json"]
    assert (tmp_path / "p.json").read_text() == "the previous output"


def test_ctrl_c_during_start_up_is_one_line(monkeypatch, capsys):
    def interrupted(*args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr(cli_main, "build_parser", interrupted)
    monkeypatch.setattr(sys, "argv", ["fabkiri", "info", "x.json"])
    with pytest.raises(SystemExit) as exit_:
        cli_main.entry()  # was: a KeyboardInterrupt traceback of the imports
    assert exit_.value.code == 130
    assert capsys.readouterr().err.strip() == "fabkiri: interrupted; nothing was written"
