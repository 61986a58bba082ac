"""Byte-identical outputs: every file a set of commands writes, this checkout against a baseline (issue #34).

A change that only moves code (the library layout) must not change one byte a user gets. This script runs
each command of ``CASES`` as one ``python -m fabkiri.cli.main`` process per checkout (``PYTHONPATH`` set to
that checkout, run from it so relative inputs resolve), writes into a folder per case and checkout, then
compares the two folders file by file, byte for byte. The run times a command reports (the ``time_s`` and
``cpu_s`` fields of its JSON, the "0.08 s" of its messages) differ between any two runs; a file whose only
differences are those is counted apart ("timings only") with the figures masked, never silently. A file
that still differs is run once more on the baseline: if the baseline disagrees with itself, the file is
reported as not deterministic rather than as changed.

    PYTHONPATH=. python3 bench/same_outputs.py --baseline DIR [--cases design8,cut8,...] [--keep DIR]

Prints one line per case (files, identical, differing, exit codes of both) and exits 1 when any file
differs, a file exists on one side only, or the exit codes differ.
"""

from __future__ import annotations

import argparse
import filecmp
import json
import os
import re
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

# name -> argv after ``fabkiri``; OUT is replaced by the case's output path
CASES: dict[str, tuple[str, ...]] = {
    "design8": ("design", "--tiles", "8x8", "--target", "circle", "--rigid", "-o", "OUT/p.json"),
    "heart16": ("design", "--tiles", "16x16", "--target", "heart", "-o", "OUT/p.json"),
    "kagome": (
        "design",
        "--lattice",
        "kagome",
        "--target",
        "circle",
        "--size",
        "180",
        "-o",
        "OUT/k.json",
    ),
    "tube": ("design", "--tube", "cylinder:113.137,135", "--tiles", "6x8", "-o", "OUT/t.json"),
    "export-tube3d": (
        "export",
        "OUT/../../tube/this/t.json",
        "--format",
        "tube3d",
        "-o",
        "OUT/tube3d",
    ),
    "cut8": ("cut", "templates/patterns/standard-8x8.json", "-o", "OUT/cut"),
    "cut-ligament": (
        "cut",
        "templates/patterns/circle-8x8-rigid.json",
        "--hinge",
        "ligament",
        "--material",
        "pp-0.5",
        "--scale",
        "3.5",
        "-o",
        "OUT/cut",
    ),
    "print8": (
        "print",
        "templates/patterns/circle-8x8-rigid.json",
        "--scale",
        "2",
        "-o",
        "OUT/print",
    ),
    "print-pinned": (
        "print",
        "templates/patterns/circle-8x8-rigid.json",
        "--style",
        "pinned",
        "--scale",
        "auto",
        "-o",
        "OUT/print",
    ),
    "deploy": ("deploy", "templates/patterns/circle-8x8-rigid.json", "-o", "OUT/deploy"),
    "export-fold": (
        "export",
        "templates/patterns/circle-8x8.json",
        "--format",
        "fold",
        "-o",
        "OUT/p.fold",
    ),
    "export-obj": (
        "export",
        "templates/patterns/circle-8x8.json",
        "--format",
        "obj",
        "-o",
        "OUT/p.obj",
    ),
    "export-pykirigami": (
        "export",
        "templates/patterns/circle-8x8.json",
        "--format",
        "pykirigami",
        "-o",
        "OUT/pk",
    ),
    "info": ("info", "templates/patterns/circle-8x8-rigid.json", "--json"),
    "verify": ("verify", "templates/patterns/circle-8x8-rigid.json"),
    "coupon": ("coupon", "--material", "acrylic-3", "-o", "OUT/coupon"),
    "report": ("report", "templates/patterns/circle-8x8-rigid.json", "-o", "OUT/report.html"),
    "tolerance": (
        "tolerance",
        "templates/patterns/circle-8x8-rigid.json",
        "--n",
        "50",
        "--seed",
        "1",
        "-o",
        "OUT/tol",
    ),
    "make": ("make", "circle", "--size", "120", "--material", "acrylic-3", "-o", "OUT/make"),
}


