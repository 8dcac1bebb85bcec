"""Velocity Verlet, exactly the reference scheme (one force evaluation per step)."""

from __future__ import annotations

import numpy as np

from .base import Integrator, Problem, StepKernel, finite_positive


class VelocityVerlet(Integrator):
    """``x ← x + v h + a h²/2;  a' = a(x);  v ← v + (a + a') h/2``.

    Second order, symplectic and time-reversible for conservative forces; the
    acceleration is kept in the state so each step evaluates it once. An
    external force ``a_ext(t)`` is added to ``a`` at ``t = (i + 1)·h``.
    """

    name = "verlet"
    order = 2
    symplectic = True
    evals_per_step = 1.0
    stability_limit = 2.0

    def kernel(self, problem: Problem, h: float) -> StepKernel:
        h = finite_positive(h)
        self.check(problem)
        acc, ext = problem.acceleration, problem.external
        hh, h2 = 0.5 * h * h, 0.5 * h

        if ext is None:
            def step(x, v, a, i):
                x = x + h * v + hh * a
                a_new = acc(x)
                return x, v + h2 * (a + a_new), a_new
        else:
            def step(x, v, a, i):
                x = x + h * v + hh * a
                a_new = acc(x) + np.reshape(ext((i + 1) * h), (-1, 1))
                return x, v + h2 * (a + a_new), a_new
        return step
