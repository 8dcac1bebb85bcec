"""Run a fixed-step integrator, or SciPy's DOP853, as one compiled loop on a small scene.

:func:`route` says whether a system and an integrator have a compiled loop (else the caller takes
the NumPy driver); :func:`run_steps` runs it into preallocated frame arrays. The loop is picked by
the integrator's class (its scheme), never by its name.
"""

from __future__ import annotations

from contextlib import contextmanager

import numpy as np

from ..integrators.base import Integrator
from ..integrators.rk4 import RK4
from ..integrators.splitting import SplittingMethod
from ..integrators.verlet import VelocityVerlet
from ..integrators.verlet_compensated import CompensatedVerlet
from ..system import System
from .cache import available, compile_seconds, compiled, force_loaded, loop_on_hand, timed_first_call

#: Frames × masses kept in memory by one compiled run (beyond it the NumPy driver streams).
MAX_FRAME_VALUES = 50_000_000
#: A loop that must be compiled is compiled only for a run of at least this many force evaluations:
#: a loop's first compile costs seconds, as much as ~10⁵ evaluations on NumPy.
COMPILE_MIN_EVALS = 100_000
#: A loop compiled already (in this process or numba's disk cache) is taken for a scene whose force is not
#: compiled yet from this many evaluations: the force's cfunc compiles in 0.2–0.3 s, ~10⁴ NumPy evaluations.
FORCE_MIN_EVALS = 10_000


def loop_name(integrator: Integrator) -> str | None:
    """The loop of :mod:`.loops` that runs ``integrator``'s scheme (None: no compiled loop)."""
    cls = type(integrator)
    if cls is CompensatedVerlet:
        return "kahan_verlet_loop"
    if cls is VelocityVerlet:
        return "verlet_loop"
    if isinstance(integrator, SplittingMethod):
        return "splitting_loop"
    if cls is RK4:
        return "rk4_loop"
    return None


def scalar_ready(system: System) -> bool:
    """Whether the system's whole force is in the module's ``scalar_force``: a ``[masses]`` scene printed
    per mass, without force or ground tables (dampers come in as a matrix), and numba loads."""
    return (not system.chain and system.has("scalar_force") and not system.tabulated
            and system.ground in (None, "expression") and available())


@contextmanager
def eager(enabled: bool = True):
    """Within the block, compile the loop of every run (a benchmark: many runs share a loop and each is
    timed after a warm-up, so a compile costs wall time once and no timing)."""
    global COMPILE_MIN_EVALS
    old = COMPILE_MIN_EVALS
    if enabled:
        COMPILE_MIN_EVALS = 0
    try:
        yield
    finally:
        COMPILE_MIN_EVALS = old


def ready(system: System, loop: str) -> bool:
    """Whether a run of ``loop`` on ``system`` compiles nothing: the system's force is loaded in this process
    and the loop is loaded or in numba's disk cache (:func:`.cache.loop_on_hand`)."""
    return force_loaded(system) and loop_on_hand(loop)


def min_evals(system: System, loop: str) -> float:
    """Force evaluations from which a run of ``loop`` on ``system`` takes the compiled loop: 0 when nothing
    must compile (:func:`ready`); :data:`FORCE_MIN_EVALS` when only the force must (the loop is loaded or
    on disk); else :data:`COMPILE_MIN_EVALS` (within :func:`eager`: 0)."""
    if not loop_on_hand(loop):
        return float(COMPILE_MIN_EVALS)
    return 0.0 if force_loaded(system) else float(min(COMPILE_MIN_EVALS, FORCE_MIN_EVALS))


def worth_compiling(system: System, loop: str, evals: float) -> bool:
    """Take the compiled loop for a run of ``evals`` force evaluations (:func:`min_evals`). A run shorter
    than both thresholds on a system whose force is not loaded is refused first, without importing numba."""
    if evals < min(COMPILE_MIN_EVALS, FORCE_MIN_EVALS) and not force_loaded(system):
        return False
    return evals >= min_evals(system, loop)


def route(system: System, integrator: Integrator, frames: int, evals: float = float("inf")) -> str | None:
    """The compiled loop for this run of about ``evals`` force evaluations, or None (then the NumPy
    driver): small ``[masses]`` scenes, runs long enough to pay a first compile (:func:`worth_compiling`)."""
    name = loop_name(integrator)
    if name is None or frames * system.n > MAX_FRAME_VALUES or not worth_compiling(system, name, evals):
        return None
    return name if scalar_ready(system) else None


def parameter_vector(system: System) -> np.ndarray:
    """The parameter values in the module's PARAMETERS order (``scalar_force``'s ``p``)."""
    return system.parameter_vector()


def _half_flow(system: System, h: float) -> np.ndarray:
    Ad = system.damping_rate_matrix()
    if Ad is None:
        return np.zeros((0, 0))
    import scipy.linalg

    return np.ascontiguousarray(scipy.linalg.expm(np.asarray(Ad, dtype=float) * (0.5 * h)))


