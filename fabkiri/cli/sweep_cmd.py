"""``fabkiri sweep``: many designs from a sweep file, on a local Dask cluster or an existing one."""

from __future__ import annotations

import argparse
import re
import sys
import time
from typing import TextIO

from ..errors import InputError
from .argtypes import bounded


class Bar:
    """done/failed/running and the ETA on one terminal line (one line per finished job when not a terminal)."""

    def __init__(self, stream: TextIO | None = None):
        stream = (
            sys.stderr if stream is None else stream
        )  # at call time: a default bound at import outlives it
        self.stream, self.tty, self.last = stream, stream.isatty(), None

    def __call__(self, c: dict) -> None:
        finished = c["done"] + c["failed"]
        elapsed = time.perf_counter() - c["started"]
        left = c["total"] - finished
        eta = (
            f"ETA {left * elapsed / finished:.0f} s"
            if finished and left
            else ("done" if not left else "ETA ?")
        )
        width = 24
        fill = int(width * finished / max(1, c["total"]))
        line = (
            f"[{'#' * fill}{'.' * (width - fill)}] {finished}/{c['total']}: {c['done']} done, "
            f"{c['failed']} failed, {c['running']} running, {eta}"
        )
        if self.tty:
            self.stream.write("\r" + line.ljust(78))
            if not left and not c["running"]:
                self.stream.write("\n")
        elif finished != self.last:
            self.stream.write(line + "\n")
        self.last = finished
        self.stream.flush()


def _client(address: str):
    from distributed import Client

    try:
        return Client(address, timeout=10)
    except (OSError, TimeoutError) as exc:
        raise InputError(f"cannot reach the Dask scheduler at {address}: {exc}") from None


def _show_cluster(client, jobs: str) -> None:
    """The jobs and the cluster, once the output folder was accepted and the cluster is up."""
    print(f"fabkiri: {jobs}", file=sys.stderr)
    try:
        import bokeh  # noqa: F401  (the dashboard is served only with bokeh installed)

        note = ""
    except ImportError:
        note = " (install bokeh to serve it)"
    print(
        f"fabkiri: {len(client.nthreads())} Dask workers; dashboard {client.dashboard_link}{note}",
        file=sys.stderr,
    )


def cmd_sweep(args: argparse.Namespace) -> int:
    from ..sweep import load_spec, sweep
    from ..sweep.run import summary

    spec = load_spec(args.file)
    client = _client(args.scheduler) if args.scheduler else None
    try:
        res = sweep(
            spec,
            client,
            output=args.output,
            workers=args.workers,
            job_timeout=args.job_timeout,
            retry_failed=args.retry_failed,
            progress=Bar(),
            on_cluster=lambda c: _show_cluster(
                c, f"{len(spec.jobs)} jobs ({'+'.join(spec.actions)})"
            ),
        )
    except (
        KeyboardInterrupt
    ):  # every finished job is in DIR already: say so (not the CLI's "nothing written")
        print(
            f"\nfabkiri: interrupted; the jobs finished so far are in {args.output}; run the same command "
            f"again to resume",
            file=sys.stderr,
        )
        return 130
    finally:
        if client is not None:
            client.close()
    print(
        f"wrote {args.output}: {len(res.rows)} jobs ({res.ran} run now, {res.skipped} already done) in "
        f"{res.wall_s:.1f} s: {summary(res.rows)}; results.csv, index.html",
        file=sys.stderr,
    )
    for r in res.rows:
        if r.get("error"):  # every failure of every job, one line each
            print(f"fabkiri: job {r['id']} {r['status']}: {r.get('error')}", file=sys.stderr)
    return 1 if res.failed or any(r.get("status") in ("error", "timeout") for r in res.rows) else 0


def _scheduler(text: str) -> str:
    if not re.fullmatch(r"(tcp|tls|ws|wss|inproc)://[^\s/]+(:\d+)?/?", text):
        raise argparse.ArgumentTypeError(f"expected an address like tcp://HOST:PORT, got {text!r}")
    return text


_count = bounded(
    int, lambda v: 1 <= v <= 1024, "expected a whole number", "expected 1 to 1024, got {text!r}"
)
_seconds = bounded(
    float,
    lambda v: 0 < v < 1e7,
    "expected seconds",
    "expected a positive number of seconds, got {text!r}",
)


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "sweep",
        help="many designs from a sweep file (TOML axes) on a local or existing Dask cluster",
    )
    p.add_argument(
        "file", metavar="SWEEP.toml", help="axes (target, tiles, rigid, seed, ...) and actions"
    )
    p.add_argument(
        "--scheduler",
        type=_scheduler,
        metavar="tcp://HOST:PORT",
        help="run on an existing Dask cluster (dask scheduler / dask worker) instead of a local one",
    )
    p.add_argument(
        "--workers", type=_count, metavar="N", help="local cluster size (default: one per core)"
    )
    p.add_argument(
        "--job-timeout",
        type=_seconds,
        metavar="S",
        help="record a job still running after S seconds as timed out (its worker is restarted)",
    )
    p.add_argument(
        "--retry-failed",
        action="store_true",
        help="run again the jobs recorded as error or timeout",
    )
    p.add_argument(
        "-o",
        "--output",
        required=True,
        metavar="DIR",
        help="folder: jobs/<id>/ per job, results.csv, results.parquet, index.html",
    )
    p.set_defaults(func=cmd_sweep)
