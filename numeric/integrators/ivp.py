"""SciPy's adaptive ``solve_ivp`` methods as peers: RK45, DOP853 and LSODA.

They take tolerances instead of a step, so they have their own small
interface (:class:`AdaptiveMethod`): ``solve(problem, x0, v0, t_eval, rtol,
atol)``. A batch (N, B) is flattened into one first-order state
``y = [x.ravel(), v.ravel()]`` of length 2NB; force evaluations are counted
by wrapping the right-hand side (so LSODA's finite-difference Jacobian is
included). One state (B = 1) is integrated the way a user calls ``solve_ivp``: a
right-hand side on (N,) arrays (on shape (N, 1) NumPy's per-call overhead made the
peer several times slower than the user's own call).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import ClassVar

import numpy as np
from scipy.integrate import solve_ivp

from ..errors import RunRefused
from .base import Problem


@dataclass(frozen=True)
class AdaptiveResult:
    """x, v : ndarray, shape (S, N, B) at ``t_eval``; ``force_evals`` right-hand-side calls."""

    t: np.ndarray = field(repr=False)
    x: np.ndarray = field(repr=False)
    v: np.ndarray = field(repr=False)
    force_evals: int
    steps: int


class AdaptiveMethod:
    """A ``scipy.integrate.solve_ivp`` method on the first-order system ``(x, v)' = (v, a)``."""

    name: ClassVar[str]
    #: SciPy's name of the method.
    scipy_method: ClassVar[str]
    order: ClassVar[float]
    symplectic: ClassVar[bool] = False
    #: Whether the method integrates velocity-dependent (damping) forces.
    supports_damping: ClassVar[bool] = True
    #: Not a constant: counted per run.
    evals_per_step: ClassVar[float] = math.nan
    #: Whether the method keeps a dense N × N Jacobian (refused above the dense limit).
    dense_jacobian: ClassVar[bool] = False

    def solve(self, problem: Problem, x0: np.ndarray, v0: np.ndarray, t_eval: np.ndarray,
              rtol: float, atol: float) -> AdaptiveResult:
        """Integrate from ``t_eval[0]`` to ``t_eval[-1]``, returning the state at ``t_eval``.

        Parameters
        ----------
        problem : Problem
        x0, v0 : ndarray, shape (N,) or (N, B)
        t_eval : ndarray, shape (S,)
            Increasing times, the first being the initial time.
        rtol, atol : float
            Tolerances passed to ``solve_ivp``.

        Returns
        -------
        AdaptiveResult
            x, v shape (S, N, B) (B = 1 for 1-D input).
        """
        if not (rtol > 0 and atol > 0):
            raise RunRefused(f"method {self.name!r}: rtol and atol must be > 0, got {rtol!r}, {atol!r}", quantity="rtol")
        t_eval = np.asarray(t_eval, dtype=float)
        x0 = np.asarray(x0, dtype=float)
        v0 = np.asarray(v0, dtype=float)
        if x0.ndim == 1:
            x0, v0 = x0[:, None], v0[:, None]
        n, b = x0.shape
        nb = n * b
        acc, damp, ext = problem.acceleration, problem.damping, problem.external
        calls = [0]

        def rhs_single(t, y):  # one state: (N,) arrays, the way a user writes the right-hand side
            calls[0] += 1
            a = acc(y[:n])
            if damp is not None:
                a = a + damp(y[n:])
            if ext is not None:
                a = a + np.reshape(ext(t), -1)
            return np.concatenate((y[n:], a))

        def rhs(t, y):
            calls[0] += 1
            x = y[:nb].reshape(n, b)
            v = y[nb:].reshape(n, b)
            a = acc(x)
            if damp is not None:
                a = a + damp(v)
            if ext is not None:
                a = a + np.reshape(ext(t), (-1, 1))
            return np.concatenate((y[nb:], a.ravel()))

        y0 = np.concatenate((x0.ravel(), v0.ravel()))
        sol = solve_ivp(rhs_single if b == 1 else rhs, (float(t_eval[0]), float(t_eval[-1])), y0, method=self.scipy_method,
                        t_eval=t_eval, rtol=rtol, atol=atol)
        if not sol.success:
            raise RunRefused(f"method {self.name!r} failed: {sol.message}", quantity="method")
        y = sol.y.T  # (S, 2NB)
        x = y[:, :nb].reshape(-1, n, b)
        v = y[:, nb:].reshape(-1, n, b)
        return AdaptiveResult(sol.t, x, v, calls[0], int(max(len(sol.t), 1)))


class RK45(AdaptiveMethod):
    """Dormand–Prince 5(4), SciPy's default."""

    name = "rk45"
    scipy_method = "RK45"
    order = 5


class DOP853(AdaptiveMethod):
    """Dormand–Prince 8(5,3)."""

    name = "dop853"
    scipy_method = "DOP853"
    order = 8


class LSODA(AdaptiveMethod):
    """Adams/BDF with automatic stiffness switching (ODEPACK)."""

    name = "lsoda"
    scipy_method = "LSODA"
    order = 12  # Adams up to order 12 (variable)
    dense_jacobian = True
