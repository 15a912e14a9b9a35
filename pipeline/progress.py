"""One line on a terminal: how far a dask computation is, and an estimate of the time left.

``label  [#########           ]  45 %  12 s elapsed, ~15 s left``

The estimate assumes the remaining tasks take as long on average as the finished ones
(time left = elapsed x (1 - f) / f for the fraction f of tasks done); until a few tasks are
done it says ``estimating``. :class:`ProgressLine` draws the line (only on a terminal, only
once the computation has run for a while, at most every :data:`REDRAW` seconds, ending with a
newline); :class:`DaskProgress` feeds it from the local scheduler's callbacks and
:func:`watch_futures` from ``dask.distributed`` futures.
"""

from __future__ import annotations

import math
import sys
import time
from collections.abc import Callable, Sequence
from typing import Any, TextIO

from dask.callbacks import Callback

__all__ = ["DaskProgress", "ProgressLine", "describe", "format_duration", "watch_futures"]

#: Seconds between two redraws of the line.
REDRAW = 0.5
#: Tasks that must be done before the time left is estimated (the first include start-up).
SETTLE_TASKS = 3
#: Characters of the bar between the brackets.
BAR_WIDTH = 20


def format_duration(seconds: float) -> str:
    """A duration for people: ``12 s``, ``2 min 05 s``, ``1 h 30 min``.

    Parameters
    ----------
    seconds
        Duration in s (negative counts as 0).

    Returns
    -------
    str
        Whole seconds below a minute, minutes and seconds below an hour, else hours and minutes.
    """
    whole = round(max(seconds, 0.0))
    if whole < 60:
        return f"{whole} s"
    if whole < 3600:
        return f"{whole // 60} min {whole % 60:02d} s"
    hours, minutes = divmod(round(whole / 60), 60)
    return f"{hours} h {minutes:02d} min"


def describe(fraction: float, elapsed: float, *, settled: bool = True) -> str:
    """The bar, the percentage, the elapsed time and the estimated time left.

    Parameters
    ----------
    fraction
        Fraction of the work done, clamped to [0, 1] (NaN counts as 0).
    elapsed
        Time since the work started, in s.
    settled
        False while too few tasks are done for a fair estimate: the time left then reads
        ``estimating`` (as it does at fraction 0).

    Returns
    -------
    str
        E.g. ``[##########          ]  50 %  10 s elapsed, ~10 s left``; at fraction 1 the
        time left reads ``done``.
    """
    fraction = min(max(fraction, 0.0), 1.0) if not math.isnan(fraction) else 0.0
    elapsed = max(elapsed, 0.0)
    if fraction >= 1.0:
        left = "done"
    elif fraction == 0.0 or not settled:
        left = "estimating"
    else:
        left = f"~{format_duration(elapsed * (1.0 - fraction) / fraction)} left"
    bar = "#" * int(BAR_WIDTH * fraction)
    return f"[{bar:<{BAR_WIDTH}}] {int(100 * fraction):3d} %  {format_duration(elapsed)} elapsed, {left}"


class ProgressLine:
    """Draws ``label  describe(...)`` over and over on one line of a stream.

    Parameters
    ----------
    label
        What is computed, e.g. ``cube round 2 (adaptive: 27 of 108 cells still open)``.
    stream
        Where to draw; None means ``sys.stderr`` at construction.
    after
        Nothing is drawn before the work has run this long (s): short runs stay silent.
    force
        Draw even when ``stream`` is not a terminal (tests); otherwise a stream that is not a
        terminal (a log file, a pipe) gets nothing, so no carriage returns end up in logs.
    clock
        Seconds from an arbitrary origin (``time.monotonic``; tests pass their own).
    """

    def __init__(
        self, label: str, stream: TextIO | None = None, after: float = 0.0, force: bool = False,
        clock: Callable[[], float] = time.monotonic,
    ) -> None:
        self.label = label
        self._stream = sys.stderr if stream is None else stream
        self._after = after
        self._clock = clock
        isatty = getattr(self._stream, "isatty", None)
        self.enabled = force or bool(isatty and isatty())
        self._start = self._last = 0.0
        self._total = self._done = self._width = 0
        self._shown = False

    def start(self, total: int) -> None:
        """Start the clock on ``total`` tasks."""
        self._start = self._clock()
        self._total, self._done, self._width, self._shown = total, 0, 0, False

    def update(self, done: int) -> None:
        """``done`` tasks are finished: redraw if the run is long enough and the line is stale."""
        self._done = done
        now = self._clock()
        if not self.enabled or now - self._start < self._after or (self._shown and now - self._last < REDRAW):
            return
        self._draw(now)

    def finish(self, failed: bool = False) -> None:
        """The work ended: the final line (100 % unless ``failed``) and a newline, if it was long."""
        if not self.enabled:
            return
        now = self._clock()
        if not self._shown and now - self._start < self._after:
            return
        if not failed:
            self._done = self._total
        self._draw(now)
        self._stream.write("\n")
        self._stream.flush()

    def _draw(self, now: float) -> None:
        fraction = self._done / self._total if self._total else 1.0
        settled = self._done >= min(SETTLE_TASKS, self._total)
        text = f"{self.label}  {describe(fraction, now - self._start, settled=settled)}"
        # Blanks over the tail of a longer previous line ("estimating" is longer than most estimates).
        self._stream.write("\r" + text + " " * max(self._width - len(text), 0))
        self._stream.flush()
        self._width, self._last, self._shown = len(text), now, True


class DaskProgress(Callback):
    """Feeds a :class:`ProgressLine` from the local (threaded or synchronous) dask scheduler.

    The tasks counted are those the scheduler runs (literal data in the graph is not a task).

    Parameters
    ----------
    line
        The line to draw.
    """

    def __init__(self, line: ProgressLine) -> None:
        super().__init__()
        self._line = line
        self._done = 0

    def _start_state(self, dsk: Any, state: dict[str, Any]) -> None:
        self._done = 0
        self._line.start(len(state["ready"]) + len(state["waiting"]) + len(state["running"]))

    def _posttask(self, key: Any, result: Any, dsk: Any, state: dict[str, Any], worker_id: Any) -> None:
        self._done += 1
        self._line.update(self._done)

    def _finish(self, dsk: Any, state: dict[str, Any], failed: bool) -> None:
        self._line.finish(failed)


def watch_futures(futures: Sequence[Any], line: ProgressLine) -> None:
    """Feed ``line`` from ``dask.distributed`` futures as they complete; returns when all are done.

    Parameters
    ----------
    futures
        ``distributed.Future`` objects (one per task output: an array chunk, a delayed value).
    line
        The line to draw.
    """
    from distributed import as_completed

    line.start(len(futures))
    failed = False
    for done, future in enumerate(as_completed(futures), start=1):
        failed = failed or future.status == "error"
        line.update(done)
    line.finish(failed)
