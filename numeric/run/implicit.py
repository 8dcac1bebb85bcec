"""Implicit step methods as methods: integrators built on the system's own operators.

An implicit step (Newmark-β, HHT-α: :mod:`numeric.integrators.newmark`) solves with the scene's
stiffness, damping and loads, so it is built on the :class:`~numeric.system.System` (the
integrator class's ``for_system(system, **settings)``) and integrates damping, forces and ground
motion in its step instead of inside a splitting. Its per-mode propagator is rational in ``z = ωh``,
known in closed form: the integrator's ``response()`` gives plan's error models.

A registry entry names :class:`ImplicitStep` as the runner of such an integrator; nothing else
in the run layer knows about it.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

from ..integrators.base import Integrator
from ..system import System
from .step import StepMethod


@dataclass(frozen=True)
class ImplicitStep(StepMethod):
    """A fixed-step implicit integrator run on the system's operators.

    Attributes
    ----------
    settings : tuple of (str, float)
        Keyword settings of the integrator (HHT's ``alpha``), passed to ``for_system``.
    """

    settings: tuple = field(default=(), compare=False)

    def with_settings(self, **settings) -> "ImplicitStep":
        """The same method with other settings (validated by the integrator when it is built)."""
        return replace(self, settings=tuple(sorted(settings.items())))

    def integrator(self, system: System) -> Integrator:
        """The integrator on ``system``'s stiffness, damping and loads (no splitting around it)."""
        return self.integrator_class.for_system(system, **dict(self.settings))

    def response(self):
        """The closed-form per-mode response of the step (rational in ``z = ωh``)."""
        return self.integrator_class(**dict(self.settings)).response()


__all__ = ["ImplicitStep"]
