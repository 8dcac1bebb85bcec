"""Classic fourth-order Runge–Kutta on the first-order system ``(x, v)' = (v, a(x) + a_damp(v) + a_ext(t))``.

Not symplectic: on an undamped chain its energy decays steadily (the
amplification factor is ``1 − (ωh)⁶/72 + …`` per step). The force at the
step's end is kept in the state as the next step's first stage, so a step
costs 4 force evaluations.
"""

from __future__ import annotations

import math

import numpy as np

from .base import Integrator, Problem, StepKernel, finite_positive


class RK4(Integrator):
    """The classic Runge–Kutta method (Kutta 1901), order 4, 4 force evaluations per step."""

    name = "rk4"
    order = 4
    symplectic = False
    evals_per_step = 4.0
    #: Stable (non-growing) on the imaginary axis up to |ωh| = 2√2.
    stability_limit = 2.0 * math.sqrt(2.0)
    supports_damping = True

    def kernel(self, problem: Problem, h: float) -> StepKernel:
        h = finite_positive(h)
        self.check(problem)
        acc, damp, ext = problem.acceleration, problem.damping, problem.external
        h2, h6 = 0.5 * h, h / 6.0

        if damp is None and ext is None:
            def step(x, v, a, i):
                x2 = v + h2 * a
                a2 = acc(x + h2 * v)
                x3 = v + h2 * a2
                a3 = acc(x + h2 * x2)
                x4 = v + h * a3
                a4 = acc(x + h * x3)
                x = x + h6 * (v + 2.0 * (x2 + x3) + x4)
                v = v + h6 * (a + 2.0 * (a2 + a3) + a4)
                return x, v, acc(x)
            return step

        def force(x, t):
            f = acc(x)
            return f if ext is None else f + np.reshape(ext(t), (-1, 1))

        def total(f, v):
            return f if damp is None else f + damp(v)

        def step(x, v, a, i):
            t = i * h
            k1 = total(a, v)
            x2 = v + h2 * k1
            k2 = total(force(x + h2 * v, t + h2), x2)
            x3 = v + h2 * k2
            k3 = total(force(x + h2 * x2, t + h2), x3)
            x4 = v + h * k3
            k4 = total(force(x + h * x3, (i + 1) * h), x4)
            x = x + h6 * (v + 2.0 * (x2 + x3) + x4)
            v = v + h6 * (k1 + 2.0 * (k2 + k3) + k4)
            return x, v, force(x, (i + 1) * h)
        return step
