"""Adaptive embedded Runge–Kutta–Nyström pairs for ``ẍ = a(x) + a_ext(t)``, behind :class:`AdaptiveMethod`.

The force never depends on the velocity, so a step of an ``s``-stage pair costs ``s`` force
evaluations (``s − 1`` with first-same-as-last) and reaches a higher order than a general
Runge–Kutta method with as many stages applied to the first-order system (DOP853: 12
evaluations for order 8; RKN 8(6): 8 for order 8; RKN 12(10): 17 for order 12).

Step-size control
-----------------
The local error estimate is the difference of the two solutions of the pair, on positions
``h² Σ (b_i − b̂_i) k_i`` and velocities ``h Σ (b'_i − b̂'_i) k_i``, measured in the RMS norm
of ``error / (atol + rtol·max(|y_old|, |y_new|))`` over all positions and velocities; a step
is accepted when that norm is ≤ 1 and the next step is
``h·min(4, max(0.2, 0.9·err_n^(−0.7/k)·err_{n−1}^(0.4/k)))``, ``k = q + 1`` with ``q`` the
embedded order (Gustafsson's PI controller, which damps the step-size oscillation that makes a
plain ``err^(−1/k)`` rule reject about one step in four with the 12(10) pair); after a
rejection the step shrinks by ``max(0.2, 0.9·err^(−1/k))`` and does not grow on the next step. The solution carried on is the higher-order one (local
extrapolation), as in DOP853. The first step follows Hairer, Nørsett & Wanner (II.4).

Output times
------------
There is no interpolant: the integrator steps exactly onto every requested time (the step is
shortened to land on it, and the controller's proposal is kept for the step after). On a
dense output grid this costs evaluations; a few frames (or only the final state) cost
nothing extra.

The force is the problem's vectorised acceleration ``a(x)`` on the whole (N, B) state; stage
sums are one small matrix–vector product over the stored stages (no loop over masses).
"""

from __future__ import annotations

import math
from typing import ClassVar

import numpy as np

from ..errors import RunRefused
from .base import Problem
from .ivp import AdaptiveMethod, AdaptiveResult
from .nystrom_tables import NystromTable

#: Step-size controller constants: safety factor, largest and smallest change per step.
SAFETY, FAC_MAX, FAC_MIN = 0.9, 4.0, 0.2
#: Exponents of the PI controller, times 1/(q+1): the current and the previous accepted error.
BETA1, BETA2 = 0.7, 0.4


def rkn_step(tab: dict, force, x: np.ndarray, v: np.ndarray, K: np.ndarray, t: float, h: float):
    """One step of an RKN pair from ``(x, v)`` at ``t`` with step ``h``.

    Parameters
    ----------
    tab : dict
        :attr:`NystromTable.arrays` of the pair.
    force : callable
        ``force(x, t) -> a``, x and a of shape (N, B).
    x, v : ndarray, shape (N, B)
    K : ndarray, shape (s, N, B)
        Stage forces; ``K[0]`` must hold ``force(x, t)`` on entry, the others are overwritten.
    t, h : float

    Returns
    -------
    x_new, v_new, err_x, err_v : ndarray, shape (N, B)
        The order-``p`` solution and the local error estimates (solution minus embedded).
    """
    c, A = tab["c"], tab["A"]
    s = c.shape[0]
    shape = x.shape
    K2 = K.reshape(s, -1)
    h2 = h * h
    for i in range(1, s):
        xi = x + (c[i] * h) * v + h2 * (A[i, :i] @ K2[:i]).reshape(shape)
        K[i] = force(xi, t + c[i] * h)
    x_new = x + h * v + h2 * (tab["b"] @ K2).reshape(shape)
    v_new = v + h * (tab["bp"] @ K2).reshape(shape)
    return x_new, v_new, (h2 * (tab["e"] @ K2)).reshape(shape), (h * (tab["ep"] @ K2)).reshape(shape)


