"""Wall-clock timing for benchmarks: single-threaded BLAS, a warm-up, the minimum of repeats.

On this kind of small box OpenBLAS's threading makes tiny matrix products
slower and noisier, so every timed region runs inside
:func:`single_threaded_blas`. A measurement is the *minimum* of several
repeats after a warm-up (the minimum estimates the cost without
interference from other processes; the median is kept for reference).
Long runs are repeated fewer times: repeats stop once their total time
exceeds a budget, but at least one timed run always follows the warm-up.
"""

from __future__ import annotations

import contextlib
import math
import time
from dataclasses import dataclass
from typing import Callable, Generic, Iterator, TypeVar

import numpy as np

T = TypeVar("T")


@contextlib.contextmanager
def single_threaded_blas() -> Iterator[None]:
    """Limit BLAS/OpenMP pools to one thread for the duration of the block."""
    from threadpoolctl import threadpool_limits

    with threadpool_limits(limits=1):
        yield


@dataclass(frozen=True)
class Timing(Generic[T]):
    """The result of :func:`measure`.

    Attributes
    ----------
    seconds : float
        Minimum over the timed repeats.
    median : float
        Median over the timed repeats.
    repeats : int
        Number of timed repeats (the warm-up excluded).
    result : object
        The value returned by the last call.
    """

    seconds: float
    median: float
    repeats: int
    result: T


def measure(run: Callable[[], T], *, warmup: Callable[[], object] | None = None, budget: float = 0.5,
            max_repeats: int = 7, min_repeats: int = 1) -> Timing[T]:
    """Time ``run()``: a warm-up, then repeats until ``budget`` seconds are spent.

    Parameters
    ----------
    run : callable
        The work to time, with all its own set-up inside.
    warmup : callable, optional
        A cheaper call that warms the same code paths (e.g. the same method on
        a short horizon). Default: one untimed call of ``run`` itself, unless
        ``run`` turns out to be long (> ``budget``), in which case the first
        call is both warm-up and the only repeat needed to stay in budget.
    budget : float
        Total seconds of timed repeats after which no further repeat starts.
    max_repeats, min_repeats : int
        Bounds on the number of timed repeats.

    Returns
    -------
    Timing
    """
    times: list[float] = []
    if warmup is not None:
        warmup()
    else:
        t0 = time.perf_counter()
        result = run()
        first = time.perf_counter() - t0
        if first > budget:  # a long run: its own first call is warm enough (caches warm in ms)
            times.append(first)
    while len(times) < max_repeats and (len(times) < min_repeats or sum(times) < budget):
        t0 = time.perf_counter()
        result = run()
        times.append(time.perf_counter() - t0)
        if len(times) >= min_repeats and times[-1] > budget:
            break
    return Timing(float(min(times)), float(np.median(times)), len(times), result)


# -- minimum-of-repeats and interleaved timing (the scaling study) -------------------------------
def best_seconds(fn: Callable[[], object], *, budget: float = 0.25, max_repeats: int = 9, min_time: float = 2e-3,
                 warmup: bool = True) -> float:
    """Minimum seconds per call of ``fn`` after a warm-up.

    A call longer than ``budget`` is timed once (its own first run). Short calls
    are batched so that one timed sample lasts at least
    ``min_time``; samples are repeated until ``budget`` seconds are spent
    (at least one, at most ``max_repeats``).
    """
    if warmup:
        t0 = time.perf_counter()
        fn()
        first = time.perf_counter() - t0
        if first > budget:  # a long call (an O(N³) set-up): its caches are warm within it; one run is enough
            return float(first)
    else:
        first = 0.0
    inner = 1 if first >= min_time else int(min(10_000, max(1, math.ceil(min_time / max(first, 1e-7)))))
    samples: list[float] = []
    spent = 0.0
    while len(samples) < max_repeats and (not samples or spent < budget):
        t0 = time.perf_counter()
        for _ in range(inner):
            fn()
        dt = time.perf_counter() - t0
        spent += dt
        samples.append(dt / inner)
    return float(min(samples))


def interleaved_samples(calls: dict[str, tuple[Callable[[], object], int]], *, budget: float,
                        min_rounds: int = 5, max_rounds: int = 200, min_time: float = 2e-3) -> dict[str, list[float]]:
    """Seconds per unit of several calls timed in turns, so that they share the same conditions.

    Parameters
    ----------
    calls : dict of name -> (callable, units per call)
        E.g. ``(advance, 100)`` for a call that makes 100 steps.
    budget : float
        Seconds after which no new round starts (at least ``min_rounds`` rounds).

    Returns
    -------
    dict of name -> list of float
        One sample per round, in round order (so samples of one round can be paired).

    Each call is warmed up once and batched so that one sample lasts at least
    ``min_time``; a round times every call once.
    """
    inner = {}
    for name, (fn, _) in calls.items():
        t0 = time.perf_counter()
        fn()
        first = time.perf_counter() - t0
        inner[name] = int(min(10_000, max(1, math.ceil(min_time / max(first, 1e-7)))))
    samples: dict[str, list[float]] = {name: [] for name in calls}
    spent, rounds = 0.0, 0
    while rounds < min_rounds or (spent < budget and rounds < max_rounds):
        for name, (fn, units) in calls.items():
            t0 = time.perf_counter()
            for _ in range(inner[name]):
                fn()
            dt = time.perf_counter() - t0
            spent += dt
            samples[name].append(dt / (inner[name] * units))
        rounds += 1
    return samples


def interleaved_seconds(calls: dict[str, tuple[Callable[[], object], int]], **kw) -> dict[str, float]:
    """The minimum of :func:`interleaved_samples` for each call."""
    return {name: float(min(v)) for name, v in interleaved_samples(calls, **kw).items()}
