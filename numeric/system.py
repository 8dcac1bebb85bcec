"""A generated module bound to parameter values: the numbers every numeric method consumes."""

from __future__ import annotations

from dataclasses import dataclass, field
from types import ModuleType
from typing import Callable

import numpy as np


@dataclass(frozen=True)
class System:
    """A scene's generated equations at fixed parameter values.

    Attributes
    ----------
    module : module
        The generated module.
    params : dict of str to float
        Parameter values (keyword arguments of the module's functions).
    masses : ndarray, shape (N,)
    spring_ends : ndarray of int, shape (S, 2)
        Mass indices of the spring ends, -1 for a wall.
    stiffness : ndarray, shape (S,)
    """

    module: ModuleType
    params: dict[str, float]
    masses: np.ndarray = field(repr=False)
    spring_ends: np.ndarray = field(repr=False)
    stiffness: np.ndarray = field(repr=False)

    @classmethod
    def from_module(cls, module: ModuleType, params: dict[str, float] | None = None) -> "System":
        values = dict(module.DEFAULTS)
        values.update(params or {})
        if getattr(module, "CHAIN", False):
            ends = np.asarray(module.spring_ends(), dtype=np.intp).reshape(-1, 2)
        else:
            ends = np.asarray(module.SPRING_ENDS, dtype=np.intp).reshape(-1, 2)
        return cls(module, values, np.asarray(module.masses(**values), dtype=float),
                   ends, np.asarray(module.spring_constants(**values), dtype=float))

    @property
    def chain(self) -> bool:
        """A [chain] scene: stencil acceleration, no dense matrices for large n."""
        return bool(getattr(self.module, "CHAIN", False))

    @property
    def n(self) -> int:
        return int(self.masses.shape[0])

    @property
    def effects(self) -> frozenset[str]:
        return frozenset(self.module.EFFECTS)

    @property
    def linear(self) -> bool:
        return bool(self.module.LINEAR)

    def acceleration(self, x: np.ndarray) -> np.ndarray:
        """Conservative acceleration a(x); x shape (N, ...)."""
        return self.module.acceleration(x, **self.params)

    @property
    def acceleration_fn(self) -> Callable[[np.ndarray], np.ndarray]:
        """a(x) with everything that does not depend on x computed once."""
        mod, p = self.module, self.params
        if hasattr(mod, "make_acceleration"):
            return mod.make_acceleration(**p, n=self.n) if self.chain else mod.make_acceleration(**p)
        return lambda x: mod.acceleration(x, **p)

    @property
    def damped(self) -> bool:
        return hasattr(self.module, "damping_matrix")

    @property
    def forced(self) -> bool:
        return hasattr(self.module, "external_acceleration")

    @property
    def conservative(self) -> bool:
        """Springs only (linear or cubic): no dampers, no external forces, no gravity.

        The one definition: bench, plan, the fused chain kernel and the modal
        solution without augmentation all ask this.
        """
        return not (self.damped or self.forced or "gravity" in self.effects)

    def damping_rate_matrix(self) -> np.ndarray | None:
        """``-M⁻¹C``, shape (N, N); None without dampers."""
        if not self.damped:
            return None
        return -np.asarray(self.module.damping_matrix(**self.params), dtype=float) / self.masses[:, None]

    @property
    def external_fn(self) -> Callable[[float], np.ndarray] | None:
        """``a_ext(t)`` shape (N,); None without external forces."""
        if not self.forced:
            return None
        mod, p = self.module, self.params
        return lambda t: mod.external_acceleration(t, **p)

    @property
    def exact_available(self) -> bool:
        """Whether an exact solution exists: linear, and forces (if any) constant + harmonic."""
        return self.linear and (not self.forced or bool(getattr(self.module, "FORCING_HARMONIC", False)))

    def energy(self, x: np.ndarray, v: np.ndarray) -> np.ndarray:
        """Total energy; x, v shape (N, ...) -> (...)."""
        return self.module.energy(x, v, **self.params)

    def momentum(self, v: np.ndarray) -> np.ndarray:
        """Total momentum Σ m_i v_i; v shape (N, ...) -> (...)."""
        return np.tensordot(self.masses, v, axes=(0, 0))
