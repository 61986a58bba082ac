"""BLAS threads of this process: whether OpenBLAS started with one thread, so that the design solver's own limit
(``design/quad/solve.single_thread_blas``, a threadpoolctl controller that scans every loaded library) has nothing
left to do."""

from __future__ import annotations

import sys

# set by the CLI where it set OPENBLAS_NUM_THREADS=1 before numpy loaded (``cli.main.single_thread_blas_process``)
started_single = False


def single_threaded() -> bool:
    """Whether the BLAS of numpy and of scipy (those loaded) is OpenBLAS, started with one thread."""
    if not started_single:
        return False
    for name in ("numpy", "scipy"):
        module = sys.modules.get(name)
        if module is None:
            continue
        config = getattr(getattr(module, "__config__", None), "CONFIG", None) or {}
        blas = config.get("Build Dependencies", {}).get("blas", {})
        if "openblas" not in str(blas.get("name", "")).lower():
            return False  # another BLAS (MKL, BLIS...) does not read OPENBLAS_NUM_THREADS
    return True
