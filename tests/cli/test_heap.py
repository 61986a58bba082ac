"""The CLI's design process keeps freed large blocks in the C heap (``cli/heap.py``); a library caller's
process and other commands are left alone."""

from __future__ import annotations

import subprocess
import sys

import numpy  # noqa: F401  (a library caller's process: numpy loaded before the CLI's main)
import pytest
from fabkiri.cli import heap
from fabkiri.cli import main as cli

glibc = pytest.mark.skipif(
    not sys.platform.startswith("linux")
    or "glibc" not in " ".join(__import__("platform").libc_ver()),
    reason="mallopt is glibc's",
)
# a small design command, its output file appended
DESIGN8 = "design --tiles 8x8 --target circle --rigid --no-preview -o".split()


@glibc
def test_a_design_process_keeps_freed_blocks_before_its_modules_load(tmp_path):
    code = (
        "import sys\nfrom fabkiri.cli import heap\ncalls = []\norig = heap.keep_freed_memory\n"
        "def spy(command):\n"
        "    calls.append((command, 'numpy' in sys.modules, orig(command)))\n"
        "    return calls[-1][-1]\n"
        "heap.keep_freed_memory = spy\n"
        "from fabkiri.cli.main import main\n"
        f"main({[*DESIGN8, str(tmp_path / 'p.json')]!r})\n"
        "print(calls)\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip().splitlines()[-1] == "[('design', False, True)]"
    assert (tmp_path / "p.json").exists()


def test_only_the_commands_that_make_large_arrays_and_not_a_library_caller(monkeypatch, tmp_path):
    assert not heap.keep_freed_memory("cut") and not heap.keep_freed_memory(None)
    calls = []
    monkeypatch.setattr(heap, "keep_freed_memory", calls.append)
    # this test process has numpy loaded: a library caller's heap is its own
    assert "numpy" in sys.modules
    cli.main([*DESIGN8, str(tmp_path / "p.json")])
    assert calls == [] and (tmp_path / "p.json").exists()
