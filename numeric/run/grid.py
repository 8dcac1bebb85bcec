"""The one output grid: recorded times ``t = i·h`` for ``i`` in ``0, k, 2k, …`` and always ``steps``.

Every caller (simulate, plan, bench, their pilots and references) builds its times here; nothing
else computes step counts or recorded indices.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property

import numpy as np


def step_count(t_end: float, h_target: float) -> int:
    """``ceil(t_end/h_target)`` steps, a quotient within 1e-9 steps of an integer counting as that
    integer (so ``t_end = 100, h_target = 0.1`` gives 1000 steps whatever the rounding)."""
    t_end, h_target = float(t_end), float(h_target)
    if not (math.isfinite(t_end) and t_end > 0 and math.isfinite(h_target) and h_target > 0):
        raise ValueError(f"need t_end > 0 and h_target > 0 (finite), got {t_end!r}, {h_target!r}")
    q = t_end / h_target
    return max(1, int(math.ceil(q - 1e-9 * max(1.0, q))))


def record_indices(steps: int, record_every: int) -> np.ndarray:
    """Recorded step indices: every ``record_every``-th, and always 0 and ``steps``; shape (S,)."""
    if steps < 0 or record_every < 1:
        raise ValueError(f"need steps >= 0 and record_every >= 1, got {steps}, {record_every}")
    idx = np.arange(0, steps + 1, record_every)
    return idx if idx[-1] == steps else np.append(idx, steps)


def step_grid(t_end: float, h_target: float) -> tuple[float, int]:
    """``(h, n)`` of :meth:`Grid.covering`: ``n = ceil(t_end/h_target)`` steps of ``h = t_end/n``."""
    g = Grid.covering(t_end, h_target)
    return g.h, g.steps


@dataclass(frozen=True)
class Grid:
    """``steps`` steps of size ``h`` (times ``t = i·h``), every ``record_every``-th state recorded, and
    always the last one."""

    h: float  #: the step
    steps: int  #: the number of steps (the last time is ``steps·h``)
    record_every: int = 1  #: the recording stride

    def __post_init__(self):
        if not (math.isfinite(self.h) and self.h > 0):
            raise ValueError(f"step size h must be finite and > 0, got {self.h!r}")
        record_indices(self.steps, self.record_every)  # validates

    @classmethod
    def covering(cls, t_end: float, h_target: float, record_every: int = 1) -> "Grid":
        """The grid over ``[0, t_end]`` with ``h = t_end/n ≤ h_target``, ``n = ceil(t_end/h_target)``."""
        n = step_count(t_end, h_target)
        return cls(float(t_end) / n, n, record_every)

    @classmethod
    def frames_of(cls, spacing: float, frames: int) -> "Grid":
        """``frames`` recorded times ``k·spacing``, k = 0 … frames − 1 (one step per frame)."""
        return cls(float(spacing), max(int(frames) - 1, 0))

    @cached_property
    def indices(self) -> np.ndarray:
        """Recorded step indices, shape (S,)."""
        return record_indices(self.steps, self.record_every)

    @property
    def t(self) -> np.ndarray:
        """Recorded times, shape (S,)."""
        return self.indices * self.h

    @property
    def frames(self) -> int:
        """Number of recorded times S."""
        return int(self.indices.shape[0])

    @property
    def t_end(self) -> float:
        return self.steps * self.h

    @property
    def spacing(self) -> float:
        """Time between recorded frames (the last interval may be shorter)."""
        return self.h * self.record_every


__all__ = ["Grid", "step_count", "step_grid", "record_indices"]
