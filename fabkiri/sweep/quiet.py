"""Preloaded in each local worker process: Ctrl-C is the sweep's to handle (it closes the cluster), so
the workers ignore SIGINT instead of each printing its own KeyboardInterrupt traceback."""

from __future__ import annotations

import signal


def dask_setup(worker) -> None:  # noqa: ARG001 (the preload hook's signature)
    signal.signal(signal.SIGINT, signal.SIG_IGN)
