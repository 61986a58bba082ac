"""One sweep job, run on a worker: design (and cut, print, deploy) into files held in memory.

Nothing here touches the sweep's folder: the job returns its row and its files
(name -> bytes) and the client publishes them all at once, so a worker that
dies mid-job leaves nothing behind and the workers need no shared disk.
"""

from __future__ import annotations

import json
import os
import socket
import time
from dataclasses import replace

from ..api.design import design_pattern
from ..errors import CheckFailed, FabkiriError
from .spec import Job, request_of

DEFAULT_CUT_MATERIAL = "acrylic-3"
DEFAULT_PRINTER = "prusa-mk4"


def worker_name() -> str:
    try:
        from distributed import get_worker

        w = get_worker()
        return str(w.name if w.name is not None else w.address)
    except (ImportError, ValueError):
        return f"{socket.gethostname()}:{os.getpid()}"


def run_job(job: Job) -> tuple[dict, dict[str, bytes]]:
    """The job's row (figures) and files; a job whose design fails a check still returns them.

    Exceptions (bad inputs a job meets, fabrication refusals) propagate: the sweep records them in the row.
    """
    from threadpoolctl import threadpool_limits

    t0, c0 = time.perf_counter(), time.process_time()
    with threadpool_limits(1):  # one job per core: BLAS threads would only fight the other workers
        row, files = _run(job)
    row.update(
        time_s=round(time.perf_counter() - t0, 4),
        cpu_s=round(time.process_time() - c0, 4),
        worker=worker_name(),
    )
    return row, files


def _run(job: Job) -> tuple[dict, dict[str, bytes]]:
    out = design_pattern(request_of(job.params))
    files = {str(k): v for k, v in out.files("pattern.json").items()}
    row = design_figures(out, job.params)
    pattern = out.pattern
    if not out.valid and set(job.actions) - {"design"}:
        row["notes"] = "not cut, printed or deployed: the design failed its checks"
        return row, _encoded(files)
    failures = [] if row["status"] == "ok" else [row["status"]]
    for stage, make in (("cut", _cut), ("print", _print), ("deploy", _deploy)):
        if stage not in job.actions:
            continue
        try:
            files.update(make(pattern, job.params, row))
        except (
            FabkiriError
        ) as exc:  # a refusal of this stage: the design and the other stages are kept
            failures.append(f"{stage} failed")
            row["status"] = f"{stage} failed" if row["status"] == "ok" else row["status"]
            row["error"] = "; ".join(
                filter(None, [row.get("error"), f"{stage}: {describe_error(exc)}"])
            )
    row["failures"] = "; ".join(failures)  # every one (the status names the first)
    return row, _encoded(files)


def design_figures(out, params: dict | None = None) -> dict:
    """The row figures of a design: status, residual, conformance, fabricability (the smallest cut width for
    the job's material and hinge, acrylic-3 with tape hinges when it names none)."""
    params = params or {}
    r = out.report
    conf = r.get("conformance") or {}
    worst = max(conf.values(), key=lambda c: c["hausdorff_rel"], default=None)
    fab = r.get("fabricability") or {}
    row = {
        "status": out.status,
        "max_equality_residual": r.get("max_equality_residual"),
        "hausdorff_mm": worst and worst["hausdorff_mm"],
        "hausdorff_rel": worst and worst["hausdorff_rel"],
        "one_minus_iou": worst and worst["one_minus_iou"],
        "shape": "met" if out.shape_met else "missed",
        "thinnest_tile_mm": fab.get("thinnest_tile_mm"),
        "hole_fraction": (r.get("opening") or {}).get("hole_fraction"),  # how much it opens
        "design_time_s": r.get("time_s_total"),
        "problems": "; ".join(out.problems),
    }
    name = params.get("cut_material") or params.get("material") or DEFAULT_CUT_MATERIAL
    cut = (fab.get("cut") or {}).get(name) or {}
    hinge = params.get("hinge") or ("tape" if "tape" in cut else next(iter(cut), None))
    row["min_cut_width_mm"] = (cut.get(hinge) or {}).get(
        "min_width_mm"
    )  # the smallest `cut --width` allowed
    row["cut_material"] = f"{name} {hinge}" if hinge else name
    return row


