"""Tolerance-driven methods as methods: SciPy's ``rk45``, ``dop853``, ``lsoda`` on the first-order
system and the Runge–Kutta–Nyström pairs ``dprkn6/8/12`` on ``ẍ = f(t, x)``.

:meth:`AdaptiveRun.problem` is the one place the full problem (springs, damping, forces) is built
for them, and :meth:`AdaptiveRun.refusal` the one statement of which of them apply to a system.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from ...generated.contract import MAX_DENSE
from ..integrators.base import Problem
from ..integrators.ivp import AdaptiveMethod
from ..progress import phase
from ..system import System
from .protocol import Kind, Method


def full_problem(system: System) -> Problem:
    """``ẍ = a(x) − M⁻¹C ẋ + a_ext(t)``: everything the system has, for methods that integrate it whole."""
    Ad = system.damping_rate_matrix()
    from ..compiled.fast import acceleration_of  # a long potential chain: its compiled law

    return Problem(acceleration_of(system), damping=None if Ad is None else (lambda v: Ad @ v),
                   external=system.external_fn)


@dataclass(frozen=True)
class AdaptiveRun(Method):
    """An adaptive method (the ``implementation``, an :class:`AdaptiveMethod` subclass), evaluated on the
    grid's times with the options' tolerances."""

    kind: ClassVar[Kind] = Kind.ADAPTIVE

    @property
    def solver_class(self) -> type[AdaptiveMethod]:
        return self.implementation

    def refusal(self, system: System) -> str | None:
        own = getattr(self.solver_class, "refusal", None)  # a compiled peer: the scenes it compiles
        if own is not None and own(system):
            return own(system)
        if system.damped and not self.solver_class.supports_damping:
            return ("a Runge–Kutta–Nyström pair integrates x'' = f(t, x) and this scene has dampers; "
                    "use dop853, rk45 or lsoda")
        if self.solver_class.dense_jacobian and system.n > MAX_DENSE:
            return (f"it keeps a dense N x N Jacobian: at most {MAX_DENSE} masses (this scene has {system.n}); "
                    "use dop853 or a step method")
        return None

    def problem(self, system: System) -> Problem:
        return full_problem(system)

    def solve(self, system: System, x0: np.ndarray, v0: np.ndarray, t: np.ndarray, rtol: float, atol: float):
        """The solver's result on ``t`` (:class:`~numeric.integrators.ivp.AdaptiveResult`), no recorder.
        The RKN pairs run compiled on small ``[masses]`` scenes (:func:`numeric.compiled.run.rkn`)."""
        if getattr(self.solver_class, "needs_system", False):  # dop853-compiled (numeric.compiled.peer)
            return self.solver_class().run_system(system, x0, v0, t, rtol, atol)
        table = getattr(self.solver_class, "table", None)
        if table is not None and self.options.compiled and np.ndim(x0) == 1 and not system.chain \
                and not system.damped:
            from ..compiled.run import rkn, scalar_ready, worth_compiling

            # a rough count: steps of the error control, and half a step per output time it steps onto
            evals = table.evals_per_step * (float(t[-1] - t[0]) * system.omega_max * rtol ** (-1.0 / table.order)
                                            + 0.5 * len(t))
            if rtol > 0 and atol > 0 and np.all(np.diff(t) > 0) and worth_compiling(system, "rkn_loop", evals) \
                    and scalar_ready(system):
                return rkn(system, table, x0, v0, t, rtol, atol)
        return self.solver_class().solve(self.problem(system), x0, v0, t, rtol, atol)

    def run(self, system, x0, v0, grid, recorder) -> int:
        self.check(system)
        with phase(self.name, enabled=self.options.progress):
            res = self.solve(system, x0, v0, grid.t, self.options.rtol, self.options.atol)
        recorder.frames(0, res.x[:, :, 0], res.v[:, :, 0])
        return res.force_evals


__all__ = ["AdaptiveRun", "full_problem"]
