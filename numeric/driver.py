"""The one loop: step an integrator on the grid ``t = i·h`` and record every ``record_every`` steps."""

from __future__ import annotations

import sys
import time
from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from .integrators.base import Integrator, Problem


@dataclass(frozen=True)
class Trajectory:
    """Recorded states.

    t : ndarray, shape (S,)
    x, v : ndarray, shape (S, N, B)
    """

    t: np.ndarray = field(repr=False)
    x: np.ndarray = field(repr=False)
    v: np.ndarray = field(repr=False)
    force_evals: int = 0


class Progress:
    """A minimal progress bar on stderr, shown only for long runs on a terminal."""

    def __init__(self, total: int, label: str, enabled: bool | None = None):
        self.total = max(total, 1)
        self.label = label
        self.enabled = sys.stderr.isatty() if enabled is None else enabled
        self.last = 0.0

    def update(self, done: int) -> None:
        if not self.enabled:
            return
        now = time.monotonic()
        if now - self.last < 0.2 and done < self.total:
            return
        self.last = now
        frac = done / self.total
        bar = "#" * int(30 * frac)
        sys.stderr.write(f"\r{self.label} [{bar:<30}] {100 * frac:5.1f}%")
        if done >= self.total:
            sys.stderr.write("\n")
        sys.stderr.flush()


def integrate(integrator: Integrator, problem: Problem, x0: np.ndarray, v0: np.ndarray, h: float,
              steps: int, record_every: int = 1,
              on_frame: Callable[[int, np.ndarray, np.ndarray], None] | None = None,
              progress: Progress | None = None) -> Trajectory:
    """Run ``steps`` steps of size ``h`` from (x0, v0).

    Parameters
    ----------
    x0, v0 : ndarray, shape (N,) or (N, B)
    h : float
    steps : int
    record_every : int
        Keep every ``record_every``-th state (the first is always kept, and the last).
    on_frame : callable, optional
        If given, frames are passed to it as ``on_frame(i, x, v)`` instead of
        being kept in memory (for chunked writing of long runs).

    Returns
    -------
    Trajectory
        ``t = i·h`` at the recorded indices; x, v shape (S, N, B) (B = 1 for 1-D input).
    """
    x0 = np.asarray(x0, dtype=float)
    squeeze = x0.ndim == 1
    if squeeze:
        x0 = x0[:, None]
        v0 = np.asarray(v0, dtype=float)[:, None]
    idx = list(range(0, steps + 1, record_every))
    if idx[-1] != steps:
        idx.append(steps)
    keep = set(idx)
    xs, vs = [], []
    state = integrator.init(problem, x0, v0)

    def record(st):
        if on_frame is not None:
            on_frame(st.i, st.x, st.v)
        else:
            xs.append(st.x)
            vs.append(st.v)

    record(state)
    for _ in range(steps):
        state = integrator.step(problem, state, h)
        if state.i in keep:
            record(state)
        if progress is not None and state.i % 256 == 0:
            progress.update(state.i)
    if progress is not None:
        progress.update(steps)
    t = np.asarray(idx, dtype=float) * h
    evals = 1 + int(round(integrator.evals_per_step * steps))
    if on_frame is not None:
        return Trajectory(t, np.empty((0,)), np.empty((0,)), evals)
    return Trajectory(t, np.stack(xs), np.stack(vs), evals)
