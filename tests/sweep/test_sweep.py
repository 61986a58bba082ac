"""Design sweeps on dask.distributed: a local cluster, an external `dask scheduler` + `dask worker`s on
loopback, faults (a job that raises, one that times out, one whose worker dies) and resuming."""

from __future__ import annotations

import csv
import json
import os
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path

import pytest

pytest.importorskip("distributed")

from fabkiri.sweep import load_spec, spec_from_dict, sweep  # noqa: E402
from fabkiri.sweep.job import run_job  # noqa: E402

from ..conftest import REPO  # noqa: E402

# 12 tiny jobs: 3 targets x 2 sizes x rigid or not; a loose shape tolerance so each is one solve
SWEEP_12 = """
[sweep]
actions = ["design"]
[axes]
target = ["circle", "square", "outline.csv"]
tiles = ["4x4", "5x5"]
rigid = [true, false]
[fixed]
shape_tol = "25%"
init = "rescaled"
"""
SWEEP_2 = SWEEP_12.replace(
    'target = ["circle", "square", "outline.csv"]', 'target = ["circle"]'
).replace('tiles = ["4x4", "5x5"]', 'tiles = ["4x4"]')  # the same sweep cut to 2 jobs
FIGURES = ("max_equality_residual", "hausdorff_mm", "one_minus_iou", "thinnest_tile_mm")


def _write_sweep(folder: Path) -> Path:
    (folder / "outline.csv").write_text("x,y\n0,0\n60,0\n60,40\n0,40\n")  # a user's target file
    path = folder / "s.toml"
    path.write_text(SWEEP_12)
    return path


@pytest.fixture(scope="module")
def local_run(tmp_path_factory):
    folder = tmp_path_factory.mktemp("sweep")
    spec = load_spec(_write_sweep(folder))
    res = sweep(spec, output=folder / "out", workers=2)
    return spec, res, folder


@pytest.mark.slow
@pytest.mark.xdist_group("sweep-local-run")  # one worker makes local_run once
def test_twelve_jobs_on_a_two_worker_local_cluster(local_run):
    spec, res, folder = local_run
    out = folder / "out"
    assert len(spec.jobs) == 12 and res.ran == 12 and res.skipped == 0 and res.workers == 2
    assert [r["status"] for r in res.rows].count("error") == 0
    assert all(r["max_equality_residual"] < 1e-9 for r in res.rows)
    assert len({r["worker"] for r in res.rows}) == 2  # both workers took jobs
    for r in res.rows:
        job = out / "jobs" / r["id"]
        assert {"pattern.json", "pattern.png", "row.json"} <= {p.name for p in job.iterdir()}
        assert json.loads((job / "pattern.json").read_text())["design"]["report"]["status"] in (
            "converged",
            "unconverged",
        )
    with open(out / "results.csv") as f:
        table = list(csv.DictReader(f))
    assert [t["id"] for t in table] == [j.id for j in spec.jobs]
    assert {
        "p_target",
        "p_tiles",
        "p_rigid",
        "status",
        "hausdorff_mm",
        "one_minus_iou",
        "thinnest_tile_mm",
        "min_cut_width_mm",
        "energy_barrier",
        "time_s",
        "worker",
    } <= set(table[0])
    import pyarrow.parquet as pq

    assert pq.read_table(out / "results.parquet").num_rows == 12
    page = (out / "index.html").read_text()
    assert page.count("<tr class=") == 12 and page.count("<img") == 12


@pytest.mark.slow  # the 12-job, 2-process cluster run; the fast loop checks the same on a small in-process sweep below
@pytest.mark.xdist_group("sweep-local-run")  # one worker makes local_run once
def test_a_second_run_does_no_work(local_run):
    spec, res, folder = local_run
    out = folder / "out"
    stamps = {p: p.stat().st_mtime_ns for p in (out / "jobs").rglob("*") if p.is_file()}
    again = sweep(spec, output=out, workers=2)
    assert (
        again.ran == 0 and again.skipped == 12 and again.workers == 0
    )  # no cluster was even started
    assert {p: p.stat().st_mtime_ns for p in (out / "jobs").rglob("*") if p.is_file()} == stamps
    assert [r["id"] for r in again.rows] == [r["id"] for r in res.rows]


