"""The kick–drift loop shared by every splitting and composition method.

A subclass declares a :class:`~numeric.integrators.coefficients.SplittingTable`
as ``table``; ``order``, ``evals_per_step`` and ``stability_limit`` follow
from it. The force kept in the state is the last kick's, which is the next
step's first (first same as last).

External forcing ``a_ext(t)`` is applied in each kick at that kick's time
``t + c_j h`` (``t`` is advanced by the drifts as an extra coordinate, which
keeps the splitting's order).
"""

from __future__ import annotations

from typing import ClassVar

import numpy as np

from .base import Integrator, Problem, StepKernel, finite_positive
from .coefficients import SplittingTable


class _TableStabilityLimit:
    """``stability_limit`` read from the class's table on first use (a scan: no work at import)."""

    def __get__(self, obj, cls=None):
        return (cls or type(obj)).table.stability_limit


class SplittingMethod(Integrator):
    """A symplectic ``BAB`` splitting method given by its coefficient table."""

    table: ClassVar[SplittingTable]
    symplectic = True
    stability_limit = _TableStabilityLimit()

    def __init_subclass__(cls, **kwargs):
        super().__init_subclass__(**kwargs)
        table = cls.__dict__.get("table")
        if table is not None:
            cls.order = table.order
            cls.evals_per_step = float(table.stages)

    def kernel(self, problem: Problem, h: float) -> StepKernel:
        h = finite_positive(h)
        self.check(problem)
        kicks = [b * h for b in self.table.kicks]
        drifts = [a * h for a in self.table.drifts]
        acc = problem.acceleration
        ext = problem.external
        if ext is not None:
            nodes = self.table.nodes

            def acc_at(x, i, j):
                return acc(x) + np.reshape(ext((i + nodes[j]) * h), (-1, 1))
        first, rest = kicks[0], list(zip(drifts, kicks[1:]))

        if ext is None:
            def step(x, v, a, i):
                v = v + first * a
                for d, k in rest:
                    x = x + d * v
                    a = acc(x)
                    v = v + k * a
                return x, v, a
        else:
            def step(x, v, a, i):
                v = v + first * a
                for j, (d, k) in enumerate(rest, start=1):
                    x = x + d * v
                    a = acc_at(x, i, j)
                    v = v + k * a
                return x, v, a
        return step
