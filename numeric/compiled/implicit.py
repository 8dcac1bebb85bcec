"""Run Newmark-β / HHT-α as one compiled loop (:func:`.implicit_loops.newmark_loop`) on a small scene.

:func:`route` says whether the run takes it (the scene's whole force in ``scalar_force``, linear or
cubic springs — a potential's tangent is not the operator's — and a run long enough to pay a first
compile, as :func:`numeric.compiled.run.route`); :func:`run_newmark` runs it. The matrix
``S = I − (1 + α)(βh²A + γhD)`` is factored here, once, by LAPACK (as the NumPy step does).
"""

from __future__ import annotations

import numpy as np

from ..errors import RunRefused
from ..system import System
from .cache import compiled, timed_first_call
from .run import MAX_FRAME_VALUES, parameter_vector, scalar_ready, worth_compiling

#: The loop's name in the compiled file.
LOOP = "newmark_loop"


def route(system: System, integrator, frames: int, evals: float = float("inf")) -> str | None:
    """:data:`LOOP` when this run of ``integrator`` (a Newmark-family step built on ``system``) takes the
    compiled loop, else None (the NumPy driver)."""
    op = getattr(integrator, "operator", None)
    if op is None or system.potential or getattr(op, "sparse", True) or frames * system.n > MAX_FRAME_VALUES:
        return None
    return LOOP if worth_compiling(system, LOOP, evals) and scalar_ready(system) else None


def run_newmark(system: System, integrator, x0: np.ndarray, v0: np.ndarray, h: float, steps: int,
                rec: np.ndarray) -> tuple[np.ndarray, np.ndarray, int]:
    """``steps`` steps of ``integrator``'s scheme from (x0, v0) (shape (N,)), compiled.

    Returns
    -------
    xs, vs : ndarray, shape (F, N)
        Frames at the step indices ``rec`` (F,).
    evals : int
        Force evaluations (Newton iterations counted one by one), the initial one included.
    """
    import scipy.linalg

    from ..integrators.newmark import MAX_NEWTON

    n = system.n
    op = integrator.operator
    par = integrator.parameters
    b, g, al = par.beta, par.gamma, par.alpha
    c1, c2 = (1 + al) * b * h * h, (1 + al) * g * h
    S = np.eye(n) - c1 * np.asarray(op.tangent())
    D = np.zeros((0, 0)) if op.damping is None else np.ascontiguousarray(op.damping, dtype=float)
    if D.shape[0]:
        S = S - c2 * D
    lu, piv = scipy.linalg.lu_factor(S, check_finite=False)
    k3 = np.zeros(op.stiffness.shape[0]) if op.cubic is None else np.asarray(op.cubic, dtype=float)
    rec = np.ascontiguousarray(rec, dtype=np.int64)
    xs = np.empty((rec.shape[0], n))
    vs = np.empty_like(xs)
    args = (np.ascontiguousarray(x0, dtype=float).reshape(n), np.ascontiguousarray(v0, dtype=float).reshape(n),
            parameter_vector(system), float(h), int(steps), rec, xs, vs, float(b), float(g), float(al),
            np.ascontiguousarray(lu), np.ascontiguousarray(piv, dtype=np.int64), D, op.cubic is not None,
            np.ascontiguousarray(op.masses, dtype=float), np.ascontiguousarray(op.spring_ends, dtype=np.int64),
            np.ascontiguousarray(op.stiffness, dtype=float), np.ascontiguousarray(k3), int(MAX_NEWTON))
    evals, failed = timed_first_call(compiled(system), LOOP, *args)
    if failed >= 0:
        raise RunRefused(f"Newton iterations of the implicit step did not converge at step {failed} "
                         f"(cubic springs); accepted: a smaller dt", quantity="dt")
    return xs, vs, int(evals)


__all__ = ["LOOP", "route", "run_newmark"]
