"""One protocol for every simulation method, and one recorder interface for in-memory and streamed runs.

A :class:`Method` says whether it applies to a system (:meth:`Method.refusal`) and runs from an
initial state onto a :class:`Grid`, handing each recorded frame to a :class:`Recorder`
(:meth:`Method.run`). The exact solution, the fixed-step integrators and SciPy's adaptive
methods are the three kinds; :func:`method` is the one lookup from a name to a method (used at
the edge only). :class:`MemoryRecorder` keeps the frames in arrays; a streamed run passes a
recorder that writes them to disk (:mod:`numeric.simulate`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property
from typing import Protocol

import numpy as np

from .errors import RunRefused
from .methods import ADAPTIVE as ADAPTIVE_NAMES
from .methods import EXACT, FIXED_STEP
from .system import LOADED_CHAIN_EXACT_MAX, System

#: Runs shorter than this many mass-steps show no progress bar.
PROGRESS_MIN_WORK = 2_000_000
#: Rows per block when the exact solution is evaluated into a recorder.
EXACT_BLOCK_BYTES = 64 * 2**20


@dataclass(frozen=True)
class Grid:
    """Recorded times ``t = i·h`` for ``i`` in ``0, k, 2k, …`` and always ``steps``."""

    h: float
    steps: int
    record_every: int = 1

    @cached_property
    def indices(self) -> np.ndarray:
        """Recorded step indices, shape (S,)."""
        idx = np.arange(0, self.steps + 1, self.record_every)
        return idx if idx[-1] == self.steps else np.append(idx, self.steps)

    @property
    def t(self) -> np.ndarray:
        """Recorded times, shape (S,)."""
        return self.indices * self.h


class Recorder(Protocol):
    """Receives a run's recorded frames in order; ``row`` is the frame number 0 … S-1."""

    def frame(self, row: int, x: np.ndarray, v: np.ndarray) -> None:
        """x, v : ndarray, shape (N,) or (N, 1): copied or written out before returning."""


class MemoryRecorder:
    """Keeps every frame: ``x``, ``v`` of shape (S, N)."""

    def __init__(self, frames: int, n: int):
        self.x = np.empty((frames, n))
        self.v = np.empty((frames, n))

    def frame(self, row: int, x: np.ndarray, v: np.ndarray) -> None:
        n = self.x.shape[1]
        self.x[row] = np.reshape(x, -1)[:n]
        self.v[row] = np.reshape(v, -1)[:n]


@dataclass
class RunContext:
    """What every method of one simulation shares: the system and the options, and the
    spectrum computed once (the exact solution and the stability check both read it)."""

    system: System
    spectrum_source: str = "svd"
    rtol: float = 1e-10
    atol: float = 1e-12
    progress: bool | None = None

    @cached_property
    def spectrum(self):
        from .simulate import system_spectrum

        return system_spectrum(self.system, self.spectrum_source)

    def omega_max(self) -> float:
        """ω_max for the stability check: exact from the spectrum for dense systems, a proven
        Gershgorin bound for ``[chain]`` scenes (no eigen-solve)."""
        if self.system.chain:
            from .bounds import omega2_bound

            s = self.system
            return math.sqrt(omega2_bound(s.masses, s.spring_ends, s.stiffness))
        return float(self.spectrum.omega_max)


@dataclass(frozen=True)
class Method:
    """A way to compute a trajectory. Subclasses implement :meth:`refusal` and :meth:`run`."""

    name: str

    def refusal(self, system: System) -> str | None:
        """Why this method does not apply to ``system`` (None when it does)."""
        return None

    def check(self, system: System) -> None:
        why = self.refusal(system)
        if why:
            raise RunRefused(f"method {self.name!r}: {why}", quantity="method")

    def run(self, ctx: RunContext, x0: np.ndarray, v0: np.ndarray, grid: Grid, recorder: Recorder) -> int:
        """Compute the frames of ``grid`` from (x0, v0) into ``recorder``; returns force evaluations."""
        raise NotImplementedError