def test_a_second_run_of_a_small_sweep_does_no_work(tmp_path):
    """Two jobs on an in-process (threaded) dask client, then the same sweep again: nothing runs, no cluster
    is started, no file is touched, the rows come back in the same order."""
    from distributed import Client

    path = tmp_path / "s.toml"
    path.write_text(SWEEP_2)
    spec = load_spec(path)
    assert len(spec.jobs) == 2
    out = tmp_path / "out"
    with Client(
        processes=False, n_workers=1, threads_per_worker=1, dashboard_address=None
    ) as client:
        res = sweep(spec, client, output=out)
    assert res.ran == 2 and res.skipped == 0 and [r["status"] for r in res.rows].count("error") == 0
    stamps = {p: p.stat().st_mtime_ns for p in (out / "jobs").rglob("*") if p.is_file()}
    assert len(stamps) >= 6  # pattern.json, pattern.png, row.json per job
    again = sweep(spec, output=out, workers=2)
    assert (
        again.ran == 0 and again.skipped == 2 and again.workers == 0
    )  # no cluster was even started
    assert {p: p.stat().st_mtime_ns for p in (out / "jobs").rglob("*") if p.is_file()} == stamps
    assert [r["id"] for r in again.rows] == [r["id"] for r in res.rows]


def test_changed_inputs_are_new_jobs(tmp_path):
    base = {"axes": {"target": ["circle"], "tiles": ["4x4"]}}
    a = spec_from_dict(base).jobs[0]
    b = spec_from_dict({"axes": {"target": ["circle"], "tiles": ["4x4"], "rigid": [True]}}).jobs[0]
    (tmp_path / "t.csv").write_text("0,0\n1,0\n1,1\n0,1\n")
    c = spec_from_dict({"axes": {"target": ["t.csv"], "tiles": ["4x4"]}}, base=tmp_path).jobs[0]
    (tmp_path / "t.csv").write_text("0,0\n2,0\n2,1\n0,1\n")
    d = spec_from_dict({"axes": {"target": ["t.csv"], "tiles": ["4x4"]}}, base=tmp_path).jobs[0]
    assert len({a.id, b.id, c.id, d.id}) == 4  # a target file's contents are part of the hash
    assert spec_from_dict(base).jobs[0].id == a.id


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def _dask(*args, log: Path) -> subprocess.Popen:
    env = {**os.environ, "PYTHONPATH": str(REPO)}
    return subprocess.Popen(
        [sys.executable, "-m", "dask", *args],
        env=env,  # `dask scheduler`, `dask worker`
        stdout=log.open("w"),
        stderr=subprocess.STDOUT,
        start_new_session=True,
    )


@pytest.mark.slow  # ~20-30 s on the shared 2-core box: three more interpreters and the 12 designs again
@pytest.mark.xdist_group("sweep-local-run")  # one worker makes local_run once
def test_the_same_sweep_on_dask_scheduler_and_two_dask_workers(local_run, tmp_path):
    _, res, folder = local_run
    port = _free_port()
    address = f"tcp://127.0.0.1:{port}"
    procs = [
        _dask(
            "scheduler",
            "--host",
            "127.0.0.1",
            "--port",
            str(port),
            "--no-dashboard",
            log=tmp_path / "scheduler.log",
        )
    ]
    try:
        for k in range(2):
            procs.append(
                _dask(
                    "worker",
                    address,
                    "--host",
                    "127.0.0.1",
                    "--nthreads",
                    "1",
                    "--nworkers",
                    "1",
                    "--no-dashboard",
                    "--name",
                    f"w{k}",
                    log=tmp_path / f"worker{k}.log",
                )
            )
        from distributed import Client

        with Client(address, timeout=60) as c:
            c.wait_for_workers(2, timeout=120)
        run = subprocess.run(
            [
                sys.executable,
                "-m",
                "fabkiri.cli.main",
                "sweep",
                str(folder / "s.toml"),
                "--scheduler",
                address,
                "-o",
                str(tmp_path / "out"),
            ],
            capture_output=True,
            text=True,
            env={**os.environ, "PYTHONPATH": str(REPO)},
            timeout=600,
        )
    finally:
        for p in reversed(procs):  # only the processes this test started, by their id
            os.killpg(p.pid, signal.SIGTERM)  # its own session: the worker nanny and its child
        for p in procs:
            try:
                p.wait(timeout=30)
            except subprocess.TimeoutExpired:
                p.kill()
                p.wait()
    assert run.returncode == 0, run.stderr
    assert "2 Dask workers" in run.stderr and "12 jobs (12 run now, 0 already done)" in run.stderr
    with open(tmp_path / "out" / "results.csv") as f:
        rows = {r["id"]: r for r in csv.DictReader(f)}
    assert {r["worker"] for r in rows.values()} == {"w0", "w1"}
    for r in res.rows:  # the same designs, whichever cluster made them
        for k in FIGURES:
            assert float(rows[r["id"]][k]) == pytest.approx(r[k], rel=1e-6, abs=1e-12), (r["id"], k)