class EmbeddedNystrom(AdaptiveMethod):
    """An embedded RKN pair (``table``) with error control; see the module docstring."""

    table: ClassVar[NystromTable]
    scipy_method = ""
    supports_damping: ClassVar[bool] = False

    @classmethod
    def of(cls, name: str, table: NystromTable) -> type["EmbeddedNystrom"]:
        """The pair ``table`` as a method class called ``name`` (its order is the table's: declared
        once, where the table checks it)."""
        return type(name.upper(), (cls,), {"name": name, "table": table, "order": table.order,
                                           "__doc__": f"{table.source} (``{name}``)", "__module__": cls.__module__})

    @property
    def evals_per_accepted_step(self) -> int:
        return self.table.evals_per_step

    def solve(self, problem: Problem, x0: np.ndarray, v0: np.ndarray, t_eval: np.ndarray,
              rtol: float, atol: float) -> AdaptiveResult:
        """Integrate from ``t_eval[0]`` to ``t_eval[-1]``, stepping onto each time of ``t_eval``.

        Parameters
        ----------
        problem : Problem
            Its ``damping`` must be None (the stages never see the velocity).
        x0, v0 : ndarray, shape (N,) or (N, B)
        t_eval : ndarray, shape (S,)
            Increasing times, the first being the initial time.
        rtol, atol : float
            Relative and absolute tolerance of the local error on positions and velocities.

        Returns
        -------
        AdaptiveResult
            x, v shape (S, N, B) (B = 1 for 1-D input); ``steps`` counts accepted steps.
        """
        if not (rtol > 0 and atol > 0 and math.isfinite(rtol) and math.isfinite(atol)):
            raise RunRefused(f"method {self.name!r}: rtol and atol must be finite and > 0, got {rtol!r}, {atol!r}",
                             quantity="rtol")
        if problem.damping is not None:
            raise RunRefused(f"method {self.name!r} integrates x'' = f(t, x) (a Runge–Kutta–Nyström pair): "
                             f"this scene has dampers; use dop853, rk45 or lsoda", quantity="method")
        t_eval = np.asarray(t_eval, dtype=float)
        if t_eval.ndim != 1 or t_eval.shape[0] < 1 or np.any(np.diff(t_eval) <= 0):
            raise RunRefused(f"method {self.name!r}: output times must be increasing", quantity="t_eval")
        x = np.array(x0, dtype=float)
        v = np.array(v0, dtype=float)
        if x.ndim == 1:
            x, v = x[:, None], v[:, None]
        shape = x.shape
        tab = self.table.arrays
        s = tab["c"].shape[0]
        fsal = self.table.fsal
        acc, ext = problem.acceleration, problem.external
        evals = [0]

        def force(xx, tt):
            evals[0] += 1
            a = acc(xx)
            if ext is not None:
                a = a + np.reshape(ext(tt), (-1, 1))
            return a

        xs = np.empty((t_eval.shape[0],) + shape)
        vs = np.empty_like(xs)
        xs[0], vs[0] = x, v
        K = np.empty((s,) + shape)
        t = float(t_eval[0])
        K[0] = force(x, t)
        q_hat = self.table.embedded_order
        h = self._first_step(force, x, v, K[0], t, float(t_eval[-1] - t_eval[0]), rtol, atol)
        steps = 0
        k_ctrl = q_hat + 1.0
        err_prev = 1.0
        rejected = False
        for row in range(1, t_eval.shape[0]):
            target = float(t_eval[row])
            while t < target:
                clamped = h >= target - t
                hs = target - t if clamped else h
                if hs <= 1e-14 * max(abs(t), 1.0):
                    raise RunRefused(f"method {self.name!r}: step size underflow at t = {t:.6g}", quantity="rtol")
                x_new, v_new, ex, ev = rkn_step(tab, force, x, v, K, t, hs)
                sx = atol + rtol * np.maximum(np.abs(x), np.abs(x_new))
                sv = atol + rtol * np.maximum(np.abs(v), np.abs(v_new))
                err = math.sqrt(0.5 * (float(np.mean((ex / sx) ** 2)) + float(np.mean((ev / sv) ** 2))))
                if not math.isfinite(err):
                    raise RunRefused(f"method {self.name!r}: the solution is not finite at t = {t:.6g}",
                                     quantity="method")
                if err <= 1.0:
                    t = target if clamped else t + hs
                    x, v = x_new, v_new
                    steps += 1
                    K[0] = K[-1] if fsal else force(x, t)
                    err = max(err, 1e-10)
                    grow = SAFETY * err ** (-BETA1 / k_ctrl) * err_prev ** (BETA2 / k_ctrl)
                    grow = min(1.0 if rejected else FAC_MAX, max(FAC_MIN, grow))
                    err_prev, rejected = err, False
                    h_next = hs * grow
                    h = max(h, h_next) if clamped else h_next  # a shortened step keeps the proposal
                else:
                    h = hs * max(FAC_MIN, SAFETY * err ** (-1.0 / k_ctrl))
                    rejected = True
            xs[row], vs[row] = x, v
        return AdaptiveResult(t_eval, xs, vs, evals[0], steps)

    def _first_step(self, force, x, v, a0, t0, span, rtol, atol) -> float:
        """Hairer–Nørsett–Wanner's starting step for the first-order system ``(x, v)' = (v, a)``."""
        if span <= 0:
            return 1.0
        sx = atol + rtol * np.abs(x)
        sv = atol + rtol * np.abs(v)

        def norm(dx, dv):
            return math.sqrt(0.5 * (float(np.mean((dx / sx) ** 2)) + float(np.mean((dv / sv) ** 2))))

        d0, d1 = norm(x, v), norm(v, a0)
        h0 = 1e-6 if d0 < 1e-5 or d1 < 1e-5 else 0.01 * d0 / d1
        h0 = min(h0, span)
        a1 = force(x + h0 * v, t0 + h0)
        d2 = norm(a0, (a1 - a0) / h0)  # ‖f(y0 + h0 f(y0)) − f(y0)‖ / h0
        p = self.table.order
        h1 = max(1e-6, h0 * 1e-3) if max(d1, d2) <= 1e-15 else (0.01 / max(d1, d2)) ** (1.0 / (p + 1))
        return min(100 * h0, h1, span)


__all__ = ["EmbeddedNystrom", "rkn_step", "SAFETY", "FAC_MAX", "FAC_MIN", "BETA1", "BETA2"]