@dataclass(frozen=True)
class ExactMethod(Method):
    """The exact solution: modal (conservative), augmented matrix exponential (dampers, forces,
    gravity), or the O(N log N) transforms of uniform ``[chain]`` scenes."""

    name: str = EXACT

    def refusal(self, system: System) -> str | None:
        if system.exact_available:
            return None
        why = ("this scene has cubic springs" if not system.linear else
               f"a loaded [chain] of more than {LOADED_CHAIN_EXACT_MAX} masses (the exact solution is dense)"
               if system.chain and system.n > LOADED_CHAIN_EXACT_MAX else
               "its external forces or ground acceleration are not constant + harmonic")
        return f"no exact solution applies ({why}); use one of {', '.join(FIXED_STEP)}"

    def run(self, ctx, x0, v0, grid, recorder) -> int:
        self.check(ctx.system)
        system, t = ctx.system, grid.t
        if system.chain and system.conservative:
            from .chain_modal import ChainModal
            from .driver import Progress
            from .progress import phase

            # uniform chains: sine/cosine/Fourier transforms, O(N log N) per frame, no N x N
            with phase("exact solution: set-up", enabled=ctx.progress):
                sol = ChainModal.from_module(system.module, system.params, x0, v0)
            bar = Progress(t.shape[0], "exact solution", enabled=ctx.progress)
            for row, ti in enumerate(t):
                x, v = sol.at(float(ti))
                recorder.frame(row, x, v)
                bar.update(row + 1)
            return 0
        from .progress import phase

        if system.conservative:
            from .modal import ModalSolution

            with phase("exact solution: modes", enabled=ctx.progress):
                sol = ModalSolution.from_initial(ctx.spectrum, x0, v0)
            block = max(1, EXACT_BLOCK_BYTES // (16 * max(system.n, 1)))
            for start in range(0, t.shape[0], block):
                x, v = sol.at(t[start:start + block])
                for r in range(x.shape[0]):
                    recorder.frame(start + r, x[r], v[r])
            return 0
        from .linear_exact import AugmentedLinear

        with phase("exact solution", enabled=ctx.progress):
            x, v = AugmentedLinear.from_system(system).solve(x0, v0, t, grid.h * grid.record_every)
        for r in range(x.shape[0]):
            recorder.frame(r, x[r], v[r])
        return 0


@dataclass(frozen=True)
class StepMethod(Method):
    """A fixed-step integrator (one of ``integrators.INTEGRATORS``) through :func:`driver.integrate`;
    dampers and forces by splitting around it; plain ``[chain]`` Verlet through the fused kernel."""

    def integrator(self, system: System):
        from .integrators import INTEGRATORS

        if self.name == "verlet" and system.chain and system.conservative:
            from .simulate import FusedChainVerlet

            return FusedChainVerlet(system)
        if getattr(INTEGRATORS[self.name], "implicit", False):  # Newmark, HHT: damping and loads in the step
            return INTEGRATORS[self.name].for_system(system)
        integ = INTEGRATORS[self.name]()
        if system.damped or system.forced:
            from .effects import EffectSplitting

            integ = EffectSplitting(integ, system.damping_rate_matrix(), system.external_fn)
        return integ

    def run(self, ctx, x0, v0, grid, recorder) -> int:
        from .driver import Progress, integrate
        from .integrators.base import Problem
        from .simulate import check_stable

        system = ctx.system
        integ = self.integrator(system)
        if system.linear:
            check_stable(ctx.omega_max(), grid.h, self.name, getattr(integ, "stability_limit", 2.0))
        long_run = grid.steps * system.n > PROGRESS_MIN_WORK
        bar = Progress(grid.steps, self.name, enabled=(ctx.progress if long_run else False))
        rows = {int(i): r for r, i in enumerate(grid.indices)}
        traj = integrate(integ, Problem.from_system(system), x0, v0, grid.h, grid.steps, grid.record_every,
                         on_frame=lambda i, x, v: recorder.frame(rows[int(i)], x[:, :1], v[:, :1]),
                         progress=bar)
        return traj.force_evals


@dataclass(frozen=True)
class AdaptiveRunner(Method):
    """An adaptive method (SciPy's rk45, dop853, lsoda on the first-order system; the RKN pairs
    dprkn6/8/12 on ``ẍ = f(t, x)``, stepping onto every recorded time), evaluated on the grid."""

    def refusal(self, system: System) -> str | None:
        from .integrators import ADAPTIVE

        if system.damped and not ADAPTIVE[self.name].supports_damping:
            return ("a Runge–Kutta–Nyström pair integrates x'' = f(t, x) and this scene has dampers; "
                    "use dop853, rk45 or lsoda")
        return None

    def run(self, ctx, x0, v0, grid, recorder) -> int:
        from .integrators import ADAPTIVE
        from .integrators.base import Problem

        self.check(ctx.system)
        system = ctx.system
        Ad = system.damping_rate_matrix()
        problem = Problem(system.acceleration_fn, damping=None if Ad is None else (lambda v: Ad @ v),
                          external=system.external_fn)
        from .progress import phase

        with phase(self.name, enabled=ctx.progress):
            res = ADAPTIVE[self.name]().solve(problem, x0, v0, grid.t, ctx.rtol, ctx.atol)
        for r in range(res.x.shape[0]):
            recorder.frame(r, res.x[r, :, 0], res.v[r, :, 0])
        return res.force_evals


def method(name: str) -> Method:
    """The method called ``name`` (the one table from names to methods)."""
    if name == EXACT:
        return ExactMethod()
    if name in FIXED_STEP:
        return StepMethod(name)
    if name in ADAPTIVE_NAMES:
        return AdaptiveRunner(name)
    raise RunRefused(f"method {name!r} is unknown; accepted: {', '.join((EXACT, *FIXED_STEP, *ADAPTIVE_NAMES))}",
                     quantity="method")


__all__ = ["Grid", "Recorder", "MemoryRecorder", "RunContext", "Method", "ExactMethod", "StepMethod",
           "AdaptiveRunner", "method"]