def run_steps(system: System, integrator: Integrator, name: str, x0: np.ndarray, v0: np.ndarray,
              h: float, steps: int, rec: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``steps`` steps of ``integrator``'s scheme from (x0, v0) (shape (N,)), compiled.

    Parameters
    ----------
    name : str
        The loop (:func:`route`).
    rec : ndarray of int, shape (F,)
        Recorded step indices, increasing, starting at 0.

    Returns
    -------
    xs, vs : ndarray, shape (F, N)
    """
    n = system.n
    c = compiled(system)
    x0 = np.ascontiguousarray(x0, dtype=np.float64).reshape(n)
    v0 = np.ascontiguousarray(v0, dtype=np.float64).reshape(n)
    rec = np.ascontiguousarray(rec, dtype=np.int64)
    xs = np.empty((rec.shape[0], n))
    vs = np.empty_like(xs)
    p = parameter_vector(system)
    E = _half_flow(system, h)
    args = (x0, v0, p, float(h), int(steps), rec, xs, vs, E)
    if name == "splitting_loop":
        tab = integrator.table
        kicks = np.array([b * h for b in tab.kicks], dtype=np.float64)
        drifts = np.array([a * h for a in tab.drifts], dtype=np.float64)
        nodes = np.array(tab.nodes, dtype=np.float64)
        args += (kicks, drifts, nodes)
    elif name == "rk4_loop":
        args += (np.zeros((0, 0)),)
    timed_first_call(c, name, *args)
    return xs, vs


def dop853(system: System, x0: np.ndarray, v0: np.ndarray, t_end: float, rtol: float, atol: float,
           max_steps: int = 0, t_eval: np.ndarray | None = None):
    """SciPy's DOP853 compiled: ``(x, v, step_ends, evaluations)`` at ``t_end`` from t = 0.

    Same tableau (``scipy.integrate._ivp.dop853_coefficients``), initial step, error norm and
    step control as ``scipy.integrate.solve_ivp(method="DOP853")`` on ``y = (x, v)``; ``step_ends``
    (shape (min(accepted, max_steps),)) are the accepted steps' end times. With ``t_eval`` (S,)
    (increasing, in [0, t_end]) ``x``, ``v`` are the frames there, shape (S, N), from SciPy's dense
    output as ``solve_ivp(..., t_eval=t_eval)`` computes them; else the state at ``t_end`` (N,).
    """
    from scipy.integrate._ivp import dop853_coefficients as dc

    from ..errors import RunRefused

    if not scalar_ready(system):
        raise RunRefused("the compiled DOP853 needs a [masses] scene of at most 12 masses without tables",
                         quantity="method")
    n = system.n
    c = compiled(system)
    Ad = system.damping_rate_matrix()
    Ad = np.zeros((0, 0)) if Ad is None else np.ascontiguousarray(Ad, dtype=float)
    ts = np.empty(max(int(max_steps), 1))
    te = np.zeros(0) if t_eval is None else np.ascontiguousarray(t_eval, dtype=np.float64)
    xs = np.empty((te.shape[0], n))
    vs = np.empty_like(xs)
    args = (np.ascontiguousarray(x0, dtype=float).reshape(n), np.ascontiguousarray(v0, dtype=float).reshape(n),
            parameter_vector(system), 0.0, float(t_end), float(rtol), float(atol), Ad,
            np.ascontiguousarray(dc.A), np.ascontiguousarray(dc.B), np.ascontiguousarray(dc.C),
            np.ascontiguousarray(dc.E3), np.ascontiguousarray(dc.E5), ts, int(max_steps), te, xs, vs,
            np.ascontiguousarray(dc.D))
    x, v, accepted, evals = timed_first_call(c, "dop853_loop", *args)
    if accepted < 0:
        raise RunRefused("compiled DOP853: the step size fell below the minimum", quantity="rtol")
    if t_eval is not None:
        x, v = xs, vs
    return x, v, ts[:min(accepted, max_steps)], int(evals)


def rkn(system: System, table, x0: np.ndarray, v0: np.ndarray, t_eval: np.ndarray, rtol: float, atol: float):
    """An embedded RKN pair (``table``, a :class:`~numeric.integrators.nystrom_tables.NystromTable`) compiled,
    with the step control of :class:`~numeric.integrators.nystrom.EmbeddedNystrom`, onto ``t_eval``.

    Returns
    -------
    AdaptiveResult
        x, v shape (S, N, 1).
    """
    from ..errors import RunRefused
    from ..integrators.ivp import AdaptiveResult

    n = system.n
    c = compiled(system)
    tab = table.arrays
    t_eval = np.ascontiguousarray(t_eval, dtype=np.float64)
    xs = np.empty((t_eval.shape[0], n))
    vs = np.empty_like(xs)
    args = (np.ascontiguousarray(x0, dtype=float).reshape(n), np.ascontiguousarray(v0, dtype=float).reshape(n),
            parameter_vector(system), t_eval, float(rtol), float(atol),
            *(np.ascontiguousarray(tab[key], dtype=np.float64) for key in ("c", "A", "b", "bp", "e", "ep")),
            bool(table.fsal), float(table.embedded_order), float(table.order), xs, vs)
    evals, steps = timed_first_call(c, "rkn_loop", *args)
    if steps == -1:
        raise RunRefused(f"method {table.name!r}: step size underflow", quantity="rtol")
    if steps == -2:
        raise RunRefused(f"method {table.name!r}: the solution is not finite", quantity="method")
    return AdaptiveResult(t_eval, xs[:, :, None], vs[:, :, None], int(evals), int(steps))


__all__ = ["eager", "rkn", "route", "ready", "min_evals", "worth_compiling", "COMPILE_MIN_EVALS", "FORCE_MIN_EVALS", "run_steps", "loop_name", "scalar_ready", "parameter_vector", "compile_seconds", "dop853",
           "MAX_FRAME_VALUES"]
