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
