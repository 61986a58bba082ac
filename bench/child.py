"""One CLI run of a checkout as its own process, timed: the helper the whole-process benches share."""

from __future__ import annotations

import os
import resource
import subprocess
import sys
import time
from dataclasses import dataclass
from pathlib import Path


@dataclass
class Child:
    code: int  # -9: timed out
    cpu_s: float  # the child's user + system CPU
    wall_s: float
    stdout: str
    stderr: str


def run_cli(repo: Path, *args: str, timeout: float) -> Child:
    """``fabkiri ARGS`` from ``repo`` (its package first on sys.path), one BLAS thread."""
    env = {**os.environ, "PYTHONPATH": str(repo), "OMP_NUM_THREADS": "1"}
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    try:
        p = subprocess.run(
            [sys.executable, "-m", "fabkiri.cli.main", *args],
            capture_output=True,
            text=True,
            env=env,
            cwd=repo,  # `python -m` puts the working folder first on sys.path: the repo's own package
            timeout=timeout,
        )
        code, out, err = p.returncode, p.stdout, p.stderr
    except subprocess.TimeoutExpired:
        code, out, err = -9, "", f"timed out after {timeout:g} s"
    wall = time.perf_counter() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return Child(code, cpu, wall, out, err)
