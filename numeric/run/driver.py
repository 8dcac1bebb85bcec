"""The one loop: step an integrator on the grid ``t = i·h`` and record every ``record_every`` steps."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from ..integrators.base import Integrator, Problem
from ..progress import Reporter
from .grid import record_indices


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


def integrate(integrator: Integrator, problem: Problem, x0: np.ndarray, v0: np.ndarray, h: float,
              steps: int, record_every: int = 1,
              on_frame: Callable[[int, np.ndarray, np.ndarray], None] | None = None,
              progress: Reporter | None = None) -> Trajectory:
    """Run ``steps`` steps of size ``h`` from (x0, v0).

    The loop runs the integrator's array kernel (:meth:`Integrator.kernel`,
    built once) rather than building a :class:`State` per step; recorded
    states are written into preallocated arrays.

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
    v0 = np.asarray(v0, dtype=float)
    if x0.ndim == 1:
        x0, v0 = x0[:, None], v0[:, None]
    idx = record_indices(steps, record_every)
    state = integrator.init(problem, x0, v0)
    kernel = integrator.kernel(problem, h)
    x, v, a = state.x, state.v, state.a
    keep = on_frame is None
    if keep:
        xs = np.empty((idx.shape[0],) + x.shape)
        vs = np.empty_like(xs)
        xs[0], vs[0] = x, v
    else:
        on_frame(0, x, v)
    targets = idx.tolist()
    advance = getattr(kernel, "advance", None)
    if advance is not None and getattr(kernel, "inplace", False):
        # an in-place kernel with a multi-step sweep: run straight from frame to frame at the
        # sweep's speed, on private copies (the caller's arrays are never touched)
        x, v, a = (np.array(arr, dtype=float, order="C", copy=True) for arr in (x, v, a))
        done = 0
        for j, target in enumerate(targets[1:], start=1):
            x, v, a = advance(x, v, a, target - done)
            done = target
            if keep:
                xs[j], vs[j] = x, v
            else:
                on_frame(target, x, v)
            if progress is not None:
                progress.update(done)
    else:
        j = 1
        nxt = targets[1] if len(targets) > 1 else -1
        for i in range(steps):
            x, v, a = kernel(x, v, a, i)
            if i + 1 == nxt:
                if keep:
                    xs[j], vs[j] = x, v
                else:
                    on_frame(nxt, x, v)
                j += 1
                nxt = targets[j] if j < len(targets) else -1
            if progress is not None and not (i + 1) & 255:
                progress.update(i + 1)
    if progress is not None:
        progress.update(steps)
    t = idx.astype(float) * h
    evals = integrator.force_evals(problem, h, steps)
    if not keep:
        return Trajectory(t, np.empty((0,)), np.empty((0,)), evals)
    return Trajectory(t, xs, vs, evals)
