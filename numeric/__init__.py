"""springchain's numeric side (NumPy/SciPy/matplotlib only, never SymPy): the exact modal solution,
integrators, trajectories, plots and benchmarks, all driven by the generated modules.

Organised by concern: :mod:`.system` (a generated module bound to parameter values: the only reader of a
generated module), :mod:`.errors`, :mod:`.progress` at the top; subpackages ``modes``, ``exact``,
``integrators``, ``run``, ``compiled``, ``frf``, ``structural``, ``bands``, ``sensitivity``, ``updating``,
``interop``, ``random``, ``plan``, ``bench``, ``sweep``, ``plots`` and ``io``."""
