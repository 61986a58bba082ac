"""Where a long design is, for whoever listens: the stage and the share of it done.

The loops that know how many steps they take (the continuation's steps into the fabrication limits,
the minimax refinement's Lawson steps) call :func:`step` as each one starts and ends; a caller that
wants to hear it (the API's ``progress``, the CLI's status line with its ETA) runs the design inside
:func:`listening`. Nobody listening: nothing happens, so the design's results do not depend on it.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from contextlib import contextmanager
from contextvars import ContextVar

Listener = Callable[[str, float], None]  # (stage, share of the stage done in [0, 1])

_LISTENER: ContextVar[Listener | None] = ContextVar("fabkiri_design_stage", default=None)


@contextmanager
def listening(listener: Listener | None) -> Iterator[None]:
    """Run the body with ``listener`` hearing every :func:`step` (None: nobody)."""
    token = _LISTENER.set(listener)
    try:
        yield
    finally:
        _LISTENER.reset(token)


def step(stage: str, done: int, of: int) -> None:
    """``done`` of the ``of`` steps of ``stage`` are done (0 as the stage starts)."""
    listener = _LISTENER.get()
    if listener is not None and of > 0:
        listener(stage, min(done / of, 1.0))
