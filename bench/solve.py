"""Benchmark of the inverse-design solver: rigid-deployable circle, n x n tiles.

Prints, in one run, time / iterations / residual / fit for n = 4, 8, 16, 32, 64
(128 with --big) with fabkiri's default solver (``auto``: the closed-form rigid
family, design/quad/rigid/family.py), the full sparse solver on the same problem (``full``
lines, skip with --no-full), and the same problem at n = 4
and 8 with scipy's dense SLSQP (exact Jacobians, the same families, shape
matching as the objective) as the baseline, with the speed ratio: once with the
constraint rows as written (SLSQP stops at once on the dependent rows) and once
("SLSQP-ind") with the rows cut to an independent set by pivoted QR. Both run with
single-threaded BLAS, as ``design`` does (threaded OpenBLAS on a loaded 2-core box
slows SLSQP's dense algebra ~10x, which would flatter the ratio).

From 32x32 tiles both solvers start coarse to fine, as the CLI does for rigid designs (the time includes
the coarse levels); ``--init coarse`` benchmarks that start at every size.

Timing on a shared 2-core VM scatters by ±20 % from run to run, so the runs that take under a second
(fabkiri up to 16x16, SLSQP up to 8x8) are repeated ``--repeat`` times and the median is printed with
the first and fastest run; the speed ratio compares medians. Every run builds its problem afresh
(target, lattice, rigid family); what persists in the process between runs is the memoised tile
topology (``Pattern.topology``), about 0.5 ms at 8x8. SLSQP's time excludes its set-up (problem and
pivoted QR), fabkiri's includes all of ``design()``.

Then the solver-speed lines (``bench/speed.py``, each in a fresh process, with the baseline checkout
given by ``--baseline DIR`` measured in the same run): whole-process start-up of ``fabkiri --help`` and an
8x8 rigid design (median of 5); the full solver (non-rigid heart and ellipse 2:1) through the API with the
tip polygon's conformance to the target; the rigid circle at the large sizes; square->circle outlines.

    PYTHONPATH=. python3 bench/solve.py [--sizes 4,8,16,32,64] [--big] [--init standard] [--no-full]
                                        [--slsqp-sizes 8,16] [--repeat 5] [--baseline /tmp/base]
                                        [--full-sizes 16,32,64] [--square-circle 5,7,9,13,17]
                                        [--rigid-sizes 64,128] [--only startup,full,rigid,square,slsqp,circle]
"""

from __future__ import annotations

import argparse
import statistics
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
from fabkiri.cli.design_cmd import BIG_TILES
from fabkiri.design.quad.solve import (
    DesignRequest,
    _ineq_values,
    design,
    design_problem,
    single_thread_blas,
)
from fabkiri.design.targets import lookup as T
from scipy.optimize import minimize

sys.path.insert(0, str(Path(__file__).resolve().parent))
import speed  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]


