"""Run a sweep's jobs on dask.distributed: a local cluster by default, any cluster on request.

Jobs are independent tasks. At most as many are in flight as the cluster has
threads, so a job's clock starts when it is submitted; one past ``job_timeout``
is recorded as timed out, cancelled and its worker restarted (a Python thread
cannot be stopped otherwise). A worker that dies mid-job is the scheduler's to
handle: it reruns the job elsewhere (up to ``distributed.scheduler.allowed-failures``
times). The client publishes each job's files and its ``row.json`` (last) into
``DIR/jobs/<id>/``; a job whose ``row.json`` exists is done and skipped next time.
"""

from __future__ import annotations

import json
import os
import time
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

from ..errors import InputError
from ..fileio import atomic_write_many, check_output_folder
from .job import describe_error, run_job
from .report import write_tables
from .spec import Job, SweepSpec

ROW_FILE = "row.json"
POLL_S = 0.1


@dataclass
class SweepResult:
    """Every job's row (done before or now), the folder, and what this run did."""

    rows: list[dict]
    output: Path
    ran: int = 0  # jobs run now (finished, failed or timed out)
    skipped: int = 0  # jobs already done in the folder
    failed: int = 0  # of those run now: errors and time-outs
    wall_s: float = 0.0
    workers: int = 0
    dashboard: str | None = None
    tables: list[Path] = field(default_factory=list)

    @property
    def ok(self) -> int:
        return sum(r.get("status") == "ok" for r in self.rows)

    def to_pandas(self):
        import pandas as pd

        return pd.DataFrame(self.rows)


def sweep(
    spec: SweepSpec,
    client=None,
    *,
    output: str | Path = "sweep-out",
    workers: int | None = None,
    job_timeout: float | None = None,
    retry_failed: bool = False,
    progress: Callable | None = None,
    runner: Callable[[Job], tuple[dict, dict]] = run_job,
    on_cluster: Callable | None = None,
) -> SweepResult:
    """Run every job of ``spec`` not yet done in ``output``; returns all rows.

    ``client``: a ``distributed.Client`` to use (left open); without one a
    ``LocalCluster`` of ``workers`` processes (default: one per core) is started
    and closed. ``progress(counts)`` is called as jobs start and end;
    ``on_cluster(client)`` once the cluster is up (the CLI prints the dashboard).
    """
    out = Path(output)
    check_output_folder(out)
    if workers is not None and workers < 1:
        raise InputError(f"--workers must be at least 1, got {workers}")
    if job_timeout is not None and not job_timeout > 0:
        raise InputError(f"--job-timeout must be positive, got {job_timeout}")
    check_same_sweep(out, spec)
    (out / "jobs").mkdir(parents=True, exist_ok=True)
    t0 = time.perf_counter()
    done = {
        j.id: row
        for j in spec.jobs
        if (row := read_row(out, j)) is not None
        and (not retry_failed or row.get("status") not in ("error", "timeout"))
    }
    todo = [j for j in spec.jobs if j.id not in done]
    result = SweepResult(rows=[], output=out, skipped=len(done))
    if todo:
        own = client is None
        cluster = None
        if own:
            client, cluster = local_client(workers)
        try:
            result.dashboard = client.dashboard_link
            result.workers = len(client.nthreads())
            if on_cluster is not None:
                on_cluster(client)
            for job, row in _execute(client, todo, out, job_timeout, runner, progress):
                done[job.id] = row
                result.ran += 1
                result.failed += row.get("status") in ("error", "timeout")
        finally:
            result.rows = [done[j.id] for j in spec.jobs if j.id in done]
            result.tables = write_tables(out, result.rows)
            if own:
                client.close()
            if cluster is not None:  # ours: started above
                cluster.close()
    else:
        result.rows = [done[j.id] for j in spec.jobs]
        result.tables = write_tables(out, result.rows)
    result.wall_s = time.perf_counter() - t0
    return result


def _inputs(row: dict) -> str:
    """A row's inputs (its parameters and actions), the same across fabkiri versions."""
    return json.dumps(
        {k: v for k, v in row.items() if k.startswith("p_") or k == "actions"},
        sort_keys=True,
        default=str,
    )


def check_same_sweep(out: Path, spec: SweepSpec) -> None:
    """Refuse an output folder that holds another sweep's results: a job this sweep does not have
    (its tables would be replaced without it). The same sweep, resumed or grown, is accepted."""
    jobs = out / "jobs"
    if not jobs.is_dir():
        tables = [n for n in ("results.csv", "results.parquet") if (out / n).exists()]
        if tables:
            raise InputError(
                f"-o {out}: holds {tables[0]} but no jobs/ (not this sweep's folder); "
                "choose another folder"
            )
        return
    ours = {_inputs(_base_row(j)) for j in spec.jobs}
    ids = {j.id for j in spec.jobs}
    foreign = []
    for d in sorted(jobs.iterdir()):
        try:
            row = json.loads((d / ROW_FILE).read_text())
        except (OSError, ValueError):
            continue  # no finished job there
        if isinstance(row, dict) and row.get("id") not in ids and _inputs(row) not in ours:
            foreign.append(d.name)
    if foreign:
        raise InputError(
            f"-o {out}: holds the results of another sweep ({len(foreign)} job(s) not in "
            f"{spec.source or 'this sweep'}, e.g. {foreign[0]}); choose another folder"
        )


