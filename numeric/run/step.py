"""Fixed-step integrators as methods: the one place an integrator is made ready for a system.

:meth:`StepMethod.integrator` wraps the registered :class:`~numeric.integrators.base.Integrator`
for what the system has — a Strang splitting for dampers and time as a coordinate for forces
(:class:`~numeric.run.effects.EffectSplitting`) — and chooses the loop: plain ``[chain]`` Verlet runs
the fused single-pass kernel (:mod:`numeric.compiled.fast`, numba when installed), everything else the
NumPy driver (:func:`numeric.run.driver.integrate`). :func:`stability_refusal` is the one stability
check (``ω_max·h`` below the method's limit, ``ω_max`` from :attr:`System.omega_max`).

Small ``[masses]`` scenes run their whole loop compiled (:mod:`numeric.compiled`: the module's
``scalar_force`` in numba loops, chosen in :meth:`StepMethod.compiled_loop`); the NumPy driver stays
the fallback (chains, tables, batches, ``Options(compiled=False)``, implicit steps). Extension point:
an implicit method that takes the damping and loads into its step is a subclass that overrides
:meth:`StepMethod.integrator` (:class:`.implicit.ImplicitStep`, named by its registry entry).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from .driver import integrate
from ..integrators.base import Integrator, Problem
from ..integrators.verlet import VelocityVerlet
from ..progress import Reporter
from ..system import System
from .protocol import Kind, Method

#: Runs shorter than this many mass-steps show no progress bar.
PROGRESS_MIN_WORK = 2_000_000


def stability_refusal(system: System, h: float, name: str, limit: float) -> str | None:
    """Why a step ``h`` is refused: at or beyond the stability edge ``ω_max·h < limit`` of a linear
    system (None when it is inside, or the system is nonlinear)."""
    if not system.linear or system.stable(h, limit):
        return None
    w = system.omega_max
    return (f"dt = {h:g} is at or beyond {name}'s stability limit: ω_max = {w:.6g}, so dt must be < "
            f"{limit:g}/ω_max = {limit / w:.6g}; use a smaller dt (the scene's simulation.dt or the run's) or "
            f"the exact method 'modal' (any dt)")


class FusedChainVerlet(VelocityVerlet):
    """Velocity Verlet on a ``[chain]`` scene through the fused single-pass kernel
    (:mod:`numeric.compiled.fast`: numba when installed, else the NumPy stencil). Same scheme,
    same name; frames are copied by the recorder, so the in-place kernel is safe."""

    def __init__(self, system: System):
        self.system = system

    def kernel(self, problem: Problem, h: float):
        from ..compiled.fast import FusedVerlet

        return FusedVerlet.from_system(self.system, h).kernel(inplace=True)


@dataclass(frozen=True)
class StepMethod(Method):
    """A fixed-step integrator (the ``implementation``, an :class:`Integrator` subclass) as a method."""

    kind: ClassVar[Kind] = Kind.STEP

    @property
    def integrator_class(self) -> type[Integrator]:
        return self.implementation

    def problem(self, system: System) -> Problem:
        """The conservative problem the (wrapped) integrator steps (:meth:`Problem.from_system`)."""
        return Problem.from_system(system)

    def integrator(self, system: System) -> Integrator:
        """The integrator as it runs on ``system``: the fused kernel for plain ``[chain]`` Verlet; a
        damping/forcing splitting around it where the system has dampers or forces."""
        if self.integrator_class is VelocityVerlet and system.chain and system.springs_only:
            return FusedChainVerlet(system)
        integ = self.integrator_class()
        if system.damped or system.forced:
            from .effects import EffectSplitting

            integ = EffectSplitting(integ, system.damping_rate_matrix(), system.external_fn)
        return integ

    def splits(self, system: System) -> bool:
        """Whether the integrator runs inside the damping/forcing splitting on ``system`` (an
        implicit step integrates damping and loads in its step instead)."""
        from .effects import EffectSplitting

        return isinstance(self.integrator(system), EffectSplitting)

    def response(self):
        """The one-step response on a mode ``q̈ = −ω²q`` that plan's error models read (amplitude,
        phase defect, shape distortion per ``z = ωh``): an :class:`~numeric.plan.error_models.OscillatorResponse`
        from the integrator's step."""
        from ..plan.error_models import OscillatorResponse

        return OscillatorResponse.from_integrator(self.integrator_class())

    def compiled_loop(self, system: System, integ: Integrator, grid) -> str | None:
        """The compiled loop (:func:`numeric.compiled.run.route`) this run takes, or None (NumPy driver)."""
        if not self.options.compiled or system.chain:
            return None
        from ..compiled.run import route

        return route(system, getattr(integ, "inner", integ), grid.frames,
                     max(integ.evals_per_step, 1.0) * grid.steps)

    def refusal(self, system: System) -> str | None:
        why = self.integrator(system).refusal(self.problem(system))
        return why.replace(f"method {self.name!r} ", "", 1) if why else None

    def run(self, system, x0, v0, grid, recorder) -> int:
        integ = self.integrator(system)
        problem = self.problem(system)
        integ.check(problem)
        why = stability_refusal(system, grid.h, self.name, integ.stability_limit)
        if why:
            from ..errors import RunRefused

            raise RunRefused(why, quantity="dt")
        n = system.n
        loop = self.compiled_loop(system, integ, grid)
        if loop is not None:  # small [masses] scene: the whole run as one compiled loop
            from ..compiled.run import run_steps

            xs, vs = run_steps(system, integ.inner if hasattr(integ, "inner") else integ, loop, x0, v0, grid.h,
                               grid.steps, grid.indices)
            recorder.frames(0, xs, vs)
            return integ.force_evals(problem, grid.h, grid.steps)
        long_run = grid.steps * n > PROGRESS_MIN_WORK
        bar = Reporter(self.name, grid.steps, enabled=self.options.progress if long_run else False)
        if getattr(recorder, "bulk", False):  # the recorder keeps every frame anyway: hand them over at once
            traj = integrate(integ, problem, x0, v0, grid.h, grid.steps, grid.record_every, progress=bar)
            recorder.frames(0, traj.x[:, :n, 0], traj.v[:, :n, 0])
            return traj.force_evals
        rows = {int(i): r for r, i in enumerate(grid.indices)}

        def on_frame(i, x, v):
            recorder.frames(rows[int(i)], np.reshape(x[:n, 0], (1, n)), np.reshape(v[:n, 0], (1, n)))

        return integrate(integ, problem, x0, v0, grid.h, grid.steps, grid.record_every, on_frame=on_frame,
                         progress=bar).force_evals


__all__ = ["StepMethod", "FusedChainVerlet", "stability_refusal", "PROGRESS_MIN_WORK"]