def slsqp(n: int, independent: bool, init: str, max_iter: int = 500):
    """The same rigid circle problem with scipy's dense SLSQP.

    As written, the equality set has dependent rows and SLSQP stops at once;
    with ``independent`` the rows are first reduced to a maximal independent
    set at the initial guess (pivoted QR), which is what SLSQP needs.
    """
    req = DesignRequest(n, n, T.load_target("circle", 100.0), rigid=True, init=init)
    prob = design_problem(req)
    shape = prob.X0.shape
    eqs, fits, ineqs = prob.of("eq"), prob.of("fit"), prob.of("ineq")
    reg = prob.of("reg")[0]
    w = req.reg_weight

    def obj(x):
        X = x.reshape(shape)
        f = sum(float(r @ r) for r, _ in (fam(X) for fam in fits))
        rr, _ = reg(X)
        return f + w * float(rr @ rr)

    def obj_grad(x):
        X = x.reshape(shape)
        g = np.zeros(x.size)
        for fam in fits:
            r, J = fam(X)
            g += 2 * (J.T @ r)
        rr, Jr = reg(X)
        return g + 2 * w * (Jr.T @ rr)

    def ceq_all(x):
        return np.concatenate([f(x.reshape(shape))[0] for f in eqs])

    def ceq_j_all(x):
        return np.vstack([f(x.reshape(shape))[1].toarray() for f in eqs])

    keep = slice(None)
    if independent:
        from scipy.linalg import qr

        J0 = ceq_j_all(prob.X0.reshape(-1))
        _, R, piv = qr(J0.T, mode="economic", pivoting=True)
        d = np.abs(np.diag(R))
        keep = np.sort(piv[: int((d > 1e-9 * d.max()).sum())])

    def ceq(x):
        return ceq_all(x)[keep]

    def ceq_j(x):
        return ceq_j_all(x)[keep]

    def cin(x):
        return np.concatenate([f(x.reshape(shape))[0] - prob.margin[f.name] for f in ineqs])

    def cin_j(x):
        return np.vstack([f(x.reshape(shape))[1].toarray() for f in ineqs])

    t0 = time.perf_counter()
    with (
        single_thread_blas()
    ):  # same BLAS threading as design() (single thread), so the ratio compares solvers
        res = minimize(
            obj,
            prob.X0.reshape(-1),
            jac=obj_grad,
            method="SLSQP",
            constraints=[
                {"type": "eq", "fun": ceq, "jac": ceq_j},
                {"type": "ineq", "fun": cin, "jac": cin_j},
            ],
            options={"maxiter": max_iter, "ftol": 1e-12},
        )
    dt = time.perf_counter() - t0
    X = res.x.reshape(shape)
    eq = float(np.abs(ceq_all(res.x)).max())
    fit = max(float(np.abs(f(X)[0]).max()) for f in fits) * prob.L0
    return {
        "time": dt,
        "iterations": int(res.nit),
        "eq": eq,
        "fit_mm": fit,
        "status": res.message,
        "ineq_min": float(_ineq_values(prob, X).min()),
        "success": bool(res.success and eq <= 1e-10),
    }


def ours(n: int, init: str, solver: str = "auto"):
    res = design(
        DesignRequest(n, n, T.load_target("circle", 100.0), rigid=True, init=init, solver=solver)
    )
    r = res.report
    fit = r["fit"]["shape"]
    return {
        "time": r["time_s"],
        "iterations": r["iterations_total"],
        "eq": r["max_equality_residual"],
        "fit_mm": fit["max_mm"],
        "fit_rel_radius": fit["max_mm"] / 50.0,
        "status": r["status"],
        "mode": r["shape_matching"],
        "success": res.converged,
        "solver": r["solver"].split(" (")[0],
    }


def repeated(run, k: int) -> dict:
    """``run()`` ``k`` times: the last result with the median, first and fastest time."""
    times = []
    for _ in range(k):
        r = run()
        times.append(r["time"])
    return {
        **r,
        "time": statistics.median(times),
        "first": times[0],
        "fastest": min(times),
        "runs": k,
    }


def _times(r: dict) -> str:
    return (
        f" [median of {r['runs']}: first {r['first']:.3f}, fastest {r['fastest']:.3f} s]"
        if r["runs"] > 1
        else ""
    )


def _codes(args) -> list[tuple[str, Path]]:
    return [("this", ROOT)] + ([("baseline", Path(args.baseline))] if args.baseline else [])


def _fmt_design(r: dict) -> str:
    if "error" in r:
        return f"ERROR {r['error']} (load {r['load']:.1f})"
    return (
        f"wall {r['wall']:7.2f} s  cpu {r['cpu']:7.2f} s  {r['status']:<11} res {r['eq']:.1e}  "
        f"fit {r['fit_mm']:.3g} mm {r['mode']:<13} Hausdorff {r['hausdorff_pct']:5.2f} %  "
        f"1-IoU {r['one_minus_iou']:.4f}  [{r['solver']}; load {r['load']:.1f}]"
    )


def section_startup(args) -> None:
    print(
        "\nstart-up: whole process, median of 5 (goals: --help < 0.25 s, 8x8 rigid design < 0.6 s); "
        "bytecode compiled once as installed ('source': every run compiles fabkiri, PYTHONDONTWRITEBYTECODE)"
    )
    design8 = [
        "design",
        "--tiles",
        "8x8",
        "--target",
        "circle",
        "--rigid",
        "-o",
        "/tmp/bench-startup.json",
    ]
    cmds = [["--help"], design8, design8 + ["--no-preview"]]  # --no-preview: no PNG drawn
    for label, code in _codes(args):
        with tempfile.TemporaryDirectory(prefix="bench-pyc-") as pyc:
            for argv in cmds:
                shown = " ".join(a for a in argv if a not in ("-o", "/tmp/bench-startup.json"))
                for how, r in (
                    ("bytecode", speed.startup(code, argv, bytecode=pyc)),
                    ("source", speed.startup(code, argv)),
                ):
                    print(
                        f"  {label:<8} fabkiri {shown:<58} {how:<8} median {r['median']:.3f} s (fastest "
                        f"{r['fastest']:.3f}; CPU {r['cpu']:.3f} s; load {r['load']:.1f})",
                        flush=True,
                    )


