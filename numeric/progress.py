"""One progress reporter for every long phase (runs, derivation, loading, exact solutions, writes).

On a terminal a phase shows a bar (known total) or an elapsed-time line redrawn in place after
about a second; when stderr is not a terminal it prints a plain line every 5 s instead (the first
after 5 s), so logs of long runs still say what is going on while short phases stay silent. A
phase that ends in an error (a refusal) says nothing more: its one error line stands alone.
``SPRINGCHAIN_PROGRESS=0`` in the environment silences every reporter.

    bar = Reporter("verlet", total=steps)      # bar.update(done) as work proceeds; bar.close()
    bar.say("reference ready"); bar.count("run 3")   # milestones and counted items, one line each
    with phase("deriving the model"):          # elapsed time after 1 s, then every few seconds
        ...
    note("compiling numba kernels")            # one line
"""

from __future__ import annotations

import os
import sys
import threading
import time
from contextlib import contextmanager

#: Nothing is shown for the first QUIET_SECONDS of a phase.
QUIET_SECONDS = 1.0
#: Redraw interval on a terminal, and the interval of plain lines otherwise (seconds).
TTY_INTERVAL, PLAIN_INTERVAL = 0.2, 5.0
PREFIX = "springchain"
#: The environment variable that silences every reporter when set to one of :data:`OFF`.
ENV, OFF = "SPRINGCHAIN_PROGRESS", ("0", "off", "no", "false")


def silenced() -> bool:
    """Whether ``SPRINGCHAIN_PROGRESS`` turns progress off (``0``, ``off``, ``no``, ``false``)."""
    return os.environ.get(ENV, "").strip().lower() in OFF


def _isatty(stream) -> bool:
    try:
        return bool(stream.isatty())
    except (AttributeError, ValueError, OSError):
        return False


def line(text: str, prefix: str = PREFIX, stream=None) -> None:
    """One line ``<prefix>: <text>`` on stderr (flushed); silent if stderr is closed."""
    stream = stream or sys.stderr
    try:
        stream.write(f"{prefix}: {text}\n" if prefix else f"{text}\n")
        stream.flush()
    except (OSError, ValueError):
        pass


def note(text: str, prefix: str = PREFIX, stream=None) -> None:
    """A progress milestone as one :func:`line` (e.g. "compiling numba kernels"), unless silenced."""
    if not silenced():
        line(text, prefix, stream)


class Reporter:
    """Progress of one phase with an optional known ``total`` of work units.

    Parameters
    ----------
    label : str
        What is being done (``"verlet"``, ``"exact solution"``).
    total : int, optional
        Units of work; without it only the elapsed time is shown.
    enabled : bool, optional
        Default: on. ``False`` (or ``SPRINGCHAIN_PROGRESS=0`` in the environment) silences it.
    quiet_seconds : float, optional
        Nothing is shown before this much time has passed (default: :data:`QUIET_SECONDS` on a
        terminal, :data:`PLAIN_INTERVAL` otherwise).
    prefix : str
        What each line starts with (``springchain``, ``bench``, ``sweep``, ...).
    interval : float, optional
        Seconds between lines (default: 0.2 s redraws on a terminal, a line every 5 s otherwise).
    """

    def __init__(self, label: str, total: int | None = None, *, enabled: bool | None = None,
                 stream=None, quiet_seconds: float | None = None, prefix: str = PREFIX,
                 interval: float | None = None):
        self.label = label
        self.total = None if total is None else max(int(total), 1)
        self.enabled = (True if enabled is None else bool(enabled)) and not silenced()
        self.stream = stream or sys.stderr
        self.tty = _isatty(self.stream)
        self.quiet = quiet_seconds if quiet_seconds is not None else (
            QUIET_SECONDS if self.tty else max(QUIET_SECONDS, PLAIN_INTERVAL))
        self.prefix = prefix
        self.interval = interval
        self.t0 = time.monotonic()
        self.last = -1e300
        self.shown = False  # something was printed
        self.open_line = False  # a terminal line awaits its newline
        self.done = 0
        self.finished = False  # the final line (done = total) was written

    def _text(self, done: int | None) -> str:
        elapsed = time.monotonic() - self.t0
        if self.total is None or done is None:
            return f"{self.label} ... {elapsed:.0f} s"
        frac = min(done / self.total, 1.0)
        if self.tty:
            return f"{self.label} [{'#' * int(30 * frac):<30}] {100 * frac:5.1f}% {elapsed:6.1f} s"
        return f"{self.label}: {done}/{self.total} ({100 * frac:.0f}%), {elapsed:.0f} s"

    def update(self, done: int | None = None) -> None:
        """Report ``done`` units (or just that time passes); throttled."""
        if done is not None:
            self.done = done
        if not self.enabled:
            return
        now = time.monotonic()
        finished = self.total is not None and done is not None and done >= self.total
        if now - self.t0 < self.quiet and not (finished and self.shown):
            return
        if finished and self.finished:  # the final line once, however often the end is reported
            return
        every = self.interval if self.interval is not None else (TTY_INTERVAL if self.tty else PLAIN_INTERVAL)
        if now - self.last < every and not finished:
            return
        self.last = now
        try:
            if self.tty:
                self.stream.write(f"\r{self.prefix}: {self._text(done)}")
                self.open_line = True
            else:
                self.stream.write(f"{self.prefix}: {self._text(done)}\n")
            self.shown = True
            self.finished = finished
            if finished:
                self.close()
            self.stream.flush()
        except (OSError, ValueError):
            self.enabled = False

    def say(self, text: str) -> None:
        """One line ``<prefix>: <text>`` now (a phase's milestone), if enabled."""
        if self.enabled:
            line(text, prefix=self.prefix, stream=self.stream)

    def count(self, text: str) -> None:
        """One more unit done, said as ``[done/total] elapsed  text``."""
        self.done += 1
        self.say(f"[{self.done:3d}/{self.total}] {time.monotonic() - self.t0:6.1f}s  {text}")

    def close(self, message: str | None = None) -> None:
        """End the phase: finish the terminal line; say ``message`` (e.g. "done in 3.2 s") if
        anything was shown."""
        if not self.enabled:
            return
        try:
            if self.open_line:
                self.stream.write("\n")
                self.open_line = False
            if self.shown and message:
                self.stream.write(f"{self.prefix}: {self.label}: {message}\n")
            self.stream.flush()
        except (OSError, ValueError):
            pass


@contextmanager
def phase(label: str, *, enabled: bool | None = None, stream=None):
    """Show the elapsed time of a phase of unknown length if it lasts over ~1 s (5 s when stderr is
    not a terminal; a thread wakes up to report, the work itself is not touched), then ``done in
    T s`` — unless the phase raised: a refusal's error line is then the only line that follows."""
    rep = Reporter(label, enabled=enabled, stream=stream)
    stop = threading.Event()

    def tick():
        while not stop.wait(TTY_INTERVAL if rep.tty else 1.0):
            rep.update()

    thread = threading.Thread(target=tick, name=f"progress: {label}", daemon=True)
    if rep.enabled:
        thread.start()
    failed = True
    try:
        yield rep
        failed = False
    finally:
        stop.set()
        if rep.enabled:
            thread.join()
        rep.close(None if failed else f"done in {time.monotonic() - rep.t0:.1f} s")


__all__ = ["Reporter", "phase", "line", "note", "silenced", "QUIET_SECONDS", "ENV"]
