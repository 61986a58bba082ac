"""PrusaSlicer driven from the tests: slice a written 3MF the way a maker would and read the G-code."""

from __future__ import annotations

import subprocess
from pathlib import Path

# words in PrusaSlicer's log that mean the 3MF does not slice as written
SLICER_WARNINGS = ("empty layer", "outside", "could not fit", "not printable", "error")


def slice_3mf(model: Path, gcode: Path) -> str:
    """Slice ``model`` to ``gcode`` with PrusaSlicer's command line; assert it exits 0 with no warning
    in its log (trace, debug and info lines left out) and return the G-code text."""
    proc = subprocess.run(
        ["prusa-slicer", "--export-gcode", str(model), "-o", str(gcode)],
        capture_output=True,
        text=True,
        timeout=1800,
    )
    log = "\n".join(
        ln
        for ln in (proc.stdout + proc.stderr).splitlines()
        if "[trace]" not in ln and "[debug]" not in ln and "[info]" not in ln
    )
    assert proc.returncode == 0, log[-2000:]
    bad = [w for w in SLICER_WARNINGS if w in log.lower()]
    assert not bad, log[-2000:]
    return gcode.read_text()
