"""Step-based integrators, one module each, behind :class:`~numeric.integrators.base.Integrator`."""

from .base import Integrator, Problem, State
from .verlet import VelocityVerlet

#: The one table from command-line names to integrator classes.
INTEGRATORS: dict[str, type[Integrator]] = {cls.name: cls for cls in (VelocityVerlet,)}

__all__ = ["Integrator", "Problem", "State", "VelocityVerlet", "INTEGRATORS"]
