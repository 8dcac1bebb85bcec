"""Integrators for scenes with dampers and time-dependent forces, from any conservative integrator.

* **Time-dependent forces**: time becomes one more coordinate that drifts
  with unit velocity and feels no force, so every kick of the inner method
  sees ``a(x) + a_ext(t)`` at its own stage time and the method keeps its
  order. After each step the time row is reset to exactly ``(i+1)·h``.
* **Linear damping**: Strang splitting with the exact damping flow
  ``v ← exp(-M⁻¹C h/2) v`` around each conservative step: second order,
  unconditionally stable in the damping, and symmetric. For a long ``[chain]`` the damping
  matrix is sparse (a dashpot list) and the half flow is its Crank–Nicolson (Cayley)
  approximation ``(I − A h/4)⁻¹(I + A h/4)``: also second order, symmetric and stable for
  any h, by one sparse LU solve per half step (never N × N).

Scenes without dampers or forces never go through this module.
"""

from __future__ import annotations

from typing import Callable

import numpy as np
import scipy.linalg

from ..integrators.base import Integrator, Problem, State  # noqa: F401  (State: the contract's type)


class EffectSplitting(Integrator):
    """Wrap a conservative integrator for damping (matrix ``A_d = -M⁻¹C``) and forcing ``a_ext(t)``.

    The state's arrays carry one extra row (time) when ``external`` is given:
    x, v, a have shape (N + 1, B); :func:`strip` removes it.
    """

    def __init__(self, inner: Integrator, damping: np.ndarray | None,
                 external: Callable[[float], np.ndarray] | None):
        self.inner = inner
        self.damping = damping
        self.external = external
        self.name = inner.name
        self.order = min(inner.order, 2) if damping is not None else inner.order
        self.symplectic = inner.symplectic and damping is None
        self.evals_per_step = inner.evals_per_step
        self.stability_limit = inner.stability_limit
        self._flow: dict[float, np.ndarray] = {}
        self._augmented: tuple[Problem, Problem] | None = None

    def _augment(self, problem: Problem) -> Problem:
        if self.external is None:
            return problem
        if self._augmented is not None and self._augmented[0] is problem:
            return self._augmented[1]
        ext, acc = self.external, problem.acceleration

        def acceleration(xa):
            out = np.zeros_like(xa)
            out[:-1] = acc(xa[:-1]) + np.asarray(ext(float(xa[-1, 0])), dtype=float).reshape(-1, 1)
            return out

        self._augmented = (problem, Problem(acceleration))
        return self._augmented[1]

    def refusal(self, problem: Problem) -> str | None:
        return self.inner.refusal(self._augment(problem))

    def init(self, problem: Problem, x0: np.ndarray, v0: np.ndarray) -> State:
        x0 = np.asarray(x0, dtype=float)
        v0 = np.asarray(v0, dtype=float)
        if self.external is not None:
            x0 = np.vstack([x0, np.zeros((1, x0.shape[1]))])
            v0 = np.vstack([v0, np.ones((1, v0.shape[1]))])
        return self.inner.init(self._augment(problem), x0, v0)

    def _half_flow(self, h: float):
        """``v ↦ exp(A h/2) v`` (dense A) or its Cayley approximation (sparse A), as a matrix or a function."""
        if h not in self._flow:
            import scipy.sparse

            if scipy.sparse.issparse(self.damping):
                import scipy.sparse.linalg

                eye = scipy.sparse.identity(self.damping.shape[0], format="csc")
                lu = scipy.sparse.linalg.splu((eye - self.damping * (0.25 * h)).tocsc())
                plus = (eye + self.damping * (0.25 * h)).tocsr()
                self._flow[h] = lambda v: lu.solve(np.asarray(plus @ v))
            else:
                self._flow[h] = scipy.linalg.expm(self.damping * (0.5 * h))
        return self._flow[h]

    def kernel(self, problem: Problem, h: float):
        """Strang splitting: half damping flow, the inner step on the (time-augmented) problem,
        time row reset to ``(i+1)·h``, half damping flow."""
        inner = self.inner.kernel(self._augment(problem), h)
        E = self._half_flow(h) if self.damping is not None else None
        forced = self.external is not None

        nd = None if self.damping is None else self.damping.shape[0]

        def damp(v):
            v = v.copy()
            v[:nd] = E(v[:nd]) if callable(E) else E @ v[:nd]
            return v

        def step(x, v, a, i):
            if E is not None:
                v = damp(v)
            x, v, a = inner(x, v, a, i)
            if forced:
                x = x.copy()
                x[-1] = (i + 1) * h  # t = i·h exactly
            if E is not None:
                v = damp(v)
            return x, v, a

        return step
