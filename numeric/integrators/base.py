"""The shared contract of the step-based integrators.

An integrator is a pair of pure functions over a small immutable state:
``init(problem, x0, v0) -> State`` and ``step(problem, state, h) -> State``.
It declares its ``order`` and whether it is ``symplectic``; the driver
(:mod:`numeric.driver`) owns the loop, the time grid ``t = i·h`` and recording.
"""

from __future__ import annotations

import abc
from dataclasses import dataclass, field, replace
from typing import Callable, ClassVar

import numpy as np


@dataclass(frozen=True)
class Problem:
    """What a step needs: ``ẍ = a(x) + a_damp(v) + a_ext(t)``.

    Attributes
    ----------
    acceleration : callable
        Conservative acceleration ``a(x)``; x shape (N, B) -> (N, B).
    damping : callable or None
        ``a_damp(v)``, linear in v; None for a scene without dampers.
    external : callable or None
        ``a_ext(t)`` -> (N,) or (N, 1); None for a scene without forces.
    """

    acceleration: Callable[[np.ndarray], np.ndarray]
    damping: Callable[[np.ndarray], np.ndarray] | None = None
    external: Callable[[float], np.ndarray] | None = None


@dataclass(frozen=True)
class State:
    """Positions, velocities and the acceleration at them, at step index ``i``.

    x, v, a : ndarray, shape (N, B)
    """

    x: np.ndarray = field(repr=False)
    v: np.ndarray = field(repr=False)
    a: np.ndarray = field(repr=False)
    i: int = 0

    def replace(self, **changes) -> "State":
        return replace(self, **changes)


class Integrator(abc.ABC):
    """Base class of fixed-step integrators."""

    #: Name used on the command line and in NPZ keys.
    name: ClassVar[str]
    #: Global order of accuracy.
    order: ClassVar[int]
    symplectic: ClassVar[bool]
    #: Force evaluations per step (after the first, kept in the state).
    evals_per_step: ClassVar[float] = 1.0

    def init(self, problem: Problem, x0: np.ndarray, v0: np.ndarray) -> State:
        x0 = np.array(x0, dtype=float)
        v0 = np.array(v0, dtype=float)
        return State(x0, v0, problem.acceleration(x0), 0)

    @abc.abstractmethod
    def step(self, problem: Problem, state: State, h: float) -> State:
        """Advance one step of size ``h`` from ``state`` (at time ``state.i * h``)."""
