"""The exact step of a linear chain: ``exp(h [[0, I], [−M⁻¹K, 0]])``, built from the spectrum.

In mass-weighted modal coordinates the step is a rotation per mode,
``[[cos ωh, sin(ωh)/ω], [−ω sin ωh, cos ωh]]`` (with ``sin(ωh)/ω`` written
``h·sinc(ωh)``, exact for the rigid modes). Transformed back to physical
coordinates this is the matrix exponential of the first-order system for the
step ``h``, accurate to roundoff even for stiff chains because the
frequencies come from the SVD of the spring factor (:mod:`numeric.modes.spectrum`),
not from an eigen-solve of ``M⁻¹K``. Set-up ``O(N³)`` (once per run), then one
``(2N × 2N)`` matrix product per step; no force evaluations.
"""

from __future__ import annotations

import numpy as np

from ..exact.modal import tsinc
from .base import Problem, StepKernel, finite_positive
from .propagator import LinearPropagator


def step_matrix(problem: Problem, h: float) -> np.ndarray:
    """``Φ = exp(h A)`` of the first-order system, shape (2N, 2N), acting on ``[x; v]``."""
    spec = problem.linear.spectrum()
    w = spec.omega
    c, s = np.cos(w * h), tsinc(w, h)
    r = np.sqrt(spec.masses)
    E = spec.vectors
    left = E / r[:, None]             # M^-1/2 E
    right = E.T * r[None, :]          # Eᵀ M^1/2
    n = r.shape[0]
    phi = np.empty((2 * n, 2 * n))
    phi[:n, :n] = (left * c) @ right
    phi[:n, n:] = (left * s) @ right
    phi[n:, :n] = (left * (-(w**2) * s)) @ right
    phi[n:, n:] = phi[:n, :n]
    return phi


class MatrixExponential(LinearPropagator):
    """Exact propagator of an undamped, unforced linear chain (needs ``Problem.linear``)."""

    name = "expm"
    evals_per_step = 0.0

    def kernel(self, problem: Problem, h: float) -> StepKernel:
        h = finite_positive(h)
        self.check(problem)
        phi = step_matrix(problem, h)
        n = problem.linear.n

        def step(x, v, a, i):
            y = phi @ np.concatenate((x, v))
            return y[:n], y[n:], None
        return step
