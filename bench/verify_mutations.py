"""Benchmark: the layout verifier on valid variants and breakages of real cut files.

Cuts three patterns (6x6 standard, 8x8 heart, 8x8 rigid circle) with `fabkiri cut` for tape,
separate and ligament hinges, then writes every kind of valid variant (placement, grouping,
re-save, splitting, rounding, declared units) and of breakage (moved/turned/scaled/mirrored/
swapped/missing tiles, shortened slits, extra cuts, severed ligaments, inch-for-mm, ...) of each
layout as DXF and SVG, with and without manifest.json, and runs `verify_layout` on it.
Goal: 0 false alarms, >= 99.5 % of breakages rejected, every rejection naming a tile or hinge.
Figures of the last full run: docs/cut-files.md, section "Verifier mutation benchmark".

Run: PYTHONPATH=$PWD python3 bench/verify_mutations.py [--quick] [--list]
"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
import time
from collections import defaultdict
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "tests"))

from fabkiri.exchange.pattern_json import read_pattern, write_pattern  # noqa: E402
from fabkiri.mechanics.contract import with_contracted_states  # noqa: E402
from fabkiri.pattern import standard_pattern  # noqa: E402
from fabkiri.verify import verify_layout  # noqa: E402

import layout_mutations as lm  # noqa: E402

PATTERNS = {
    "std6": None,
    "heart-8x8": "../../tests/data/heart-8x8.json",  # test data: it does not print on prusa-mk4
    "circle-8x8-rigid": "circle-8x8-rigid.json",
}
WIDTH = {
    "std6": 250.0,
    "heart-8x8": 500.0,
    "circle-8x8-rigid": 250.0,
}  # closed width every hinge kind can cut
CUT_ARGS = ["--material", "pp-0.5", "--gap", "1", "--sheet", "700x700"]


def scaled(p, width: float):
    """The pattern enlarged so that its closed state 1 is ``width`` mm wide: cut at scale 1, the file's mm are
    the pattern's, so a file without its manifest can be checked too."""
    from dataclasses import replace

    from fabkiri.mechanics.contract import contract

    Y = p.contracted.get(1)
    Y = contract(p, 1).corners if Y is None else Y
    k = width / float(Y[..., 0].max() - Y[..., 0].min())
    return replace(
        p, nodes=p.nodes * k, contracted={s: v * k for s, v in p.contracted.items()}, design={}
    )


HINGES = ("tape", "separate", "ligament")


def make_bases(root: Path, names=PATTERNS) -> list:
    from fabkiri.cli.main import main as cli

    bases = []
    for name in names:
        src = PATTERNS[name]
        pj = root / f"{name}.json"
        p = (
            with_contracted_states(standard_pattern(6, 6, tile_size=10.0))
            if src is None
            else with_contracted_states(read_pattern(ROOT / "templates" / "patterns" / src))
        )
        write_pattern(scaled(p, WIDTH[name]), pj)
        p = read_pattern(pj)
        for h in HINGES:
            args = list(CUT_ARGS)
            d = root / f"{name}-{h}"
            code = cli(
                [
                    "cut",
                    str(pj),
                    "--hinge",
                    h,
                    *args,
                    "--formats",
                    "dxf,svg",
                    "--no-verify",
                    "-o",
                    str(d),
                ]
            )
            if code:
                print(f"  (cannot cut {name} {h}: skipped)")
                continue
            for fmt in ("dxf", "svg"):
                bases.append(lm.load_base(d, fmt, p))
    return bases


def names_culprit(rep) -> bool:
    """A failed check names the tile(s) or hinge at fault (a sheet-wide fault shows on every tile)."""
    return any((c.worst or "").startswith(("tile", "hinge")) for c in rep.failed())


def run(bases, kinds, root: Path, manifests=(True, False), seed: int = 0):
    rows = []
    for bi, b in enumerate(bases):
        for ki, kind in enumerate(kinds):
            for with_m in manifests:
                out = root / f"case-{bi}-{ki}-{int(with_m)}"
                path = lm.make_case(b, kind, out, with_m, seed=seed + ki)
                if path is None:
                    continue
                try:
                    rep = verify_layout(b.pattern, path, manifest=None)
                    ok, failed, named = rep.ok, [c.name for c in rep.failed()], names_culprit(rep)
                except (
                    Exception
                ) as exc:  # a reader refusing the file counts as a rejection, named or not
                    ok, failed, named = False, [f"{type(exc).__name__}: {exc}"[:160]], False
                rows.append(
                    {
                        "base": f"{b.folder.name}.{b.fmt}",
                        "kind": kind.name,
                        "valid": kind.valid,
                        "manifest": with_m,
                        "accepted": ok,
                        "failed": failed,
                        "named": named,
                    }
                )
    return rows


