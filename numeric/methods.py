"""The names of the simulation methods, without importing any of them (the command line's choices).

A test checks this table against the registries in :mod:`springchain.numeric.integrators`.
"""

#: The exact modal (or augmented matrix-exponential) solution.
EXACT = "modal"
#: Fixed-step integrators, in the order of ``integrators.INTEGRATORS``.
FIXED_STEP = ("verlet", "verlet-kahan", "yoshida4", "blanes-moan4", "blanes-moan6", "kahan-li8", "rk4",
              "expm", "chebyshev", "newmark", "newmark-linear", "hht")
#: Adaptive methods (SciPy's, then the Runge–Kutta–Nyström pairs), in the order of ``integrators.ADAPTIVE``.
ADAPTIVE = ("rk45", "dop853", "lsoda", "dprkn6", "dprkn8", "dprkn12")
#: Every method selectable by name, the exact one first.
METHOD_NAMES = (EXACT, *FIXED_STEP, *ADAPTIVE)
