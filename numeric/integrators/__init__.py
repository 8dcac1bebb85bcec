"""Integrators, one module each, behind :class:`~numeric.integrators.base.Integrator`.

Fixed-step methods take a step ``h``; the adaptive methods (SciPy's peers and the
embedded Runge–Kutta–Nyström pairs of :mod:`~numeric.integrators.nystrom`) take
tolerances and have their own small interface
(:class:`~numeric.integrators.ivp.AdaptiveMethod`). Their names are registered once,
in :mod:`numeric.run.registry`.
"""

import importlib

#: Public name -> the module that defines it (imported on first access: importing one integrator, or the
#: package, does not import the others, SciPy's solvers among them).
_WHERE = {
    "Integrator": "base", "LinearChain": "base", "Problem": "base", "State": "base",
    "BlanesMoan4": "blanes_moan4", "BlanesMoan6": "blanes_moan6", "ChebyshevPropagator": "chebyshev",
    "DPRKN6": "dprkn6", "DPRKN8": "dprkn8", "DPRKN12": "dprkn12", "MatrixExponential": "expm",
    "DOP853": "ivp", "LSODA": "ivp", "RK45": "ivp", "AdaptiveMethod": "ivp", "AdaptiveResult": "ivp",
    "KahanLi8": "kahan_li", "RK4": "rk4", "VelocityVerlet": "verlet", "CompensatedVerlet": "verlet_compensated",
    "Yoshida4": "yoshida",
}


def __getattr__(name: str):
    if name in _WHERE:
        value = getattr(importlib.import_module(f".{_WHERE[name]}", __name__), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


__all__ = [
    "Integrator", "Problem", "State", "LinearChain",
    "VelocityVerlet", "CompensatedVerlet", "Yoshida4", "BlanesMoan4", "BlanesMoan6", "KahanLi8", "RK4",
    "MatrixExponential", "ChebyshevPropagator", "AdaptiveMethod", "AdaptiveResult",
    "RK45", "DOP853", "LSODA", "DPRKN6", "DPRKN8", "DPRKN12",
]
