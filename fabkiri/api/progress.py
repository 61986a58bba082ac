"""A progress line with the elapsed time and an ETA, for the CLI's stderr or a notebook.

The doors report ``progress(stage, fraction or None, message)``; :class:`ProgressLine` turns one
such report into "make: cut  [2/4] 50 %  0:12 elapsed, ~0:12 left". The ETA is the time so far
scaled by what is left (``elapsed / fraction * (1 - fraction)``), so it exists only once some
of the work is done; without a fraction the line shows the stage and the time so far.
"""

from __future__ import annotations

import inspect
import time
from collections.abc import Callable
from typing import TextIO

Clock = Callable[[], float]


def clock_text(seconds: float) -> str:
    """``seconds`` as m:ss, or h:mm:ss past an hour."""
    whole = max(0, round(seconds))
    hours, rest = divmod(whole, 3600)
    minutes, secs = divmod(rest, 60)
    return f"{hours}:{minutes:02d}:{secs:02d}" if hours else f"{minutes}:{secs:02d}"


class ProgressLine:
    """Formats a report of ``what`` (e.g. ``"make"``) with the time since this was made by
    ``clock`` (``time.monotonic`` unless a test gives another); ``steps`` > 0 adds "[done/steps]".
    ``per_stage``: the fraction is of the stage alone (a design's continuation, its minimax steps),
    so the ETA is the stage's, timed from its first report (or its last report of 0)."""

    def __init__(
        self, what: str, steps: int = 0, clock: Clock = time.monotonic, per_stage: bool = False
    ) -> None:
        self.what, self.steps, self.clock, self.per_stage = what, steps, clock, per_stage
        self.start = clock()
        self.stage: tuple[str, float] = ("", self.start)  # the stage and when it started

    def line(self, stage: str, fraction: float | None) -> str:
        now = self.clock()
        elapsed = now - self.start
        if stage != self.stage[0] or fraction == 0:
            self.stage = (stage, now)
        spent = now - self.stage[1] if self.per_stage else elapsed
        text = f"{self.what}: {stage}"
        if fraction is None:
            return f"{text}  {clock_text(elapsed)} elapsed"
        fraction = min(max(fraction, 0.0), 1.0)
        if self.steps > 0:
            text += f"  [{round(fraction * self.steps)}/{self.steps}]"
        text += f" {fraction * 100:.0f} %  {clock_text(elapsed)} elapsed"
        if fraction > 0:  # nothing done yet: no rate to guess the rest from
            text += f", ~{clock_text(spent / fraction * (1 - fraction))} left"
        return text


def on_terminal(
    stream: TextIO, progress_line: ProgressLine, in_place: bool = True
) -> Callable[[str, float | None, str], None]:
    """A ``progress`` callback for a terminal: each message on its own line as before, under
    them one status line rewritten in place. Call it with stage ``""`` at the end to clear it.
    ``in_place`` false: the status is a whole line of its own after each message, for a stream
    others also write to (a status line left standing would run into their text)."""

    def show(stage: str, fraction: float | None, message: str) -> None:
        if in_place:
            stream.write("\r\033[K")  # clear the old status line before the message takes its place
        if message:
            stream.write(message + "\n")
        if stage:
            stream.write(progress_line.line(stage, fraction) + ("" if in_place else "\n"))
        stream.flush()

    return show


def three_args(
    progress: Callable[..., None],
) -> Callable[[str, float | None, str], None]:
    """``progress`` as a ``(stage, fraction, message)`` callback: as it is when it takes three
    arguments, else (a one-argument callback such as ``list.append`` or ``print``) hearing the
    messages alone."""
    if _takes_three(progress):
        return progress
    return lambda stage, fraction, message: progress(message)


def _takes_three(callback: Callable[..., None]) -> bool:
    """Whether ``callback`` can be called with three arguments (stage, fraction, message)."""
    try:
        inspect.signature(callback).bind(None, None, None)
    except (TypeError, ValueError):  # fewer parameters, or a builtin without a signature
        return False
    return True
