"""The work–precision benchmark behind ``springchain bench``.

Every method runs from the scene's initial state over ``[0, T]``; each run
is one record: ``method``, ``setting`` (step or tolerance), ``error``,
``energy_error``, ``final_energy_norm_error``, ``seconds``, ``force_evals``
and the planner's ``predicted_error`` for that setting.

What is measured
----------------
* ``error``: the largest absolute position error over all recorded times.
  Fixed-step methods record every step (``t = i·h``, ``h = T/ceil(T/h_target)``);
  the exact, propagator and adaptive methods record the scene's output grid.
  On a scene without an exact solution every method records a common grid
  of spacing ``Δ`` (a multiple of the scene's dt) and steps are ``Δ/m``.
* the reference: on a linear, undamped, unforced chain, the modal solution
  from an ``mpmath`` eigen-decomposition (40 digits) evaluated in 80-bit
  extended precision (:class:`ExtendedModalReference`), so even the
  float64 modal method has a measurable (roundoff) error. Otherwise: Kahan–Li 8
  at a small step, whose own error is estimated from a second run at a
  larger step and reported (:class:`GridReference`).
* ``energy_error``: ``max_t |E(t) − E(0)| / |E(0)|``.
* ``final_energy_norm_error``: ``√(δvᵀMδv + δxᵀKδx)`` of the final-state error
  (K of the linear springs).
* ``seconds``: minimum of repeats after a warm-up with single-threaded BLAS
  (:mod:`numeric.timing`); a run's seconds include its own set-up (the
  modal method's eigen-decomposition, expm's matrix exponential), not the
  error evaluation. Derive/codegen time is measured by the command and
  reported separately.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field, replace
from typing import Callable

import numpy as np

from . import progress
from .driver import integrate, step_grid
from .integrators import ADAPTIVE, INTEGRATORS
from .integrators.base import Integrator, Problem
from .integrators.ivp import AdaptiveMethod
from .errors import RunRefused
from .plan import MAX_MASSES, ExactModal, Planner, adaptive_atol, modal_run, output_grid
from .spectrum import spectrum
from .system import System
from .timing import measure

#: Accuracies at which the targets are evaluated.
LINEAR_TARGET_ACCURACIES = tuple(10.0 ** -k for k in range(3, 13))
NONLINEAR_TARGET_ACCURACIES = tuple(10.0 ** -k for k in range(3, 10))
#: Required speed-ups: fastest method vs DOP853 (exact scenes); best integrator vs DOP853 (others).
LINEAR_TARGET_RATIO = 100.0
NONLINEAR_TARGET_RATIO = 3.0


# -- references ----------------------------------------------------------------------------------
@dataclass(frozen=True)
class ExtendedModalReference:
    """The exact solution of an undamped linear chain in extended precision.

    The eigen-decomposition of ``D = M^-1/2 K M^-1/2`` is done by ``mpmath`` at
    40 digits from the float64 parameters (so it is exact for the problem the
    methods solve); ω, the shapes and the modal initial values are kept as
    ``numpy.longdouble`` (64-bit mantissa on x86-64) and the solution is
    evaluated in that precision: phase errors ``ω t ε_ld`` stay below 1e-16
    up to ``t ≈ 10⁴`` and below 1e-13 at ``t = 10⁶``. Rigid modes (zero
    eigenvalues, by structure) follow ``q0 + q̇0 t``.

    Attributes
    ----------
    omega : ndarray of longdouble, shape (N,)
    shapes : ndarray of longdouble, shape (N, N)
        ``M^-1/2 E``.
    q0, p0 : ndarray of longdouble, shape (N,)
    description : str
    """

    omega: np.ndarray = field(repr=False)
    shapes: np.ndarray = field(repr=False)
    q0: np.ndarray = field(repr=False)
    p0: np.ndarray = field(repr=False)
    description: str = ""

    @classmethod
    def from_system(cls, system: System, x0: np.ndarray, v0: np.ndarray, digits: int = 40,
                    max_n: int = 40) -> "ExtendedModalReference":
        """Build from the system's masses and springs; above ``max_n`` masses fall back to float64 modes."""
        ld = np.longdouble
        n = system.n
        if n > max_n:
            spec = spectrum(system.masses, system.spring_ends, system.stiffness)
            r = np.sqrt(spec.masses)
            E = spec.vectors
            return cls(spec.omega.astype(ld), (E / r[:, None]).astype(ld), (E.T @ (r * x0)).astype(ld),
                       (E.T @ (r * v0)).astype(ld), "modal solution, float64 spectrum (N too large for mpmath)")
        import mpmath

        with mpmath.workdps(digits):
            K = mpmath.zeros(n, n)
            for (a, b), k in zip(system.spring_ends.tolist(), system.stiffness.tolist()):
                k = mpmath.mpf(k)
                for i in (a, b):
                    if i >= 0:
                        K[i, i] += k
                if a >= 0 and b >= 0 and a != b:
                    K[a, b] -= k
                    K[b, a] -= k
            r = [mpmath.sqrt(mpmath.mpf(m)) for m in system.masses.tolist()]
            D = mpmath.matrix(n, n)
            for i in range(n):
                for j in range(n):
                    D[i, j] = K[i, j] / (r[i] * r[j])
            lam, E = mpmath.eigsy(D)
            scale = max(abs(x) for x in lam) if n else 1
            x0m = [mpmath.mpf(v) for v in np.asarray(x0, dtype=float).tolist()]
            v0m = [mpmath.mpf(v) for v in np.asarray(v0, dtype=float).tolist()]

            def to_ld(x):
                hi = float(x)
                return ld(hi) + ld(float(x - hi))

            omega = np.array([to_ld(mpmath.sqrt(l_)) if l_ > mpmath.mpf(10) ** (-25) * scale else ld(0)
                              for l_ in lam], dtype=ld)
            shapes = np.array([[to_ld(E[i, j] / r[i]) for j in range(n)] for i in range(n)], dtype=ld)
            q0 = np.array([to_ld(mpmath.fsum(E[i, j] * r[i] * x0m[i] for i in range(n))) for j in range(n)],
                          dtype=ld)
            p0 = np.array([to_ld(mpmath.fsum(E[i, j] * r[i] * v0m[i] for i in range(n))) for j in range(n)],
                          dtype=ld)
        return cls(omega, shapes, q0, p0, f"modal solution: mpmath eigen-decomposition ({digits} digits), "
                                          "evaluated in 80-bit extended precision")

    def at(self, t: np.ndarray, chunk: int = 1 << 16) -> tuple[np.ndarray, np.ndarray]:
        """Positions and velocities at times ``t`` (S,), as float64 arrays of shape (S, N)."""
        t = np.asarray(t, dtype=float)
        xs = np.empty((t.shape[0], self.shapes.shape[0]))
        vs = np.empty_like(xs)
        w = self.omega
        rigid = w == 0
        wsafe = np.where(rigid, np.longdouble(1), w)
        for lo in range(0, t.shape[0], chunk):
            tt = t[lo:lo + chunk].astype(np.longdouble)[:, None]
            ph = tt * w[None, :]
            c, s = np.cos(ph), np.sin(ph)
            q = self.q0 * c + np.where(rigid, self.p0 * tt, self.p0 * s / wsafe)
            p = np.where(rigid, self.p0, -self.q0 * wsafe * s + self.p0 * c)
            xs[lo:lo + chunk] = (q @ self.shapes.T).astype(float)
            vs[lo:lo + chunk] = (p @ self.shapes.T).astype(float)
        return xs, vs


