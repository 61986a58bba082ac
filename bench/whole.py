"""Whole-process times of the commands a person runs (issue #36), this checkout against a baseline.

Every row is one ``python -m fabkiri.cli.main ARGV -o TMP`` process, run ``--runs`` times (default 3) on
this checkout and, with ``--baseline DIR``, on that checkout too, in turns (baseline, this, baseline, ...)
so both see the same load. Each process gets ``PYTHONPATH`` set to a copy of the checkout's package with
its bytecode compiled before timing, as an installed package has it (see ``compiled_copy``); the process
runs in the checkout (relative input paths).

Per row and checkout the table gives the median wall seconds, the median CPU seconds (user + system of
the process and its children, ``getrusage`` of the reaped children), the exit code, and for a design the
solver's own time (``report.time_s_total``: every attempt's, retries included), its max equality
residual and the deployed outline's Hausdorff distance to the target (% of its size), read from the
written ``pattern.json``. ``ratio`` is baseline / this (above 1:
this checkout is faster). ``load`` is the 1-minute load average when the row started: on a loaded
machine read the CPU columns, which scatter less than wall time.

    PYTHONPATH=. python3 bench/whole.py [--baseline /work/wt/base] [--runs 3] [--rows help,design8,...]
                                        [--with-material] [--json out.json]

Rows (``--rows``, comma-separated names; default all but ``material``): see ``ROWS``.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


@dataclass(frozen=True)
class Row:
    name: str
    argv: tuple[str, ...]  # after ``fabkiri``; ``-o OUT`` is appended
    out: str  # what -o names: a file (``p.json``) or a folder (``files``)
    goal_s: float | None  # the issue's goal, quiet machine, wall seconds
    issue_s: float | None  # the issue's figure on its quiet machine
    default: bool = True


ROWS = [
    Row("help", ("--help",), "", None, 0.044),
    Row(
        "design8",
        ("design", "--tiles", "8x8", "--target", "circle", "--rigid", "--no-preview"),
        "p.json",
        0.3,
        0.60,
    ),
    Row(
        "heart16",
        ("design", "--tiles", "16x16", "--target", "heart", "--no-preview"),
        "p.json",
        1.0,
        2.41,
    ),
    Row(
        "design64",
        ("design", "--tiles", "64x64", "--target", "circle", "--rigid", "--no-preview"),
        "p.json",
        2.0,
        4.87,
    ),
    Row(
        "design128",
        ("design", "--tiles", "128x128", "--target", "circle", "--rigid"),
        "p.json",
        5.0,
        13.9,
    ),
    Row("cut8", ("cut", "templates/patterns/standard-8x8.json"), "files", 1.0, 1.89),
    Row(
        "print8",
        ("print", "templates/patterns/circle-8x8-rigid.json", "--scale", "2"),
        "files",
        2.0,
        3.38,
    ),
    Row(
        "print32",
        ("print", "tests/data/circle-32x32-rigid.json", "--style", "tiles-and-strips"),
        "files",
        5.0,
        11.5,
    ),
    Row(  # no shipped 32x32 pattern prints in tiles-and-strips (print32 times that refusal): the one it advises
        "print32strips",
        (
            "print",
            "tests/data/circle-32x32-rigid.json",
            "--style",
            "strips",
            "--scale",
            "auto",
        ),
        "files",
        None,
        None,
        default=False,
    ),
    Row(
        "material",  # owned by the fabrication-aware work (helper fabaware); off unless --with-material
        (
            "design",
            "--tiles",
            "16x16",
            "--target",
            "heart",
            "--size",
            "200",
            "--material",
            "acrylic-3",
        ),
        "p.json",
        None,
        None,
        default=False,
    ),
]


def load() -> float:
    return os.getloadavg()[0]


def env_for(pkg: Path) -> dict:
    env = dict(os.environ)
    env["PYTHONPATH"] = str(pkg)
    env.pop("PYTHONPYCACHEPREFIX", None)  # the installed libraries' own bytecode is used
    return env


def compiled_copy(code_dir: Path, into: Path) -> Path:
    """A copy of the checkout's package with its bytecode beside it, as an installed package has it (on
    this box ``PYTHONDONTWRITEBYTECODE`` is set and a checkout has none: every run would compile fabkiri
    from source, ~0.1 CPU s). ``templates`` is linked: the package finds it beside itself."""
    import shutil

    into.mkdir(parents=True)
    shutil.copytree(
        code_dir / "fabkiri", into / "fabkiri", ignore=shutil.ignore_patterns("__pycache__")
    )
    (into / "templates").symlink_to(code_dir / "templates")
    subprocess.run([sys.executable, "-m", "compileall", "-q", str(into / "fabkiri")], check=True)
    return into


def design_figures(path: Path) -> dict:
    """Solver time, max equality residual and deployed Hausdorff (% of size) of a written design."""
    try:
        rep = json.loads(path.read_text())["design"]["report"]
    except (OSError, ValueError, KeyError, TypeError):
        return {}
    dep = (rep.get("conformance") or {}).get("deployed") or {}
    return {
        "solve_s": rep.get(
            "time_s_total", rep.get("time_s")
        ),  # every attempt's solve, retries included
        "residual": rep.get("max_equality_residual"),
        "hausdorff_pct": 100 * dep["hausdorff_rel"] if "hausdorff_rel" in dep else None,
        "status": rep.get("status"),
    }


def run_once(code_dir: Path, pkg: Path, row: Row, timeout: float) -> dict:
    """One whole process: its wall seconds and exit code (``timed`` adds its CPU seconds)."""
    with tempfile.TemporaryDirectory(prefix="fabkiri-whole-") as tmp:
        argv = [*row.argv, *(["-o", str(Path(tmp) / row.out)] if row.out else [])]
        t0 = time.perf_counter()
        proc = subprocess.Popen(
            # -P: ``-m`` would put the checkout (cwd, for relative inputs) ahead of PYTHONPATH, and its
            # uncompiled sources would shadow the compiled copy
            [sys.executable, "-P", "-m", "fabkiri.cli.main", *argv],
            cwd=code_dir,
            env=env_for(pkg),
            stdout=subprocess.DEVNULL,
            stderr=subprocess.PIPE,
        )
        try:
            _, err = proc.communicate(timeout=timeout)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.communicate()
            return {"error": f"timed out after {timeout:.0f} s"}
        wall = time.perf_counter() - t0
        # communicate() reaped the child: its rusage is in RUSAGE_CHILDREN; take the difference
        out = {"wall": wall, "exit": proc.returncode, "err": err.decode(errors="replace")[-300:]}
        if row.out == "p.json":
            out.update(design_figures(Path(tmp) / "p.json"))
        return out


def timed(code_dir: Path, pkg: Path, row: Row, timeout: float) -> dict:
    import resource

    r0 = resource.getrusage(resource.RUSAGE_CHILDREN)
    out = run_once(code_dir, pkg, row, timeout)
    r1 = resource.getrusage(resource.RUSAGE_CHILDREN)
    out["cpu"] = r1.ru_utime - r0.ru_utime + r1.ru_stime - r0.ru_stime
    return out


def summary(runs: list[dict]) -> dict:
    ok = [r for r in runs if "error" not in r]
    if not ok:
        return {"error": runs[-1].get("error", "failed")}
    last = ok[-1]
    med = {k: statistics.median(r[k] for r in ok) for k in ("wall", "cpu")}
    solve = [r["solve_s"] for r in ok if r.get("solve_s") is not None]
    return {
        **med,
        "n": len(ok),
        "exit": sorted({r["exit"] for r in ok}),
        "solve_s": statistics.median(solve) if solve else None,
        "residual": last.get("residual"),
        "hausdorff_pct": last.get("hausdorff_pct"),
        "status": last.get("status"),
        "err": "" if last["exit"] == 0 else last["err"].strip().splitlines()[-1:],
    }


def fmt(v, spec: str) -> str:
    return format(v, spec) if v is not None else format("-", ">" + spec.split(".")[0])


def line(name: str, who: str, s: dict, ld: float) -> str:
    if "error" in s:
        return f"{name:<10} {who:<5} {s['error']}"
    return (
        f"{name:<10} {who:<5} {s['wall']:7.2f} {s['cpu']:7.2f} {fmt(s['solve_s'], '7.2f')} "
        f"{fmt(s['residual'], '9.1e')} {fmt(s['hausdorff_pct'], '6.3f')} {','.join(map(str, s['exit'])):>4} "
        f"{ld:5.2f}"
    )


def _note(row, this: dict, base: dict | None) -> str:
    """The line under a row: its command, the ratio to the baseline, the issue's figure and goal."""
    note = f"  {' '.join(row.argv)}"
    if base and "error" not in base and "error" not in this:
        note += f" | ratio base/this: wall {base['wall'] / this['wall']:.2f}x, cpu {base['cpu'] / this['cpu']:.2f}x"
    if row.goal_s is not None:
        note += f" | issue: {row.issue_s} s -> goal < {row.goal_s} s (quiet machine)"
    elif row.issue_s is not None:
        note += f" | issue: {row.issue_s} s, keep"
    return note


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    ap.add_argument(
        "--baseline", type=Path, help="a checkout to time in the same run (e.g. today's main)"
    )
    ap.add_argument(
        "--runs", type=int, default=3, help="runs per row and checkout (median; default 3)"
    )
    ap.add_argument("--rows", help="comma-separated row names: " + ",".join(r.name for r in ROWS))
    ap.add_argument("--with-material", action="store_true", help="add the fabrication-aware row")
    ap.add_argument("--timeout", type=float, default=600.0)
    ap.add_argument("--json", type=Path, help="also write the figures here")
    a = ap.parse_args(argv)
    names = a.rows.split(",") if a.rows else [r.name for r in ROWS if r.default or a.with_material]
    rows = [r for r in ROWS if r.name in names]
    if len(rows) != len(names):
        ap.error(f"unknown row in {names}; rows: {[r.name for r in ROWS]}")
    who = [("this", ROOT)] + ([("base", a.baseline.resolve())] if a.baseline else [])
    tmp = Path(tempfile.mkdtemp(prefix="fabkiri-whole-pkg-"))
    pkgs = {w: compiled_copy(d, tmp / w) for w, d in who}
    print(
        f"# bench/whole.py: {a.runs} run(s) per row and checkout, medians; python {sys.version.split()[0]}, "
        f"{os.cpu_count()} CPU(s), load at start {os.getloadavg()}"
    )
    for w, d in who:
        head = subprocess.run(
            ["git", "-C", str(d), "rev-parse", "--short", "HEAD"], capture_output=True, text=True
        )
        dirty = subprocess.run(
            ["git", "-C", str(d), "status", "--porcelain", "--untracked-files=no"],
            capture_output=True,
            text=True,
        )
        print(
            f"# {w}: {d} at {head.stdout.strip() or '?'}{' + uncommitted changes' if dirty.stdout.strip() else ''}"
        )
    print(
        "# wall/cpu: whole process, s; solve: the solver's own wall time, every attempt (report.time_s_total); resid: max equality "
        "residual; haus%: deployed Hausdorff, % of the target size; load: 1-min load average at the row's start"
    )
    print(
        f"{'row':<10} {'who':<5} {'wall':>7} {'cpu':>7} {'solve':>7} {'resid':>9} {'haus%':>6} {'exit':>4} {'load':>5}"
    )
    results = {}
    for row in rows:
        ld = load()
        runs: dict[str, list[dict]] = {w: [] for w, _ in who}
        for _ in range(a.runs):
            for w, d in reversed(who):  # baseline first in each turn
                runs[w].append(timed(d, pkgs[w], row, a.timeout))
        sums = {w: summary(r) for w, r in runs.items()}
        for w, _ in who:
            print(line(row.name, w, sums[w], ld))
        print(_note(row, sums["this"], sums.get("base")))
        for w, _ in who:
            if sums[w].get("err"):
                print(f"  {w} exit {sums[w]['exit']}: {sums[w]['err']}")
        results[row.name] = {"load": ld, **sums}
        sys.stdout.flush()
    if a.json:
        a.json.write_text(json.dumps(results, indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
