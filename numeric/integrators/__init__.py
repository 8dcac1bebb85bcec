"""Integrators, one module each, behind :class:`~numeric.integrators.base.Integrator`.

Fixed-step methods take a step ``h``; the adaptive methods (SciPy's peers and the
embedded Runge–Kutta–Nyström pairs of :mod:`~numeric.integrators.nystrom`) take
tolerances and have their own small interface
(:class:`~numeric.integrators.ivp.AdaptiveMethod`). Their names are registered once,
in :mod:`numeric.run.registry`.
"""

import importlib

from ..run.registry import integrator_classes

#: Public name -> the module that defines it (imported on first access: importing one integrator, or the
#: package, does not import the others, SciPy's solvers among them): the interfaces, then every
#: integrator of the registry's table (:func:`numeric.run.registry.integrator_classes`).
_WHERE = {
    "Integrator": "base", "LinearChain": "base", "Problem": "base", "State": "base",
    "AdaptiveMethod": "ivp", "AdaptiveResult": "ivp",
    **integrator_classes(),
}


def __getattr__(name: str):
    if name in _WHERE:
        value = getattr(importlib.import_module(f".{_WHERE[name]}", __name__), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


__all__ = list(_WHERE)