def run(tree: Path, argv: tuple[str, ...], keep: Path) -> int:
    """Run in ``keep.parent/out`` (the same path for every checkout, so paths the command echoes or records
    agree), then rename the folder to ``keep``. The command's stdout and stderr are one of its files."""
    out = keep.parent / "out"
    out.mkdir(parents=True)
    args = [a.replace("OUT", str(out)) for a in argv]
    env = {**os.environ, "PYTHONPATH": str(tree), "PYTHONHASHSEED": "0"}
    cmd = [sys.executable, "-m", "fabkiri.cli.main", *args]
    done = subprocess.run(cmd, cwd=tree, env=env, capture_output=True, text=True)
    (out / "stdout.txt").write_text(done.stdout + done.stderr)
    out.rename(keep)
    return done.returncode


TIMING_KEYS = re.compile(r"^(time_s|time_s_total|cpu_s|seconds|wall_s|elapsed_s|t_s)$")
TIMING_TEXT = re.compile(r"\b\d+(\.\d+)?(e-?\d+)? ?(s|ms|CPU s)\b")


def _masked_json(value):
    if isinstance(value, dict):
        return {
            k: ("<time>" if TIMING_KEYS.match(k) else _masked_json(v)) for k, v in value.items()
        }
    if isinstance(value, list):
        return [_masked_json(v) for v in value]
    return value


def masked(path: Path) -> object:
    """The file with its run times masked: JSON without its timing fields, text without "N s"."""
    data = path.read_bytes()
    if path.suffix == ".json":
        try:
            return _masked_json(json.loads(data))
        except ValueError:
            pass
    try:
        return TIMING_TEXT.sub("<time>", data.decode("utf-8"))
    except UnicodeDecodeError:
        return data


def files(folder: Path) -> set[str]:
    return {str(p.relative_to(folder)) for p in folder.rglob("*") if p.is_file()}


def compare(name: str, argv: tuple[str, ...], this: Path, base: Path, work: Path) -> bool:
    a, b = work / name / "this", work / name / "base"
    code_a, code_b = run(this, argv, a), run(base, argv, b)
    fa, fb = files(a), files(b)
    common = sorted(fa & fb)
    differ = [f for f in common if not filecmp.cmp(a / f, b / f, shallow=False)]
    timings = [f for f in differ if masked(a / f) == masked(b / f)]
    differ = [f for f in differ if f not in timings]
    unsteady = []
    if differ:  # does the baseline agree with itself?
        c = work / name / "base2"
        run(base, argv, c)
        unsteady = [
            f
            for f in differ
            if not (c / f).exists() or not filecmp.cmp(b / f, c / f, shallow=False)
        ]
        differ = [f for f in differ if f not in unsteady]
    only = sorted(fa ^ fb)
    ok = not differ and not only and code_a == code_b
    print(
        f"{name:13s} exit {code_a}/{code_b}  files {len(common):3d}"
        f"  identical {len(common) - len(differ) - len(unsteady) - len(timings):3d}"
        f"  timings only {len(timings)}"
        f"  differ {len(differ)}  not deterministic {len(unsteady)}  one side only {len(only)}"
        f"  {'ok' if ok else 'CHANGED'}"
    )
    for f in differ + only:
        print(f"    {f}")
    for f in unsteady:
        print(f"    (varies between baseline runs) {f}")
    for f in timings:
        print(f"    (run times only) {f}")
    return ok


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--baseline", type=Path, required=True, help="checkout to compare against")
    ap.add_argument("--cases", default=",".join(CASES), help="comma-separated names")
    ap.add_argument(
        "--keep", type=Path, help="write the outputs here instead of a temporary folder"
    )
    a = ap.parse_args()
    names = a.cases.split(",")
    unknown = [n for n in names if n not in CASES]
    if unknown:
        ap.error(f"unknown case(s) {', '.join(unknown)}; known: {', '.join(CASES)}")
    with tempfile.TemporaryDirectory() as tmp:
        work = a.keep or Path(tmp)
        results = [compare(n, CASES[n], ROOT, a.baseline.resolve(), work) for n in names]
    print(
        f"{sum(results)}/{len(results)} cases the same (byte-identical but for reported run times)"
    )
    return 0 if all(results) else 1


if __name__ == "__main__":
    sys.exit(main())
