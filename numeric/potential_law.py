"""A chain module's spring potential as a compiled scalar function, for the fused kernels.

The generated ``spring_force(d, *parameters)`` of a ``[chain]`` scene with ``potential = "EXPR"``
(:mod:`springchain.derive.potential_code`) is NumPy ufuncs and arithmetic only; numba compiles it,
and :func:`compiled_law` binds the parameter values as compile-time constants, so the kernels of
:mod:`numeric.fast_kernels` call ``law(d)`` inline in their loops (the law takes the place of the
cubic term; one specialisation per law and parameter set, compiled in each process: numba cannot
cache functions that take other functions). Index-dependent laws (``POTENTIAL_LAW_INDEXED``) are
not compiled: their chains run the module's NumPy stencil.
"""

from __future__ import annotations

import inspect
from types import ModuleType


_NOTED = False


def compiled_law(module: ModuleType, values: dict[str, float]):
    """``law(d) = V'(d)`` of the module at ``values``, compiled by numba; None when numba is missing.
    For index-free laws only (the caller asks :attr:`System.law_indexed`). One compiled law per law text and parameter values in a
    process (modules of the same law share it, and with it the kernels specialised on it)."""
    from .fast_kernels import available

    if not available():
        return None
    try:
        text = inspect.getsource(module.spring_force)
    except (OSError, TypeError):  # no source file (a module built in memory): this function only
        text = module.spring_force
    key = (text, tuple(float(values[p]) for p in module.PARAMETERS))
    law = _LAWS.get(key)
    if law is None:
        law = _LAWS[key] = _compile(module.spring_force, key[1])
    return law


#: Compiled laws of this process by (the generated spring_force's text, parameter values).
_LAWS: dict = {}


def _compile(spring_force, args: tuple):
    import numba

    global _NOTED
    if not _NOTED:
        from .progress import note

        note("compiling the chain kernels for this spring potential (numba, several seconds; "
             "a law's kernels are compiled in each run)")
        _NOTED = True
    force = numba.njit(spring_force)

    @numba.njit
    def law(d):
        return force(d, *args)

    return law
