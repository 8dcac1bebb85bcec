"""Implicit step methods as methods: integrators built on the system's own operators.

An implicit step (Newmark-β, HHT-α: :mod:`numeric.integrators.newmark`) solves with the scene's
stiffness, damping and loads, so it is built on the :class:`~numeric.system.System` (the
integrator class's ``for_system(system, **settings)``) and integrates damping, forces and ground
motion in its step instead of inside a splitting. Its per-mode propagator is rational in ``z = ωh``,
known in closed form: the integrator's ``response()`` gives plan's error models. Settings it takes
(its class's ``settings``, e.g. HHT's ``alpha``) come from the run's
:attr:`~.protocol.Options.settings` and are checked when the method is made.

A registry entry names :class:`ImplicitStep` as the runner of such an integrator; nothing else
in the run layer knows about it.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..integrators.base import Integrator
from ..system import System
from .step import StepMethod


@dataclass(frozen=True)
class ImplicitStep(StepMethod):
    """A fixed-step implicit integrator run on the system's operators (see the module docstring)."""

    def __post_init__(self):
        self.integrator_class(**self._settings())  # refuses settings out of range, naming them

    @property
    def takes(self) -> tuple[str, ...]:
        return tuple(self.integrator_class.settings)

    def _settings(self) -> dict:
        return {k: v for k, v in self.options.settings if k in self.takes}

    def integrator(self, system: System) -> Integrator:
        """The integrator on ``system``'s stiffness, damping and loads (no splitting around it)."""
        return self.integrator_class.for_system(system, **self._settings())

    def refusal(self, system: System) -> str | None:
        """The step solves with the stiffness of linear and cubic springs: a scene with spring
        potentials is refused (before its operator is built)."""
        if system.potential:
            return ("solves with the stiffness of linear and cubic springs; this scene has spring potentials: "
                    "use verlet, an RKN pair or an adaptive method")
        return super().refusal(system)

    def compiled_loop(self, system: System, integ: Integrator, grid) -> str | None:
        """The compiled loop of a small ``[masses]`` scene (:func:`numeric.compiled.implicit.route`), or None."""
        if not self.options.compiled or system.chain:
            return None
        from ..compiled.implicit import route

        return route(system, integ, grid.frames, max(integ.evals_per_step, 1.0) * grid.steps)

    def run(self, system, x0, v0, grid, recorder) -> int:
        """The whole run compiled where :meth:`compiled_loop` says so (frames handed over at once), else
        :meth:`StepMethod.run` (the NumPy driver)."""
        if np.ndim(x0) != 1 or self.compiled_loop(system, self.integrator(system), grid) is None:
            return super().run(system, x0, v0, grid, recorder)
        from ..compiled.implicit import run_newmark
        from ..errors import RunRefused
        from .step import stability_refusal

        integ = self.integrator(system)
        integ.check(self.problem(system))
        why = stability_refusal(system, grid.h, self.name, integ.stability_limit)
        if why:
            raise RunRefused(why, quantity="dt")
        xs, vs, evals = run_newmark(system, integ, x0, v0, grid.h, grid.steps, grid.indices)
        recorder.frames(0, xs, vs)
        return evals

    def response(self):
        """The closed-form per-mode response of the step (rational in ``z = ωh``)."""
        return self.integrator_class(**self._settings()).response()


__all__ = ["ImplicitStep"]
