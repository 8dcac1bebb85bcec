"""``dop853-compiled``: SciPy's DOP853 compiled, the benchmarks' peer that compares compiled with compiled.

The method is :func:`numeric.compiled.run.dop853` (SciPy's tableau, first step, error norm, step
control and dense output, step for step) over the generated module's ``scalar_force``; it applies to
the scenes that have one (small ``[masses]`` scenes without tables, numba installed) and runs one
state (N,). ``springchain bench`` times it beside ``dop853`` (SciPy's ``solve_ivp`` with a NumPy
right-hand side on (N,) arrays, the way a user calls it).
"""

from __future__ import annotations

import numpy as np

from ..errors import RunRefused
from ..integrators.ivp import DOP853, AdaptiveResult


class CompiledDOP853(DOP853):
    """DOP853 compiled with numba (see the module docstring); run through :meth:`run_system`."""

    name = "dop853-compiled"
    #: Runs on the system (its ``scalar_force``), not on a Problem: :class:`numeric.run.adaptive.AdaptiveRun`
    #: calls :meth:`run_system`.
    needs_system = True

    @staticmethod
    def refusal(system) -> str | None:
        from .run import scalar_ready

        if scalar_ready(system):
            return None
        return ("it runs the generated module's scalar_force compiled: a [masses] scene of at most 12 masses "
                "without force or ground tables, with numba installed; use dop853")

    def solve(self, problem, x0, v0, t_eval, rtol, atol) -> AdaptiveResult:
        raise RunRefused(f"method {self.name!r} runs on a scene's system (run_system), not on a bare problem",
                         quantity="method")

    def run_system(self, system, x0: np.ndarray, v0: np.ndarray, t_eval: np.ndarray, rtol: float,
                   atol: float) -> AdaptiveResult:
        """Frames at ``t_eval`` (S,) from ``t_eval[0] = 0``; x, v shape (S, N, 1)."""
        from .run import dop853

        if not (rtol > 0 and atol > 0):
            raise RunRefused(f"method {self.name!r}: rtol and atol must be > 0, got {rtol!r}, {atol!r}", quantity="rtol")
        x0 = np.asarray(x0, dtype=float)
        if x0.ndim == 2 and x0.shape[1] != 1:
            raise RunRefused(f"method {self.name!r} runs one state at a time (a batch of {x0.shape[1]} was given); "
                             "use dop853", quantity="method")
        t_eval = np.asarray(t_eval, dtype=float)
        if t_eval[0] != 0.0:
            raise RunRefused(f"method {self.name!r} starts at t = 0 (got {t_eval[0]!r})", quantity="method")
        xs, vs, steps, evals = dop853(system, x0.reshape(-1), np.asarray(v0, dtype=float).reshape(-1),
                                      float(t_eval[-1]), rtol, atol, max_steps=0, t_eval=t_eval)
        return AdaptiveResult(t_eval, xs[:, :, None], vs[:, :, None], int(evals), int(max(len(t_eval), 1)))


__all__ = ["CompiledDOP853"]
