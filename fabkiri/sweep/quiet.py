"""Preloaded in each local worker process: Ctrl-C is the sweep's to handle (it closes the cluster), so
the workers ignore SIGINT instead of each printing its own KeyboardInterrupt traceback; and a job that
raises is the sweep's to report (its row holds the one-line error), so the worker does not log its
traceback to the sweep's terminal."""

from __future__ import annotations

import logging
import signal


class _NoJobFailures(logging.Filter):
    """Drops the worker's "Compute Failed" record (key, task, exception and traceback of a job)."""

    def filter(self, record: logging.LogRecord) -> bool:
        return not str(record.msg).startswith("Compute Failed")


def dask_setup(worker) -> None:  # noqa: ARG001 (the preload hook's signature)
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    logging.getLogger("distributed.worker").addFilter(_NoJobFailures())
