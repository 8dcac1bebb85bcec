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

    def compiled_loop(self, system: System, integ: Integrator, grid) -> None:
        """None: an implicit step always runs on the NumPy driver (no compiled loop solves its systems)."""
        return None

    def response(self):
        """The closed-form per-mode response of the step (rational in ``z = ωh``)."""
        return self.integrator_class(**self._settings()).response()


__all__ = ["ImplicitStep"]