@dataclass(frozen=True)
class GridReference:
    """A reference trajectory on a grid, for scenes without an exact solution.

    Attributes
    ----------
    t : ndarray, shape (S,)
    x, v : ndarray, shape (S, N)
    accuracy : float
        Estimated largest position error of the reference itself.
    description : str
    """

    t: np.ndarray = field(repr=False)
    x: np.ndarray = field(repr=False)
    v: np.ndarray = field(repr=False)
    accuracy: float
    description: str

    @classmethod
    def kahan_li(cls, problem: Problem, x0, v0, t_end: float, spacing: float, m_fine: int, m_coarse: int,
                 progress: Callable[[str], None] | None = None) -> "GridReference":
        """Kahan–Li 8 with steps ``spacing/m_fine``; its error ≈ difference from ``spacing/m_coarse``
        times ``r⁸/(1 − r⁸)``, ``r = m_coarse/m_fine`` (eighth order)."""
        integ = INTEGRATORS["kahan-li8"]()
        n = int(round(t_end / spacing))
        if progress:
            progress(f"reference: kahan-li8 at h = {spacing / m_fine:.4g} over t = {t_end:g}")
        fine = integrate(integ, problem, x0, v0, spacing / m_fine, n * m_fine, record_every=m_fine)
        coarse = integrate(integ, problem, x0, v0, spacing / m_coarse, n * m_coarse, record_every=m_coarse)
        r8 = (m_coarse / m_fine) ** 8
        diff = float(np.max(np.abs(fine.x - coarse.x)))
        acc = diff * r8 / (1 - r8)
        return cls(fine.t, fine.x[..., 0], fine.v[..., 0], acc,
                   f"kahan-li8 at h = {spacing / m_fine:.4g} (estimated error {acc:.1e} from a second run at "
                   f"h = {spacing / m_coarse:.4g})")

    def at(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        idx = np.rint(np.asarray(t) / (self.t[1] - self.t[0])).astype(int)
        return self.x[idx], self.v[idx]


# -- records ---------------------------------------------------------------------------------------
@dataclass(frozen=True)
class BenchRecord:
    """One run of the benchmark (see the module docstring for the meaning of each field)."""

    method: str
    setting: str
    dt: float | None
    rtol: float | None
    steps: int | None
    error: float
    energy_error: float
    final_energy_norm_error: float
    seconds: float
    force_evals: int
    predicted_error: float | None
    repeats: int = 1

    def as_json(self) -> dict:
        def num(v):
            return None if v is None else float(v)

        return {"method": self.method, "setting": self.setting, "error": num(self.error),
                "energy_error": num(self.energy_error), "seconds": num(self.seconds),
                "force_evals": int(self.force_evals), "predicted_error": num(self.predicted_error),
                "final_energy_norm_error": num(self.final_energy_norm_error), "dt": num(self.dt),
                "rtol": num(self.rtol), "steps": self.steps, "repeats": self.repeats}


@dataclass(frozen=True)
class BenchConfig:
    """Sweep sizes. ``quick`` is the bounded version used by the tests.

    Attributes
    ----------
    eval_cap : int
        Largest force evaluations of one fixed-step run in the sweep, per 100 time units of horizon.
    adaptive_cap : int
        An adaptive method's sweep stops after a run with more evaluations (per 100 time units).
    target_errors : tuple of float
        Errors the fixed-step sweep aims at (through the planner's model; linear scenes).
    rtols : tuple of float
    timing_budget : float
        Seconds of timed repeats per run.
    horizons_measured, horizons_model : tuple of float
        Error-vs-horizon study: horizons run, and horizons predicted by the model.
    horizon_eval_cap : int
        Force evaluations per method in the horizon study (longer horizons are modelled).
    """

    quick: bool = False
    eval_cap: int = 200_000
    adaptive_cap: int = 200_000
    target_errors: tuple = tuple(10.0 ** -k for k in range(1, 14))
    rtols: tuple = tuple(10.0 ** -k for k in range(3, 14))
    dop853_rtols: tuple = tuple(10.0 ** (-k / 2) for k in range(6, 28))
    timing_budget: float = 0.3
    horizons_measured: tuple = (1e2, 1e3, 1e4)
    horizons_model: tuple = (1e2, 1e3, 1e4, 1e5, 1e6)
    horizon_eval_cap: int = 320_000
    horizon_work: float = 32.0
    horizon_dop853_rtol: float = 1e-9
    horizon_dop853_cap: float = 1e3

    @classmethod
    def quick_config(cls) -> "BenchConfig":
        return cls(True, eval_cap=6_000, adaptive_cap=8_000, target_errors=(1e-2, 1e-5, 1e-8),
                   rtols=(1e-4, 1e-7), dop853_rtols=(1e-4, 1e-7), timing_budget=0.02, horizons_measured=(1e2,),
                   horizons_model=(1e2, 1e4, 1e6), horizon_eval_cap=5_000, horizon_dop853_cap=1e2)


@dataclass(frozen=True)
class HorizonCurve:
    """Error against horizon for one method at one setting.

    measured_t, measured_error, measured_energy : ndarray — horizons actually run;
    model_t, model_error : ndarray — the model's prediction (empty if none);
    model_label : str.
    """

    method: str
    setting: str
    measured_t: np.ndarray = field(repr=False)
    measured_error: np.ndarray = field(repr=False)
    measured_energy: np.ndarray = field(repr=False)
    model_t: np.ndarray = field(repr=False)
    model_error: np.ndarray = field(repr=False)
    model_label: str = ""


@dataclass(frozen=True)
class BenchResult:
    scene: str
    t_end: float
    exact: bool
    reference: str
    records: tuple[BenchRecord, ...]
    horizons: tuple[HorizonCurve, ...] = ()
    notes: tuple[str, ...] = ()
    derive_seconds: float | None = None

    def targets(self) -> dict:
        """The issue's targets evaluated on these records (see :func:`targets`)."""
        return targets(self.records, self.exact)

    def as_json(self) -> dict:
        return {"scene": self.scene, "t_end": self.t_end, "reference": self.reference,
                "derive_seconds": self.derive_seconds, "notes": list(self.notes),
                "records": [r.as_json() for r in self.records], "targets": self.targets()}


# -- measuring -------------------------------------------------------------------------------------
def _energy_errors(system: System, x: np.ndarray, v: np.ndarray, e0: float) -> float:
    """``max |E − E0| / |E0|``; x, v shape (S, N)."""
    e = system.energy(x.T, v.T)
    return float(np.max(np.abs(e - e0)) / max(abs(e0), 1e-300))


def energy_norm(system: System, dx: np.ndarray, dv: np.ndarray) -> float:
    """``√(δvᵀMδv + δxᵀKδx)`` for one state difference (N,), K of the linear springs."""
    a, b = system.spring_ends[:, 0], system.spring_ends[:, 1]
    da = np.where(a >= 0, dx[np.maximum(a, 0)], 0.0)
    db = np.where(b >= 0, dx[np.maximum(b, 0)], 0.0)
    pot = float(np.sum(system.stiffness * (da - db) ** 2))
    return math.sqrt(max(float(np.sum(system.masses * dv**2)) + pot, 0.0))


class _Progress:
    def __init__(self, enabled: bool, total: int):
        self.enabled = enabled
        self.total = total
        self.done = 0
        self.t0 = time.perf_counter()

    def note(self, text: str) -> None:
        if self.enabled:
            progress.line(text, prefix="bench")

    def run(self, label: str, rec: BenchRecord | None = None) -> None:
        self.done += 1
        if self.enabled and rec is not None:
            progress.line(f"[{self.done:3d}/{self.total}] {time.perf_counter() - self.t0:6.1f}s  "
                          f"{label:<28} error {rec.error:9.2e}  {rec.seconds * 1e3:9.2f} ms  "
                          f"{rec.force_evals:>9} evals", prefix="bench")


@dataclass
class _Context:
    system: System
    problem: Problem
    x0: np.ndarray
    v0: np.ndarray
    t_end: float
    dt_out: float
    planner: Planner
    reference: object
    exact: bool
    spacing: float  # grid spacing for nonlinear scenes
    config: BenchConfig
    progress: _Progress
    e0: float = 0.0

    def ref(self, t):
        return self.reference.at(t)


def _record(ctx: _Context, method: str, setting: str, dt, rtol, steps, t, x, v, timing, evals,
            predicted) -> BenchRecord:
    xr, vr = ctx.ref(t)
    err = float(np.max(np.abs(x - xr)))
    fin = energy_norm(ctx.system, x[-1] - xr[-1], v[-1] - vr[-1])
    rec = BenchRecord(method, setting, dt, rtol, steps, err, _energy_errors(ctx.system, x, v, ctx.e0), fin,
                      timing.seconds, int(evals), predicted, timing.repeats)
    ctx.progress.run(f"{method} {setting}", rec)
    return rec


def _run_step(ctx: _Context, integ: Integrator, steps: int, record_every: int = 1,
              h: float | None = None) -> BenchRecord:
    h = ctx.t_end / steps if h is None else h
    timing = measure(lambda: integrate(integ, ctx.problem, ctx.x0, ctx.v0, h, steps, record_every),
                     budget=ctx.config.timing_budget)
    tr = timing.result
    predicted = None
    if integ.name in ctx.planner.responses:
        predicted = ctx.planner.predict_error(integ, steps)[0]
    elif integ.name in {p.name for p in ctx.planner.propagators}:
        predicted = ctx.planner.propagator_error(steps)
    return _record(ctx, integ.name, f"h={h:.4g}", h, None, steps, tr.t, tr.x[..., 0], tr.v[..., 0], timing,
                   tr.force_evals, predicted)


def _run_adaptive(ctx: _Context, method: AdaptiveMethod, rtol: float) -> BenchRecord:
    t = output_grid(ctx.t_end, ctx.spacing)
    atol = adaptive_atol(ctx.x0, ctx.v0, rtol)
    timing = measure(lambda: method.solve(ctx.problem, ctx.x0, ctx.v0, t, rtol, atol),
                     budget=ctx.config.timing_budget)
    res = timing.result
    law = ctx.planner.adaptive.get(method.name)
    predicted = law.error(rtol, ctx.t_end) if law else None
    return _record(ctx, method.name, f"rtol={rtol:.2g}", None, rtol, None, t, res.x[..., 0], res.v[..., 0],
                   timing, res.force_evals, predicted)


def _run_modal(ctx: _Context, source: str = "svd") -> BenchRecord:
    """The exact method, its spectrum from the SVD route (``svd``) or the generated closed forms."""
    t = output_grid(ctx.t_end, ctx.dt_out)
    timing = measure(lambda: modal_run(ctx.system, ctx.x0, ctx.v0, t, source), budget=ctx.config.timing_budget)
    x, v = timing.result
    predicted = ctx.planner.exact_error(t.shape[0] - 1)
    return _record(ctx, ExactModal.name, f"{source} spectrum", None, None, None, t, x, v, timing, 0, predicted)


def _step_sweep(ctx: _Context, integ: Integrator) -> list[int]:
    """Step counts of the sweep: the planner's steps for each target error, and the scene's dt."""
    cfg = ctx.config
    stages = max(integ.evals_per_step, 1.0)
    counts = {step_grid(ctx.t_end, ctx.dt_out)[1]}
    for tol in cfg.target_errors:
        c = ctx.planner.plan_step(integ, tol)
        if c.reachable and c.steps * stages <= cfg.eval_cap:
            counts.add(int(c.steps))
    n_min = ctx.planner._min_steps(integ)
    return sorted(n for n in counts if n >= n_min and n * stages <= max(cfg.eval_cap, 1))


def _grid_sweep(ctx: _Context, integ: Integrator) -> list[tuple[int, int, int]]:
    """Nonlinear scenes: ``(steps, stride, j)`` of steps ``h = jΔ/stride`` whose recorded states lie on the grid.

    Targets ``h`` are spaced by 2^(1/3) from the stability edge (with a margin for the
    nonlinear stiffening) down to the evaluation cap, then snapped to ``h = jΔ`` (every
    step recorded; ``floor(n_grid/j)`` steps, so a run may stop less than one step
    short of T) or ``h = Δ/m`` (every ``m``-th step recorded). The scene's own dt is
    always included.
    """
    cfg = ctx.config
    spacing = ctx.spacing
    n_grid = int(round(ctx.t_end / spacing))
    w = ctx.planner.model.omega_max * 1.25  # nonlinear stiffening margin over the linearization
    h = 0.9 * integ.stability_limit / w
    k = int(round(spacing / ctx.dt_out))
    out = {(n_grid * k, k, 1)}
    while True:
        if h >= spacing:
            j = int(math.floor(h / spacing))
            cand = (n_grid // j, 1, j)
        else:
            m = math.ceil(spacing / h)
            cand = (n_grid * m, m, 1)
        if cand[0] * integ.evals_per_step > cfg.eval_cap:
            break
        out.add(cand)
        h /= 2.0 ** (1.0 / 3.0)
    return sorted(c for c in out if c[0] * integ.evals_per_step <= cfg.eval_cap
                  and w * spacing * c[2] / c[1] < 0.9 * integ.stability_limit)


def run_bench(system: System, x0: np.ndarray, v0: np.ndarray, t_end: float, dt_out: float, scene: str = "",
              config: BenchConfig | None = None, progress: bool = True,
              methods: tuple[str, ...] | None = None) -> BenchResult:
    """Run the whole sweep (call inside :func:`~numeric.timing.single_threaded_blas`).

    Parameters
    ----------
    system : System
    x0, v0 : ndarray, shape (N,)
    t_end : float
        Horizon T.
    dt_out : float
        The scene's output spacing (its dt times record_every).
    config : BenchConfig, optional
    methods : tuple of str, optional
        Restrict to these method names (default: every method that applies).
    """
    config = config or BenchConfig()
    if t_end > 100.0:  # caps are per 100 time units: a longer horizon sweeps the same steps
        config = replace(config, eval_cap=int(config.eval_cap * t_end / 100.0),
                         adaptive_cap=int(config.adaptive_cap * t_end / 100.0))
    x0 = np.asarray(x0, dtype=float)
    v0 = np.asarray(v0, dtype=float)
    problem = Problem.from_system(system)
    exact = bool(system.exact_available and system.conservative)
    if system.n > MAX_MASSES:
        raise RunRefused(f"bench uses the dense modes of the chain: at most {MAX_MASSES} masses (this scene "
                         f"has {system.n}); for long chains see `springchain scaling`")
    if not system.conservative:
        raise RunRefused("bench covers conservative scenes (springs, cubic springs); this scene has dampers, "
                         "forces or gravity")
    prog = _Progress(progress, 0)
    notes: list[str] = []
    prog.note(f"measuring costs and building models for {scene or 'the scene'} (t = 0 … {t_end:g})")
    if exact:
        reference = ExtendedModalReference.from_system(system, x0, v0)
        spacing = dt_out
        planner = Planner.for_system(system, x0, v0, t_end, dt_out,
                                     reference=lambda t: reference.at(t)[0])
    else:
        lin = spectrum(system.masses, system.spring_ends, system.stiffness)
        w = float(lin.omega_max) if lin.omega.size else 1.0
        k = max(1, int(math.floor(0.1 / (w * dt_out))))  # a fine grid: many steps jΔ and Δ/m
        n_total = int(round(t_end / dt_out))
        if abs(n_total * dt_out - t_end) <= 1e-9 * t_end:  # a grid that ends exactly at t_end
            k = max(d for d in range(1, k + 1) if n_total % d == 0)
        spacing = dt_out * k
        n_grid = int(round(t_end / spacing))
        t_end = n_grid * spacing
        m_fine = max(2, int(math.ceil(spacing * w / 0.074)))  # Kahan-Li 8 at ω_max·h ≈ 0.074
        m_coarse = max(1, int(round(m_fine * 2 / 3)))
        reference = GridReference.kahan_li(problem, x0, v0, t_end, spacing, m_fine, m_coarse, prog.note)
        notes.append(f"no exact solution: error measured at the recorded steps on the grid t = k·{spacing:g} "
                     f"(steps h = j·{spacing:g} record every step, h = {spacing:g}/m every m-th)")
        planner = Planner.for_system(system, x0, v0, t_end, spacing,
                                     reference=lambda t: reference.at(t)[0])
    ctx = _Context(system, problem, x0, v0, t_end, dt_out, planner, reference, exact, spacing, config, prog,
                   float(system.energy(x0[:, None], v0[:, None])[0]))
    wanted = set(methods) if methods else None

    def use(name):
        return wanted is None or name in wanted

    jobs: list[tuple[str, Callable[[], BenchRecord]]] = []
    if exact and use(ExactModal.name):
        jobs.append(("modal", lambda: _run_modal(ctx, "svd")))
        if getattr(system.module, "CLOSED_FORM", False):
            jobs.append(("modal", lambda: _run_modal(ctx, "closed-form")))
    for integ in planner.step_methods:
        if not use(integ.name):
            continue
        if exact:
            for n in _step_sweep(ctx, integ):
                jobs.append((integ.name, lambda integ=integ, n=n: _run_step(ctx, integ, n)))
        else:
            for steps, stride, j in _grid_sweep(ctx, integ):
                jobs.append((integ.name, lambda integ=integ, n=steps, m=stride, j=j:
                             _run_step(ctx, integ, n, m, h=spacing * j / m)))
    for integ in planner.propagators:
        if use(integ.name):
            jobs.append((integ.name, lambda integ=integ: _run_step(ctx, integ, step_grid(t_end, dt_out)[1])))
    adaptive_jobs = [(name, cls_(), config.dop853_rtols if name == "dop853" else config.rtols)
                     for name, cls_ in ADAPTIVE.items() if use(name)]
    prog.total = len(jobs) + sum(len(r) for _, _, r in adaptive_jobs)
    records = [job() for _, job in jobs]
    for name, method, rtols in adaptive_jobs:
        for rtol in rtols:
            rec = _run_adaptive(ctx, method, rtol)
            records.append(rec)
            if rec.force_evals > config.adaptive_cap:
                skipped = [r for r in rtols if r < rtol]
                if skipped:
                    notes.append(f"{name}: stopped at rtol={rtol:.0e} ({rec.force_evals} evaluations > cap "
                                 f"{config.adaptive_cap}); not run: rtol " + ", ".join(f"{r:.0e}" for r in skipped))
                    prog.total -= len(skipped)
                break
    horizons: tuple[HorizonCurve, ...] = ()
    if exact and methods is None:
        horizons, hnotes = horizon_study(ctx)
        notes.extend(hnotes)
    desc = reference.description
    return BenchResult(scene, t_end, exact, desc, tuple(records), horizons, tuple(notes))


# -- error against horizon ---------------------------------------------------------------------------
HORIZON_METHODS = ("verlet", "yoshida4", "blanes-moan4", "blanes-moan6", "kahan-li8", "rk4")


def horizon_study(ctx: _Context) -> tuple[tuple[HorizonCurve, ...], list[str]]:
    """Error and energy error against the horizon, at equal work per unit time.

    Each step method runs at ``h = stages / W`` (``W`` force evaluations per
    unit time, the same for all) as one long run whose running maximum of the
    error is read at the horizons; runs stop at the evaluation cap and the
    longer horizons come from the closed-form model (envelope, dashed).
    DOP853 runs at one tolerance up to a cap on the horizon and is
    extrapolated linearly in T beyond it (labelled as such).
    """
    cfg = ctx.config
    curves = []
    notes = []
    model_t = np.geomspace(cfg.horizons_model[0], cfg.horizons_model[-1], 41)
    for name in HORIZON_METHODS:
        integ = INTEGRATORS[name]()
        h = integ.evals_per_step / cfg.horizon_work
        if ctx.planner.model.omega_max * h >= integ.stability_limit:
            continue
        t_cap = max([T for T in cfg.horizons_measured if T / h * integ.evals_per_step <= cfg.horizon_eval_cap]
                    or [cfg.horizons_measured[0]])
        hs, n = step_grid(t_cap, h)
        every = max(1, n // 100_000)
        ctx.progress.note(f"horizon: {name} at h = {hs:.4g} up to t = {t_cap:g} ({n} steps)")
        tr = integrate(integ, ctx.problem, ctx.x0, ctx.v0, hs, n, record_every=every)
        xr, _ = ctx.reference.at(tr.t)
        err = np.maximum.accumulate(np.max(np.abs(tr.x[..., 0] - xr), axis=1))
        e = ctx.system.energy(tr.x[..., 0].T, tr.v[..., 0].T)
        een = np.maximum.accumulate(np.abs(e - ctx.e0) / abs(ctx.e0))
        Ts = np.array([T for T in cfg.horizons_measured if T <= t_cap])
        at = np.searchsorted(tr.t, Ts * (1 - 1e-12))
        resp = ctx.planner.responses[name]
        model = np.array([ctx.planner.model.envelope(resp, hs, int(round(T / hs))) for T in model_t])
        curves.append(HorizonCurve(name, f"h={hs:.4g}", Ts, err[at], een[at], model_t, model,
                                   "closed-form envelope"))
        if t_cap < cfg.horizons_measured[-1]:
            notes.append(f"horizon study: {name} measured up to t = {t_cap:g} (cap {cfg.horizon_eval_cap} "
                         f"force evaluations); longer horizons from the model")
    # DOP853 at one tolerance
    dop = ADAPTIVE["dop853"]()
    rtol = cfg.horizon_dop853_rtol
    Ts = np.array([T for T in cfg.horizons_measured if T <= cfg.horizon_dop853_cap])
    t_cap = float(Ts[-1])
    ctx.progress.note(f"horizon: dop853 at rtol {rtol:.0e} up to t = {t_cap:g}")
    grid = output_grid(t_cap, ctx.dt_out)
    res = dop.solve(ctx.problem, ctx.x0, ctx.v0, grid, rtol, adaptive_atol(ctx.x0, ctx.v0, rtol))
    xr, _ = ctx.reference.at(grid)
    err = np.maximum.accumulate(np.max(np.abs(res.x[..., 0] - xr), axis=1))
    e = ctx.system.energy(res.x[..., 0].T, res.v[..., 0].T)
    een = np.maximum.accumulate(np.abs(e - ctx.e0) / abs(ctx.e0))
    at = np.searchsorted(grid, Ts * (1 - 1e-12))
    rate = float(err[-1] / t_cap)
    curves.append(HorizonCurve("dop853", f"rtol={rtol:.0e}", Ts, err[at], een[at], model_t, rate * model_t,
                               "measured, extrapolated ∝ T"))
    if t_cap < cfg.horizons_model[-1]:
        notes.append(f"horizon study: dop853 (rtol {rtol:.0e}, {res.force_evals} evaluations for t = {t_cap:g}) "
                     f"measured up to t = {t_cap:g} only (cost ∝ T); beyond, its error is extrapolated ∝ T")
    return tuple(curves), notes


# -- targets -------------------------------------------------------------------------------------------
def _cheapest(records, accuracy: float, key: str, pick: Callable[[BenchRecord], bool]):
    ok = [r for r in records if pick(r) and r.error <= accuracy]
    return min(ok, key=lambda r: getattr(r, key)) if ok else None


def targets(records: tuple[BenchRecord, ...], exact: bool) -> dict:
    """The issue's targets from the records.

    Exact scenes: for each accuracy 1e-3 … 1e-12 the fastest run reaching it
    against the fastest DOP853 run reaching it (needs ≥ 100×). Other scenes:
    for 1e-3 … 1e-9 the best fixed-step integrator against DOP853, in force
    evaluations and in seconds (needs ≥ 3× in both).
    """
    rows = []
    fixed = set(INTEGRATORS)
    if exact:
        for acc in LINEAR_TARGET_ACCURACIES:
            best = _cheapest(records, acc, "seconds", lambda r: True)
            dop = _cheapest(records, acc, "seconds", lambda r: r.method == "dop853")
            ratio = dop.seconds / best.seconds if best and dop else None
            rows.append({"accuracy": acc, "fastest": best and best.method, "fastest_setting": best and best.setting,
                         "fastest_seconds": best and best.seconds, "dop853_setting": dop and dop.setting,
                         "dop853_seconds": dop and dop.seconds, "speedup": ratio,
                         "met": bool(ratio is not None and ratio >= LINEAR_TARGET_RATIO)})
        return {"kind": "fastest vs dop853 (seconds)", "required": LINEAR_TARGET_RATIO, "rows": rows}
    for acc in NONLINEAR_TARGET_ACCURACIES:
        dop_e = _cheapest(records, acc, "force_evals", lambda r: r.method == "dop853")
        dop_s = _cheapest(records, acc, "seconds", lambda r: r.method == "dop853")
        best_e = _cheapest(records, acc, "force_evals", lambda r: r.method in fixed)
        best_s = _cheapest(records, acc, "seconds", lambda r: r.method in fixed)
        re_ = dop_e.force_evals / best_e.force_evals if dop_e and best_e else None
        rs = dop_s.seconds / best_s.seconds if dop_s and best_s else None
        rows.append({"accuracy": acc, "best_evals": best_e and f"{best_e.method} {best_e.setting}",
                     "best_force_evals": best_e and best_e.force_evals,
                     "dop853_force_evals": dop_e and dop_e.force_evals, "evals_ratio": re_,
                     "best_seconds_run": best_s and f"{best_s.method} {best_s.setting}",
                     "best_seconds": best_s and best_s.seconds, "dop853_seconds": dop_s and dop_s.seconds,
                     "seconds_ratio": rs,
                     "met": bool(re_ is not None and rs is not None and re_ >= NONLINEAR_TARGET_RATIO
                                 and rs >= NONLINEAR_TARGET_RATIO)})
    return {"kind": "best fixed-step integrator vs dop853 (force evaluations and seconds)",
            "required": NONLINEAR_TARGET_RATIO, "rows": rows}


# -- outputs -----------------------------------------------------------------------------------------------
def _fmt(v, spec=".3g"):
    return "—" if v is None or (isinstance(v, float) and math.isnan(v)) else format(v, spec)


def markdown_table(result: BenchResult) -> str:
    """The records as a Markdown table, then the targets."""
    lines = [f"# springchain bench: {result.scene}, t = 0 … {result.t_end:g}", "",
             f"Reference: {result.reference}.", ""]
    if result.derive_seconds is not None:
        lines += [f"Derive + codegen (once, not part of any run): {result.derive_seconds:.3f} s.", ""]
    lines += ["| method | setting | error | predicted error | energy error | final error (energy norm) "
              "| seconds | force evals |", "|---|---|---|---|---|---|---|---|"]
    for r in result.records:
        lines.append(f"| {r.method} | {r.setting} | {_fmt(r.error, '.2e')} | {_fmt(r.predicted_error, '.2e')} | "
                     f"{_fmt(r.energy_error, '.2e')} | {_fmt(r.final_energy_norm_error, '.2e')} | "
                     f"{_fmt(r.seconds, '.3e')} | {r.force_evals} |")
    lines += ["", "## Targets", ""]
    tg = result.targets()
    if result.exact:
        lines += [f"Fastest run reaching each accuracy against the fastest DOP853 run reaching it "
                  f"(required: ≥ {tg['required']:g}×).", "",
                  "| accuracy | fastest | seconds | DOP853 | seconds | speed-up | met |", "|---|---|---|---|---|---|---|"]
        for row in tg["rows"]:
            lines.append(f"| {row['accuracy']:.0e} | {row['fastest'] or '—'} {row['fastest_setting'] or ''} | "
                         f"{_fmt(row['fastest_seconds'], '.3e')} | {row['dop853_setting'] or 'not reached'} | "
                         f"{_fmt(row['dop853_seconds'], '.3e')} | {_fmt(row['speedup'], '.0f')} | "
                         f"{'yes' if row['met'] else 'NO'} |")
    else:
        lines += [f"Best fixed-step integrator against DOP853 at equal accuracy (required: ≥ {tg['required']:g}× "
                  "in force evaluations and in seconds).", "",
                  "| accuracy | best (evals) | evals | DOP853 evals | ratio | best (seconds) | seconds | "
                  "DOP853 seconds | ratio | met |", "|---|---|---|---|---|---|---|---|---|---|"]
        for row in tg["rows"]:
            lines.append(f"| {row['accuracy']:.0e} | {row['best_evals'] or '—'} | {_fmt(row['best_force_evals'])} | "
                         f"{_fmt(row['dop853_force_evals'])} | {_fmt(row['evals_ratio'], '.2f')} | "
                         f"{row['best_seconds_run'] or '—'} | {_fmt(row['best_seconds'], '.3e')} | "
                         f"{_fmt(row['dop853_seconds'], '.3e')} | {_fmt(row['seconds_ratio'], '.2f')} | "
                         f"{'yes' if row['met'] else 'NO'} |")
    if result.notes:
        lines += ["", "## Notes", ""] + [f"- {n}" for n in result.notes]
    return "\n".join(lines) + "\n"


def _method_order(records) -> list[str]:
    seen = []
    for r in records:
        if r.method not in seen:
            seen.append(r.method)
    return seen


def work_precision_figure(result: BenchResult):
    """Error against seconds and against force evaluations, log–log, one line per method."""
    import matplotlib

    from .plots import new_figure

    fig, axes = new_figure(1, 2, figsize=(13, 5.5))
    floor = 1e-17
    markers = "os^vD<>ph*Xd"
    colors = matplotlib.colormaps["tab20"].colors
    for j, name in enumerate(_method_order(result.records)):
        # connected in the order of the setting (coarse to fine), so timing noise shows as noise
        rs = sorted((r for r in result.records if r.method == name), key=lambda r: -r.error)
        err = np.array([max(r.error, floor) for r in rs])
        style = dict(marker=markers[j % len(markers)], ms=5, lw=1.2, label=name, color=colors[(2 * j) % 20])
        axes[0].loglog([r.seconds for r in rs], err, **style)
        ev = [(r.force_evals, e) for r, e in zip(rs, err) if r.force_evals > 0]
        if ev:
            axes[1].loglog([a for a, _ in ev], [b for _, b in ev], **style)
    axes[0].set_xlabel("wall-clock seconds per run (min of repeats, single-threaded BLAS)")
    axes[1].set_xlabel("force evaluations per run")
    for ax in axes:
        ax.set_ylabel("max |x − x_ref| over all recorded times [m]")
        ax.grid(alpha=0.3, which="both")
    axes[0].set_title(f"{result.scene}: error vs time (t = 0 … {result.t_end:g})")
    axes[1].set_title("error vs force evaluations (exact methods have none)")
    axes[0].legend(fontsize=8, ncol=2)
    axes[1].legend(fontsize=8, ncol=2)
    return fig


def horizon_figure(result: BenchResult):
    """Error and energy error against the horizon: measured (markers) and model (dashed)."""
    import matplotlib

    from .plots import new_figure

    fig, axes = new_figure(1, 2, figsize=(13, 5.5))
    colors = matplotlib.rcParams["axes.prop_cycle"].by_key()["color"]
    for j, c in enumerate(result.horizons):
        col = colors[j % len(colors)]
        axes[0].loglog(c.measured_t, np.maximum(c.measured_error, 1e-17), "o-", color=col,
                       label=f"{c.method} {c.setting} (measured)")
        if c.model_t.size:
            axes[0].loglog(c.model_t, np.maximum(c.model_error, 1e-17), "--", color=col, lw=1,
                           label=f"{c.method} ({c.model_label})")
        axes[1].loglog(c.measured_t, np.maximum(c.measured_energy, 1e-17), "o-", color=col, label=c.method)
    axes[0].set_xlabel("horizon T [s]")
    axes[0].set_ylabel("max |x − x_exact| over t ≤ T [m]")
    axes[0].set_title("Position error vs horizon (step methods: equal force evaluations per unit time)")
    axes[1].set_xlabel("horizon T [s]")
    axes[1].set_ylabel("max |E(t) − E(0)| / |E(0)| over t ≤ T")
    axes[1].set_title("Energy error vs horizon: bounded for symplectic methods")
    for ax in axes:
        ax.grid(alpha=0.3, which="both")
        ax.legend(fontsize=7, ncol=1)
    return fig


def write_outputs(result: BenchResult, out) -> list:
    """Write ``bench-<scene>.md``, ``.json`` and the figures into ``out``; returns the paths."""
    import json
    from pathlib import Path

    from . import plots
    from .files import atomic_write_text

    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    base = f"bench-{result.scene}"
    paths = [out / f"{base}.md", out / f"{base}.json", out / f"{base}-work-precision.png"]
    atomic_write_text(paths[0], markdown_table(result))
    atomic_write_text(paths[1], json.dumps(result.as_json(), indent=1, default=_json_default) + "\n")
    plots.save(work_precision_figure(result), paths[2])
    if result.horizons:
        paths.append(out / f"{base}-horizon.png")
        plots.save(horizon_figure(result), paths[-1])
    return paths


def _json_default(o):
    if isinstance(o, (np.floating, np.integer)):
        return o.item()
    raise TypeError(f"not JSON serialisable: {type(o).__name__}")


def with_derive_seconds(result: BenchResult, seconds: float | None) -> BenchResult:
    return replace(result, derive_seconds=seconds)