def section_full(args) -> None:
    sizes = [int(v) for v in args.full_sizes.split(",") if v]
    print(
        "\nfull solver, non-rigid, through the API (goals 16/32/64: < 2 / 10 / 60 s; conformance no worse)"
    )
    for n in sizes:
        for tgt in ("heart", "ellipse"):
            for label, code in _codes(args):
                opts = {} if label == "baseline" else dict(args.full_options)
                r = speed.run_worker(
                    code, "design", {"n": n, "target": tgt, "options": opts}, args.full_timeout
                )
                print(f"  {label:<8} {tgt:<7} {n:>3}  {_fmt_design(r)}", flush=True)


def section_rigid(args) -> None:
    sizes = [int(v) for v in args.rigid_sizes.split(",") if v]
    print("\nrigid circle, coarse to fine as the CLI (goals: 64x64 < 3 s, 128x128 < 20 s)")
    for n in sizes:
        for label, code in _codes(args):
            spec = {"n": n, "target": "circle", "options": {"rigid": True, "init": "coarse"}}
            r = speed.run_worker(code, "design", spec, args.full_timeout)
            print(f"  {label:<8} circle  {n:>3}  {_fmt_design(r)}", flush=True)


def section_square(args) -> None:
    sizes = [int(v) for v in args.square_circle.split(",") if v]
    goal = {5: 0.017, 7: 0.010}
    print(
        "\nsquare->circle (--rigid --contracted-target 1:square --contracted-target 2:circle), CLI in-process; "
        "goals: square to 1e-9 of its side, circle rms <= 1.7 % (5x5), 1.0 % (7x7), < 0.8 % from 9x9, "
        "solve < 1 s"
    )
    for n in sizes:
        for label, code in _codes(args):
            r = speed.run_worker(code, "square_circle", {"n": n}, args.full_timeout)
            if "error" in r:
                print(f"  {label:<8} {n:>3}  ERROR {r['error']}")
                continue
            ok = (
                r["square_err"] <= 1e-9
                and r["circle_rms"] <= goal.get(n, 0.008)
                and r["solve_s"] < 1.0
            )
            print(
                f"  {label:<8} {n:>3}  exit {r['exit']} {r['status']:<11} res {r['eq']:.1e}  square error "
                f"{r['square_err']:.2e}  circle rms {r['circle_rms']:.3%}  Hausdorff {r.get('hausdorff_2', float('nan')):.2%}  "
                f"solve {r['solve_s']:.3f} s (CPU {r.get('solve_cpu', float('nan')):.3f} s)  CLI cpu {r['cpu']:.2f} s  overlaps {r['overlaps']}  "
                f"{'meets' if ok else 'misses'} the goal  [{r['solver']}, {r.get('holes', 'rhombus')} holes; "
                f"load {r['load']:.1f}]",
                flush=True,
            )


def section_circle(args, sizes, k_small) -> dict:
    print(
        f"rigid-deployable circle (diameter 100 mm), init {args.init}; residual = max equality residual "
        f"relative to the tile size; fit = max |signed distance| of the boundary tips"
    )
    print(
        f"{'solver':<8} {'n':>4} {'status':<12} {'time s':>8} {'iters':>6} {'residual':>10} {'fit mm':>9} "
        f"{'fit/R':>8}  mode"
    )
    mine = {}
    for n in sizes:
        # from BIG_TILES the CLI starts a rigid design coarse to fine (design_cmd.BIG_RIGID_INITS): so does the
        # bench, for both solvers (coarse levels included in the time)
        init = "coarse" if n * n >= BIG_TILES and args.init == "rescaled" else args.init
        r = repeated(lambda n=n, init=init: ours(n, init), k_small if n <= 16 else 1)
        mine[n] = r
        print(
            f"{'fabkiri':<8} {n:>4} {r['status']:<12} {r['time']:>8.3f} {r['iterations']:>6} {r['eq']:>10.2e} "
            f"{r['fit_mm']:>9.3g} {r['fit_rel_radius']:>8.2%}  {r['mode']}; {r['solver']}"
            f"{'' if init == args.init else f', --init {init} (coarse levels included)'}{_times(r)}",
            flush=True,
        )
        if not args.no_full and n * n <= 64 * 64:  # the full solver would take hours at 128x128
            f = ours(n, init, "full")
            print(
                f"{'full':<8} {n:>4} {f['status']:<12} {f['time']:>8.3f} {f['iterations']:>6} {f['eq']:>10.2e} "
                f"{f['fit_mm']:>9.3g} {f['fit_rel_radius']:>8.2%}  {f['mode']}; --solver full"
                f"{'' if init == args.init else f', --init {init}'} "
                f"({f['time'] / r['time']:.1f}x the default's time)",
                flush=True,
            )
    return mine


