"""The shared contract of the step-based integrators.

An integrator is a pair of pure functions over a small immutable state:
``init(problem, x0, v0) -> State`` and ``step(problem, state, h) -> State``.
It declares its ``name``, ``order``, whether it is ``symplectic`` and its
``evals_per_step``; the driver (:mod:`numeric.run.driver`) owns the loop, the
time grid ``t = i·h`` and recording.

The hot loop does not build a :class:`State` per step: every integrator
also provides :meth:`Integrator.kernel`, a closure over the problem and the
step size that maps the arrays ``(x, v, a, i) -> (x, v, a)``. ``step`` is
that kernel wrapped in the :class:`State` API. Kernels never modify their
inputs, so the driver may keep references to the arrays it records.
"""

from __future__ import annotations

import abc
import math
from dataclasses import dataclass, field, replace
from typing import TYPE_CHECKING, Callable, ClassVar

import numpy as np

from ..errors import RunRefused

if TYPE_CHECKING:  # pragma: no cover
    from ..modes.spectrum import Spectrum
    from ..system import System

#: ``kernel(x, v, a, i) -> (x, v, a)``: one step from the state at ``t = i·h``; arrays shape (N, B).
StepKernel = Callable[[np.ndarray, np.ndarray, "np.ndarray | None", int],
                      "tuple[np.ndarray, np.ndarray, np.ndarray | None]"]