def summary(rows: list[dict]) -> str:
    """Each job counted once by its status; then the failed jobs (counted once each) and their
    failures by kind (a job that missed its shape and failed its cut counts in both kinds)."""
    counts: dict[str, int] = {}
    kinds: dict[str, int] = {}
    failed = 0
    for r in rows:  # str: a row without a status is counted as "None", and sorts with the others
        status = str(r.get("status"))
        counts[status] = counts.get(status, 0) + 1
        if status in ("ok", "None"):
            continue
        failed += 1
        for kind in str(r.get("failures") or status).split("; "):
            kinds[kind] = kinds.get(kind, 0) + 1
    text = ", ".join(f"{v} {k}" for k, v in sorted(counts.items()))
    if failed:
        text += (
            f" ({failed} failed: " + ", ".join(f"{v} {k}" for k, v in sorted(kinds.items())) + ")"
        )
    return text


def local_client(workers: int | None = None):
    """A LocalCluster of single-threaded worker processes, one per core unless told, dashboard on loopback."""
    from distributed import Client, LocalCluster

    n = workers or len(os.sched_getaffinity(0))
    cluster = LocalCluster(
        n_workers=n,
        threads_per_worker=1,
        processes=True,
        host="127.0.0.1",
        dashboard_address="127.0.0.1:0",
        silence_logs=40,
        preload=["fabkiri.sweep.quiet"],
    )
    return Client(cluster), cluster


def read_row(out: Path, job: Job) -> dict | None:
    """The job's recorded row if it ran with the same inputs (its digest), else None."""
    p = out / "jobs" / job.id / ROW_FILE
    try:
        row = json.loads(p.read_text())
    except (OSError, ValueError):
        return None
    return row if row.get("digest") == job.digest else None


def _base_row(job: Job) -> dict:
    return {
        "id": job.id,
        **{f"p_{k}": _flat(v) for k, v in job.params.items()},
        "actions": "+".join(job.actions),
        "digest": job.digest,
    }


def _flat(v):
    return ";".join(map(str, v)) if isinstance(v, list) else v


def _publish(out: Path, job: Job, row: dict, files: dict[str, bytes]) -> dict:
    """Every file of the job, ``row.json`` last: the job counts as done only once all are in."""
    row = {**_base_row(job), **row}
    row["files"] = len(files)
    text = json.dumps(row, indent=1, sort_keys=True, default=str) + "\n"
    all_files: dict[str, bytes | str] = {**files, ROW_FILE: text}
    atomic_write_many(out / "jobs" / job.id, all_files)
    return row


def _execute(client, todo: list[Job], out: Path, timeout: float | None, runner, progress):
    """Yield (job, row) as jobs end: at most one job per worker thread in flight."""
    pending = deque(todo)
    flight: dict = {}  # future -> (job, submitted at)
    counts = {
        "total": len(todo),
        "done": 0,
        "failed": 0,
        "running": 0,
        "started": time.perf_counter(),
    }
    try:
        yield from _loop(client, pending, flight, counts, out, timeout, runner, progress)
    finally:  # interrupted: nothing left running on a cluster that outlives the sweep
        if flight:
            client.cancel(list(flight))


def _loop(client, pending: deque, flight: dict, counts: dict, out: Path, timeout, runner, progress):
    from distributed import wait

    while pending or flight:
        slots = max(1, sum(client.nthreads().values()))
        while pending and len(flight) < slots:
            job = pending.popleft()
            fut = client.submit(
                runner, job, key=f"fabkiri-job-{job.id}-{time.monotonic_ns()}", pure=False
            )
            flight[fut] = (job, time.perf_counter())
        counts["running"] = len(flight)
        if progress:
            progress(counts)
        try:
            finished = wait(list(flight), timeout=POLL_S, return_when="FIRST_COMPLETED").done
        except TimeoutError:
            finished = set()
        for fut in finished:
            job, _ = flight.pop(fut)
            row = _finish(fut, job, out)
            counts["done" if row["status"] not in ("error", "timeout") else "failed"] += 1
            yield job, row
        if timeout is not None:
            now = time.perf_counter()
            for fut, (job, t_sub) in list(flight.items()):
                if now - t_sub > timeout:
                    flight.pop(fut)
                    note = _stop(client, fut)
                    row = _publish(
                        out,
                        job,
                        {
                            "status": "timeout",
                            "error": f"no result after {timeout:g} s{note}",
                            "time_s": round(now - t_sub, 4),
                        },
                        {},
                    )
                    counts["failed"] += 1
                    yield job, row
    counts["running"] = 0
    if progress:
        progress(counts)


def _finish(fut, job: Job, out: Path) -> dict:
    if fut.status == "finished":
        row, files = fut.result()
        return _publish(out, job, row, files)
    try:
        exc = fut.exception()
    except Exception as lost:  # cancelled or lost by the cluster (e.g. restarted under it)
        exc = lost
    name = type(exc).__name__
    error = describe_error(exc)
    if (
        name == "KilledWorker"
    ):  # the scheduler gave up after the job's workers died allowed-failures times
        error = f"KilledWorker: its worker died each time it ran ({exc})"
    return _publish(out, job, {"status": "error", "error": error}, {})


def _stop(client, fut) -> str:
    """Cancel a timed-out job and restart the worker still running it (a thread cannot be interrupted);
    returns what to add to the row's error when that restart failed."""
    key = fut.key
    holders = [w for w, keys in client.processing().items() if key in keys]
    fut.cancel()
    if not holders:
        return ""
    try:
        client.restart_workers(holders, timeout=60, raise_for_error=True)
    except Exception as exc:  # e.g. a worker without a nanny: the job keeps it busy until it ends
        return f"; its worker was not restarted ({describe_error(exc)})"
    return ""