def section_slsqp(args, mine, k_small) -> None:
    slsqp_sizes = [int(s) for s in args.slsqp_sizes.split(",") if s]
    # as written (dependent rows) SLSQP stops at its first iteration: shown at the small sizes only
    runs = [(n, False) for n in slsqp_sizes if n <= 8] + [(n, True) for n in slsqp_sizes]
    for n, indep in runs:
        if n not in mine and indep:
            mine[n] = repeated(lambda n=n: ours(n, args.init), k_small if n <= 16 else 1)
        b = repeated(
            lambda n=n, indep=indep: slsqp(n, indep, args.init), k_small if indep and n <= 8 else 1
        )
        ok = "converged" if b["success"] else "failed"
        label = "SLSQP-ind" if indep else "SLSQP"
        print(
            f"{label:<8} {n:>4} {ok:<12} {b['time']:>8.3f} {b['iterations']:>6} {b['eq']:>10.2e} "
            f"{b['fit_mm']:>9.3g} {b['fit_mm'] / 50:>8.2%}  ({b['status']}; min inequality {b['ineq_min']:.2e})"
            f"{_times(b)}",
            flush=True,
        )
        if n in mine and indep:
            print(
                f"         speed ratio at n={n}: SLSQP / fabkiri = {b['time'] / mine[n]['time']:.1f}x "
                f"(fabkiri {mine[n]['time']:.3f} s)"
                f"{'' if b['success'] else ' (SLSQP did not even reach the tolerance)'}"
            )


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--sizes", default="4,8,16,32,64")
    ap.add_argument("--big", action="store_true", help="also n = 128")
    ap.add_argument("--init", default="rescaled")
    ap.add_argument("--no-baseline", action="store_true", help="skip SLSQP")
    ap.add_argument(
        "--slsqp-sizes",
        default="8,16",
        help="sizes for the SLSQP reference (16 takes about a minute; the rows as written only at <= 8)",
    )
    ap.add_argument("--no-full", action="store_true", help="skip the full-solver comparison lines")
    ap.add_argument(
        "--repeat",
        type=int,
        default=5,
        help="runs per line for fabkiri up to 16x16 and SLSQP up to 8x8 (the median is printed)",
    )
    ap.add_argument(
        "--baseline",
        help="a checkout of the baseline code (e.g. `git worktree add --detach /tmp/base "
        "main`), measured by the speed lines in the same run",
    )
    ap.add_argument("--full-sizes", default="16,32,64")
    ap.add_argument(
        "--full-timeout", type=float, default=1800.0, help="seconds per speed line before it is cut"
    )
    ap.add_argument("--rigid-sizes", default="64,128")
    ap.add_argument("--square-circle", default="5,7,9,13,17")
    ap.add_argument(
        "--only",
        default="startup,full,rigid,square,circle,slsqp",
        help="sections to run, in this order",
    )
    args = ap.parse_args()
    args.full_options = {}
    k_small = max(1, args.repeat)
    only = args.only.split(",")
    print(f"load average at start: {speed.load():.2f}")
    sections = {
        "startup": section_startup,
        "full": section_full,
        "rigid": section_rigid,
        "square": section_square,
    }
    for name in only:
        if name in sections:
            sections[name](args)
    mine = {}
    if "circle" in only:
        print()
        mine = section_circle(
            args,
            [int(s) for s in args.sizes.split(",") if s] + ([128] if args.big else []),
            k_small,
        )
    if "slsqp" in only and not args.no_baseline:
        section_slsqp(args, mine, k_small)
    print(f"load average at end: {speed.load():.2f}")


if __name__ == "__main__":
    main()