def _cut(pattern, params: dict, row: dict) -> dict[str, bytes]:
    from ..fabricate.cut.materials import load_material
    from ..fabricate.cut.readback import verify_result
    from ..fabricate.cut.sheets import CutOptions, cut_pattern

    material = load_material(
        params.get("cut_material") or params.get("material") or DEFAULT_CUT_MATERIAL
    )
    result = cut_pattern(
        pattern,
        CutOptions(
            material=material,
            hinge=params.get("hinge"),
            stem="pattern",
            pattern_file="pattern.json",
        ),
    )  # at the designed size, as `cut`
    rb = verify_result(pattern, result)
    result.manifest["verification"] = rb.to_dict()
    if not rb.ok:
        raise CheckFailed(
            "cut: read-back verification failed: "
            + "; ".join(f"{c.name} ({c.detail})" for c in rb.failed()[:4])
        )
    man = result.manifest
    row["cut_scale"] = man.get("scale")
    row["cut_sheets"] = len(man["sheets"])
    row["cut_length_m"] = sum(s["cut_length_mm"] for s in man["sheets"]) / 1000
    files = {f"cut/{k}": v for k, v in result.files.items()}
    files["cut/manifest.json"] = result.manifest_bytes()
    return files


def _print(pattern, params: dict, row: dict) -> dict[str, bytes]:
    from ..fabricate import fabricability as fb
    from ..fabricate.print import mesh
    from ..fabricate.print.printers import load_printer

    printer = load_printer(params.get("print_printer") or params.get("printer") or DEFAULT_PRINTER)
    style = params.get("style") or "tiles-and-strips"
    need = fb.print_minimum(pattern, style, printer, 1)
    if not need.possible:
        raise CheckFailed(f"print: {style} on {printer.name}: {need.advice(printer.name)}")
    k = max(1.0, float(need.min_scale or 1.0))  # the smallest scale the print checks accept
    pattern = replace(
        pattern,
        nodes=pattern.nodes * k,
        contracted={s: v * k for s, v in pattern.contracted.items()},
    )
    job = mesh.build_job(pattern, style, 1, printer, advise_scale=k)
    mesh.print_plan(job)  # refuses a print the printer cannot make
    realised = mesh.realise_job(job)
    report = mesh.check_meshes(realised)
    if report.problems:
        raise CheckFailed("print: " + "; ".join(report.problems))
    row["print_scale"] = k
    return {f"print/{name}": data for name, data in mesh.job_files(realised, "pattern").items()}


def _deploy(pattern, params: dict, row: dict) -> dict[str, str]:
    from ..mechanics.deploy import deployment_path

    path = deployment_path(pattern, int(params.get("deploy_steps", 20)))
    summary = path.summary()
    row["energy_barrier"] = summary["energy_max"]
    row["collision_free"] = summary["collision_free"]
    csv = "t,energy\n" + "".join(f"{t:.6g},{e:.6g}\n" for t, e in zip(path.t, path.energy))
    return {
        "deploy/deploy.json": json.dumps(summary, indent=2, sort_keys=True) + "\n",
        "deploy/energy.csv": csv,
    }


def _encoded(files: dict) -> dict[str, bytes]:
    return {k: v.encode("utf-8") if isinstance(v, str) else v for k, v in files.items()}


def describe_error(exc: BaseException) -> str:
    """One line: the exception's type and message (no traceback: it is in the worker's log), a fabkiri
    error's as the command line says it (the results are the ``sweep`` command's)."""
    said = exc.cli_message() if isinstance(exc, FabkiriError) else str(exc)
    text = said.strip().splitlines()[0] if said.strip() else ""
    return f"{type(exc).__name__}: {text}" if text else type(exc).__name__
