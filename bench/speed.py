"""Measured lines of the solver-speed issue, each in a fresh process (``bench/solve.py`` prints them).

Every line runs ``python3 bench/speed.py WORKER JSON`` with ``PYTHONPATH`` set to the code under test, so
the same worker measures this checkout and a baseline checkout (``--baseline DIR``) in the same run; the
worker prints one JSON object. Workers:

- ``design``: one ``design()`` call through the API; wall and CPU seconds, status, residual, tip fit, and
  the shape conformance ``design`` reports (``design/core/conformance.py``: Hausdorff distance in % of the
  target's size, 1 − IoU);
- ``square_circle``: ``fabkiri design --tiles NxN --rigid --contracted-target 1:square
  --contracted-target 2:circle`` in-process; state 1's distance from a square (relative to its side:
  side lengths, diagonals, each boundary vertex from its side's line) and state 2's least-squares circle
  RMS (geometric fit through the outline's vertices, relative to its radius), from the contracted tiles;
- start-up (``startup``, not a worker): whole-process wall time of a command, median of 5.

The machine is shared: ``load`` is the 1-minute load average when the line started; CPU seconds
(``time.process_time``) scatter less than wall seconds under load.
"""

from __future__ import annotations

import json
import os
import statistics
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve()


def load() -> float:
    return os.getloadavg()[0]


def run_worker(code_dir: Path, worker: str, spec: dict, timeout: float) -> dict:
    """``worker(spec)`` in a fresh process on the code in ``code_dir``."""
    env = {**os.environ, "PYTHONPATH": str(code_dir)}
    t0, l0 = time.perf_counter(), load()
    try:
        out = subprocess.run(
            [sys.executable, str(HERE), worker, json.dumps(spec)],
            cwd=code_dir,
            env=env,
            capture_output=True,
            text=True,
            timeout=timeout,
        )
    except subprocess.TimeoutExpired:
        return {"error": f"timed out after {timeout:.0f} s", "load": l0}
    lines = [ln for ln in out.stdout.splitlines() if ln.startswith("{")]
    if not lines:
        return {"error": (out.stderr.strip().splitlines() or ["no output"])[-1], "load": l0}
    return {**json.loads(lines[-1]), "load": l0, "process_s": time.perf_counter() - t0}


def startup(code_dir: Path, argv: list[str], k: int = 5, bytecode: str | None = None) -> dict:
    """Median wall time of ``python3 -m fabkiri.cli.main ARGV`` as a whole process, and its CPU time
    (user + system, from ``getrusage`` of the children).

    ``bytecode``: a directory for compiled bytecode (``PYTHONPYCACHEPREFIX``, one unmeasured run first), as an
    installed package has it; without it, under ``PYTHONDONTWRITEBYTECODE`` (set on the shared box), every
    run compiles fabkiri's modules from source (about 0.1 CPU s of an 8x8 design)."""
    import resource

    env = {**os.environ, "PYTHONPATH": str(code_dir)}
    if bytecode:
        env.pop("PYTHONDONTWRITEBYTECODE", None)
        env["PYTHONPYCACHEPREFIX"] = bytecode
        subprocess.run(
            [sys.executable, "-m", "fabkiri.cli.main", *argv],
            cwd=code_dir,
            env=env,
            capture_output=True,
        )
    times, cpus, l0 = [], [], load()
    for _ in range(k):
        r0 = resource.getrusage(resource.RUSAGE_CHILDREN)
        t0 = time.perf_counter()
        subprocess.run(
            [sys.executable, "-m", "fabkiri.cli.main", *argv],
            cwd=code_dir,
            env=env,
            capture_output=True,
        )
        times.append(time.perf_counter() - t0)
        r1 = resource.getrusage(resource.RUSAGE_CHILDREN)
        cpus.append(r1.ru_utime - r0.ru_utime + r1.ru_stime - r0.ru_stime)
    return {
        "median": statistics.median(times),
        "fastest": min(times),
        "cpu": statistics.median(cpus),
        "load": l0,
    }


# ------------------------------------------------------------------ workers (run in the child process)
def outline_conformance(pattern, target) -> dict:
    """The shape-conformance measure ``design`` reports and ``--shape-tol`` judges (``design/core/conformance.py``):
    the boundary tips in outline order against the target polygon, Hausdorff distance in % of the target's
    size (the larger side of its bounding box), and 1 - IoU."""
    from fabkiri.design.core.conformance import deployed

    c = deployed(pattern.nodes, pattern.topology, target)
    return {"hausdorff_pct": 100 * c["hausdorff_rel"], "one_minus_iou": c["one_minus_iou"]}


