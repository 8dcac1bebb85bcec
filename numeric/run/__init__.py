"""The run layer: one method protocol that ``simulate``, ``plan``, ``bench`` and their pilots use.

::

    registry.py  name -> method, lazy (listing names imports no integrator); the only place where
                 method names are strings: everything inside works on :class:`~.protocol.Method` objects
    protocol.py  Method: declared :class:`~.protocol.Traits`, ``refusal(system)``,
                 ``run(system, x0, v0, grid, recorder)``; the run :class:`~.protocol.Options`
    exact.py     the exact solution; the one place that chooses its solver
    step.py      fixed-step integrators; the one place that wraps an integrator for dampers and
                 forces, checks the stability limit and chooses the loop that runs it
    implicit.py  implicit step methods (Newmark, HHT-α): the integrator built on the system's own
                 operators (damping, loads, ground in its step), its settings, its per-mode response
    adaptive.py  tolerance-driven methods on the full first-order problem
    grid.py      the one output grid ``t = i·h``
    recorder.py  where frames go: memory or a streamed NPZ

Extension points
----------------
* **A new integrator** is its own module (an :class:`~numeric.integrators.base.Integrator` or an
  :class:`~numeric.integrators.ivp.AdaptiveMethod`) and one line in :mod:`.registry`; ``simulate``,
  ``plan``, ``bench`` and the command line's ``--method`` pick it up from there. Its declared traits
  (order, symplectic, evaluations per step, stability limit, damping support) feed the error models.
* **Implicit step methods** (Newmark, HHT-α): an ``Integrator`` whose ``kernel`` factorises its
  (banded) iteration matrix once per step size and solves per step, registered with the runner
  :class:`.implicit.ImplicitStep` (the entry's fourth field): it builds the integrator with
  ``for_system(system, **settings)`` (damping, loads and ground in the step, no splitting),
  passes it the run's :attr:`~.protocol.Options.settings` its class declares (``settings``) and
  gives plan the integrator's closed-form ``response()``; ``stability_limit = inf`` lifts the step
  check.
* **Compiled whole-loop drivers** (numba) for small scenes are chosen inside the step kind:
  :meth:`.step.StepMethod.integrator` already picks the fused chain kernel for plain ``[chain]``
  Verlet; another loop plugs in there, keyed on the system, without a new method name.
* **Potentials and nonlinear forces** arrive through the system's ``acceleration_fn`` (the
  generated module) and the contract: step and adaptive methods need nothing new; the exact kind
  refuses them through :attr:`~numeric.system.System.no_exact_solution`.
"""