def report(rows) -> dict:
    valid = [r for r in rows if r["valid"]]
    broken = [r for r in rows if not r["valid"]]
    fa = [r for r in valid if not r["accepted"]]
    missed = [r for r in broken if r["accepted"]]
    rejected = [r for r in broken if not r["accepted"]]
    unnamed = [r for r in rejected if not r["named"]]
    print(
        f"valid variants: {len({r['kind'] for r in valid})} kinds, {len(valid)} files; "
        f"false alarms {len(fa)} ({100 * len(fa) / max(1, len(valid)):.2f} %)"
    )
    print(
        f"breakages: {len({r['kind'] for r in broken})} kinds, {len(broken)} files; rejected {len(rejected)} "
        f"({100 * len(rejected) / max(1, len(broken)):.2f} %), missed {len(missed)}; "
        f"rejections not naming a tile or hinge: {len(unnamed)}"
    )
    print("confusion (rows: truth, columns: verdict):")
    print(f"  {'':10s} {'accepted':>9s} {'rejected':>9s}")
    print(f"  {'valid':10s} {len(valid) - len(fa):9d} {len(fa):9d}")
    print(f"  {'broken':10s} {len(missed):9d} {len(rejected):9d}")
    print("per kind (files; valid: accepted, broken: rejected and named):")
    kinds = defaultdict(list)
    for r in rows:
        kinds[(r["valid"], r["kind"])].append(r)
    for (v, k), rs in sorted(kinds.items(), key=lambda kv: (not kv[0][0], kv[0][1])):
        if v:
            print(
                f"  valid   {k:45s} {len(rs):4d} files, {sum(r['accepted'] for r in rs):4d} accepted"
            )
        else:
            rej = [r for r in rs if not r["accepted"]]
            print(
                f"  broken  {k:45s} {len(rs):4d} files, {len(rej):4d} rejected, {sum(r['named'] for r in rej):4d} named"
            )
    for r in unnamed:
        print(
            f"  rejected without naming a tile or hinge: {r['kind']} {r['base']} manifest={r['manifest']}: "
            f"{r['failed'][:3]}"
        )
    for title, bad in (("false alarms", fa), ("missed breakages", missed)):
        by = defaultdict(list)
        for r in bad:
            by[r["kind"]].append(r)
        for k, rs in sorted(by.items(), key=lambda kv: -len(kv[1])):
            ex = rs[0]
            print(
                f"  {title}: {k}: {len(rs)} (e.g. {ex['base']}, manifest={ex['manifest']}: {ex['failed'][:2]})"
            )
    return {
        "valid": len(valid),
        "false_alarms": len(fa),
        "broken": len(broken),
        "missed": len(missed),
        "unnamed": len(unnamed),
    }


def main() -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("--quick", action="store_true", help="one pattern (std6) only")
    ap.add_argument("--list", action="store_true", help="list the kinds and exit")
    ap.add_argument(
        "--keep", metavar="DIR", help="write the cases here instead of a temporary folder"
    )
    args = ap.parse_args()
    if args.list:
        for k in lm.VALID + lm.BROKEN:
            print(f"{'valid ' if k.valid else 'broken'}  {k.fmt:4s} {k.name}")
        return 0
    t0 = time.perf_counter()
    with tempfile.TemporaryDirectory() as tmp:
        root = Path(args.keep) if args.keep else Path(tmp)
        root.mkdir(parents=True, exist_ok=True)
        bases = make_bases(root, ["std6"] if args.quick else PATTERNS)
        t1 = time.perf_counter()
        rows = run(bases, lm.VALID + lm.BROKEN, root)
        t2 = time.perf_counter()
    print(
        f"{len(bases)} base layouts (cut in {t1 - t0:.1f} s), {len(rows)} verify runs in {t2 - t1:.1f} s "
        f"(load average {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores)"
    )
    s = report(rows)
    goal = (
        s["false_alarms"] == 0
        and s["broken"]
        and (s["broken"] - s["missed"]) / s["broken"] >= 0.995
        and s["unnamed"] == 0
    )
    print(
        f"goal (0 false alarms, >= 99.5 % rejected, every rejection naming a tile or hinge): "
        f"{'met' if goal else 'NOT met'}"
    )
    return 0 if goal else 1


if __name__ == "__main__":
    sys.exit(main())