@dataclass(frozen=True)
class LinearChain:
    """The springs of a linear chain, for methods that need the operator itself.

    The problem's acceleration must then be exactly ``a(x) = -M⁻¹ K x`` with
    ``K = Bᵀ diag(k) B`` (``B``: spring–mass incidence, walls included).

    Attributes
    ----------
    masses : ndarray, shape (N,)
    spring_ends : ndarray of int, shape (S, 2)
        Mass indices of the spring ends, -1 for a wall.
    stiffness : ndarray, shape (S,)
    """

    masses: np.ndarray = field(repr=False)
    spring_ends: np.ndarray = field(repr=False)
    stiffness: np.ndarray = field(repr=False)

    def __post_init__(self):
        m = np.asarray(self.masses, dtype=float)
        ends = np.asarray(self.spring_ends, dtype=np.intp).reshape(-1, 2)
        k = np.asarray(self.stiffness, dtype=float)
        if m.ndim != 1 or k.ndim != 1 or k.shape[0] != ends.shape[0]:
            raise ValueError(f"LinearChain: masses must have shape (N,), stiffness (S,) and spring_ends (S, 2); "
                             f"got {m.shape}, {k.shape}, {ends.shape}")
        if not np.all(m > 0):
            raise ValueError("LinearChain: masses must be positive")
        if ends.size and (ends.min() < -1 or ends.max() >= m.shape[0]):
            raise ValueError(f"LinearChain: spring_ends must be mass indices 0..{m.shape[0] - 1} or -1 (wall)")
        object.__setattr__(self, "masses", m)
        object.__setattr__(self, "spring_ends", ends)
        object.__setattr__(self, "stiffness", k)

    @property
    def n(self) -> int:
        return int(self.masses.shape[0])

    def spectrum(self) -> "Spectrum":
        """Frequencies and modes by the accurate SVD route (:func:`numeric.modes.spectrum.spectrum`)."""
        from ..modes.spectrum import spectrum

        return spectrum(self.masses, self.spring_ends, self.stiffness)

    def omega2_bound(self) -> float:
        """A rigorous upper bound on ω²_max (:func:`numeric.modes.bounds.omega2_bound`)."""
        from ..modes.bounds import omega2_bound

        return omega2_bound(self.masses, self.spring_ends, self.stiffness)


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
    linear : LinearChain or None
        The chain's springs when ``acceleration`` is exactly ``-M⁻¹K x``; needed
        only by the propagators (``expm``, ``chebyshev``). None (the default)
        for nonlinear scenes or when unknown.
    """

    acceleration: Callable[[np.ndarray], np.ndarray]
    damping: Callable[[np.ndarray], np.ndarray] | None = None
    external: Callable[[float], np.ndarray] | None = None
    linear: LinearChain | None = None

    @classmethod
    def from_system(cls, system: "System") -> "Problem":
        """The conservative problem of a :class:`~numeric.system.System`, with its springs if it is linear."""
        chain = None
        if system.linear and system.effects <= frozenset({"spring", "potential"}):  # a quadratic potential is linear
            chain = LinearChain(system.masses, system.spring_ends, system.stiffness)
        from ..compiled.fast import acceleration_of  # a long potential chain: its compiled law

        return cls(acceleration_of(system), linear=chain)


@dataclass(frozen=True)
class State:
    """Positions, velocities and the acceleration at them, at step index ``i``.

    x, v : ndarray, shape (N, B)
    a : ndarray, shape (N, B), or None for propagators that never evaluate the force
    """

    x: np.ndarray = field(repr=False)
    v: np.ndarray = field(repr=False)
    a: np.ndarray | None = field(repr=False)
    i: int = 0

    def replace(self, **changes) -> "State":
        return replace(self, **changes)


class Integrator(abc.ABC):
    """Base class of fixed-step integrators.

    Subclasses declare the class attributes below and implement :meth:`kernel`.
    """

    #: Name used on the command line and in NPZ keys.
    name: ClassVar[str]
    #: Global order of accuracy; ``math.inf`` for propagators exact up to roundoff.
    order: ClassVar[float]
    symplectic: ClassVar[bool]
    #: Force evaluations per step (the one at the start is kept in the state).
    evals_per_step: ClassVar[float] = 1.0
    #: Force evaluations made by :meth:`init`.
    init_evals: ClassVar[int] = 1
    #: Largest stable ``ω_max·h`` on a linear chain (``math.inf``: any step).
    stability_limit: ClassVar[float] = 2.0
    #: Whether the method integrates ``damping`` (otherwise it refuses a problem with dampers).
    supports_damping: ClassVar[bool] = False

    def refusal(self, problem: Problem) -> str | None:
        """Why this method cannot integrate ``problem`` (None when it can)."""
        if problem.damping is not None and not self.supports_damping:
            return (f"method {self.name!r} integrates conservative and external forces only; "
                    f"this scene has dampers: use rk4 or an adaptive method (rk45, dop853, lsoda)")
        return None

    def check(self, problem: Problem) -> None:
        """Refuse a problem this method cannot integrate (raises :class:`~numeric.errors.RunRefused`)."""
        why = self.refusal(problem)
        if why:
            raise RunRefused(why, quantity="method")

    def init(self, problem: Problem, x0: np.ndarray, v0: np.ndarray) -> State:
        """The state at ``i = 0``. x0, v0 : array_like, shape (N, B)."""
        self.check(problem)
        x0 = np.array(x0, dtype=float)
        v0 = np.array(v0, dtype=float)
        a0 = self.force(problem, x0, 0.0) if self.init_evals else None
        return State(x0, v0, a0, 0)

    @staticmethod
    def force(problem: Problem, x: np.ndarray, t: float) -> np.ndarray:
        """``a(x) + a_ext(t)`` (the position-dependent part the kicks use)."""
        a = problem.acceleration(x)
        if problem.external is not None:
            a = a + np.reshape(problem.external(t), (-1, 1))
        return a

    def evals_for(self, problem: Problem, h: float) -> float:
        """Force evaluations per step for this problem and step (the class constant unless overridden)."""
        return self.evals_per_step

    def force_evals(self, problem: Problem, h: float, steps: int) -> int:
        """Total force evaluations of ``steps`` steps, the initial one included."""
        return self.init_evals + int(round(self.evals_for(problem, h) * steps))

    @abc.abstractmethod
    def kernel(self, problem: Problem, h: float) -> StepKernel:
        """A step function on arrays, ``(x, v, a, i) -> (x, v, a)``, for step ``h`` on ``problem``.

        Built once per run (expensive set-up such as a matrix exponential goes here);
        the returned callable is the hot loop's body and never modifies its inputs.
        """

    def step(self, problem: Problem, state: State, h: float) -> State:
        """Advance one step of size ``h`` from ``state`` (at time ``state.i * h``)."""
        cache = getattr(self, "_kernel_cache", None)
        if cache is None or cache[0] is not problem or cache[1] != h:
            cache = (problem, h, self.kernel(problem, h))
            self._kernel_cache = cache
        x, v, a = cache[2](state.x, state.v, state.a, state.i)
        return State(x, v, a, state.i + 1)


def finite_positive(h: float) -> float:
    """Validate a step size (ValueError naming the value)."""
    h = float(h)
    if not (math.isfinite(h) and h > 0):
        raise ValueError(f"step size h must be finite and > 0, got {h!r}")
    return h