def worker_design(spec: dict) -> dict:
    from fabkiri.design.quad.solve import DesignRequest, design
    from fabkiri.design.targets import lookup as T

    n = spec["n"]
    req = DesignRequest(n, n, T.load_target(spec["target"], 100.0), **spec.get("options", {}))
    t0, c0 = time.perf_counter(), time.process_time()
    res = design(req)
    wall, cpu = time.perf_counter() - t0, time.process_time() - c0
    r = res.report
    fit = r["fit"]["shape"]
    return {
        "wall": wall,
        "cpu": cpu,
        "status": r["status"],
        "eq": r["max_equality_residual"],
        "fit_mm": fit["max_mm"],
        "mode": r["shape_matching"],
        "solver": r["solver"].split(" (")[0],
        **outline_conformance(res.pattern, req.target),
    }


def closed_outline(pattern, state: int) -> np.ndarray:
    """Boundary vertices of a closed state's grid, CCW, from the contracted tiles."""
    from fabkiri.design.quad.constraints import ClosedGrid, Stencils

    st = Stencils.from_pattern(pattern)
    g = ClosedGrid.build(st, state, 0)
    pos = np.zeros((g.n_vertices, 2))
    cnt = np.zeros(g.n_vertices)
    np.add.at(pos, g.vertex.ravel(), np.asarray(pattern.contracted[state]).reshape(-1, 2))
    np.add.at(cnt, g.vertex.ravel(), 1.0)
    M, N = st.rows, st.cols
    idx = np.arange((M + 1) * (N + 1)).reshape(M + 1, N + 1)
    ring = np.concatenate([idx[0, :-1], idx[:-1, -1], idx[-1, :0:-1], idx[:0:-1, 0]])
    return (pos / cnt[:, None])[ring]


def square_error(p: np.ndarray, n: int) -> float:
    c = p[[0, n, 2 * n, 3 * n]]
    sides = np.linalg.norm(np.roll(c, -1, 0) - c, axis=1)
    a = sides.mean()
    err = [
        np.abs(sides - a).max(),
        abs(np.linalg.norm(c[2] - c[0]) - np.sqrt(2) * a),
        abs(np.linalg.norm(c[3] - c[1]) - np.sqrt(2) * a),
    ]
    for k in range(4):
        t = (c[(k + 1) % 4] - c[k]) / sides[k]
        q = p[np.arange(k * n, (k + 1) * n + 1) % (4 * n)] - c[k]
        err.append(np.abs(q[:, 0] * t[1] - q[:, 1] * t[0]).max())
    return float(max(err) / a)


def lsq_circle(p: np.ndarray):
    """Geometric least-squares circle through ``p`` (Gauss-Newton from the algebraic one): centre, radius."""
    sol = np.linalg.lstsq(np.c_[2 * p, np.ones(len(p))], (p * p).sum(1), rcond=None)[0]
    c = sol[:2]
    for _ in range(100):
        d = np.linalg.norm(p - c, axis=1)
        J = -(p - c) / d[:, None]
        step = np.linalg.lstsq(J - J.mean(0), -(d - d.mean()), rcond=None)[0]
        c = c + step
        if np.abs(step).max() < 1e-14 * d.mean():
            break
    return c, float(np.linalg.norm(p - c, axis=1).mean())


def circle_rms(p: np.ndarray) -> float:
    """RMS radial residual of the least-squares circle, relative to its radius."""
    c, R = lsq_circle(p)
    return float(np.sqrt(np.mean((np.linalg.norm(p - c, axis=1) - R) ** 2)) / R)


def worker_square_circle(spec: dict) -> dict:
    import contextlib
    import io
    import tempfile

    from fabkiri.cli.main import main as cli
    from fabkiri.exchange.pattern_json import read_pattern

    n = spec["n"]
    with tempfile.TemporaryDirectory() as tmp:
        out = str(Path(tmp) / "p.json")
        c0 = time.process_time()
        with contextlib.redirect_stderr(io.StringIO()):
            code = cli(
                [
                    "design",
                    "--tiles",
                    f"{n}x{n}",
                    "--rigid",
                    "--contracted-target",
                    "1:square",
                    "--contracted-target",
                    "2:circle",
                    "-o",
                    out,
                ]
            )
        cpu = time.process_time() - c0
        pat = read_pattern(out)
    rep = pat.design["report"]
    checks = rep.get("checks", {})
    return {
        "exit": code,
        "solve_s": rep["time_s"],
        "solve_cpu": rep.get("cpu_s", float("nan")),
        "cpu": cpu,
        "status": rep["status"],
        "eq": rep["max_equality_residual"],
        "square_err": square_error(closed_outline(pat, 1), n),
        "circle_rms": circle_rms(closed_outline(pat, 2)),
        "overlaps": sum(int(v) for k, v in checks.items() if k.startswith("overlaps_")),
        "hausdorff_2": rep.get("conformance", {})
        .get("state_2", {})
        .get("hausdorff_rel", float("nan")),
        "holes": pat.design["options"]["holes"],
        "solver": rep["solver"].split(" (")[0],
    }


WORKERS = {"design": worker_design, "square_circle": worker_square_circle}

if __name__ == "__main__":
    print(json.dumps(WORKERS[sys.argv[1]](json.loads(sys.argv[2]))))