# ---------------------------------------------------------------- faults (runs on the workers)


def _warm():
    """Import the job's modules on a worker, as its first job would."""
    import fabkiri.sweep.job  # noqa: F401


def faulty_runner(job):
    """The real job, except at 4x4: seed 7 hangs (to time out), seed 9 kills its worker the first time."""
    small = job.params["tiles"] == "4x4"
    if small and job.params.get("seed") == 7:
        time.sleep(600)
    if small and job.params.get("seed") == 9:
        marker = Path(os.environ["FABKIRI_TEST_MARKER"])
        if not marker.exists():
            marker.write_text(str(os.getpid()))
            os.kill(os.getpid(), signal.SIGKILL)
    return run_job(job)


@pytest.mark.slow  # waits out a 10 s job time-out and the restart of the hung worker (docs/speed.md)
def test_a_raising_a_hanging_and_a_killed_job_are_recorded_or_retried(tmp_path, monkeypatch):
    import cloudpickle
    from distributed import Client, LocalCluster

    cloudpickle.register_pickle_by_value(sys.modules[__name__])
    marker = tmp_path / "killed-once"
    monkeypatch.setenv("FABKIRI_TEST_MARKER", str(marker))  # the worker processes inherit it
    # 300x300 is refused by the size limits inside the job (an InputError raised on the worker). A job's
    # clock starts when it is submitted, so the time-out must outlast every honest job: three workers that
    # imported the job's modules first, so the killed job is rerun at once on a warm one (with two, its
    # rerun waited for its own worker's restart and imports beside the hung one)
    spec = spec_from_dict(
        {
            "axes": {"target": ["circle"], "tiles": ["4x4", "300x300"], "seed": [1, 7, 9]},
            "fixed": {"rigid": True, "shape_tol": "25%"},
        }
    )
    with (
        LocalCluster(
            n_workers=3,
            threads_per_worker=1,
            processes=True,
            host="127.0.0.1",
            dashboard_address="127.0.0.1:0",
            silence_logs=50,
        ) as cluster,
        Client(cluster) as client,
    ):
        client.run(_warm)
        res = sweep(spec, client, output=tmp_path / "out", job_timeout=10, runner=faulty_runner)
        by = {(r["p_tiles"], r["p_seed"]): r for r in res.rows}
        assert by[("4x4", 7)]["status"] == "timeout" and "after 10 s" in by[("4x4", 7)]["error"]
        assert "not restarted" not in by[("4x4", 7)]["error"]  # its worker was restarted
        for seed in (1, 7, 9):
            assert by[("300x300", seed)]["status"] == "error"
            assert by[("300x300", seed)]["error"].startswith("InputError:")
        for seed in (1, 9):
            assert by[("4x4", seed)]["status"] == "ok"
        assert marker.exists()  # the seed-9 job did kill its worker once, and was run again
        assert int(marker.read_text()) not in set(
            client.run(os.getpid).values()
        )  # that process is gone
        assert res.ran == 6 and res.failed == 4
        again = sweep(spec, client, output=tmp_path / "out", runner=faulty_runner)
        assert again.ran == 0 and again.skipped == 6


def test_the_summary_counts_a_row_without_a_status(tmp_path, run_cli):
    """A recorded row without a status (written by another runner) is counted as "None" beside the
    others: the summary's sort once compared None with a string and raised after every job had run."""
    path = tmp_path / "s.toml"
    path.write_text('[axes]\ntarget = ["circle"]\ntiles = ["4x4", "5x5"]\n')
    spec = load_spec(path)
    for job, status in zip(spec.jobs, ("ok", None), strict=True):
        folder = tmp_path / "out" / "jobs" / job.id
        folder.mkdir(parents=True)
        row = {"id": job.id, "digest": job.digest, **({"status": status} if status else {})}
        (folder / "row.json").write_text(json.dumps(row))
    code, _, err = run_cli("sweep", path, "-o", tmp_path / "out")
    assert code == 0, err
    assert "2 jobs (0 run now, 2 already done)" in err and ": 1 None, 1 ok" in err
