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
from dataclasses import dataclass, replace
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
from .bench_records import (LINEAR_TARGET_ACCURACIES, LINEAR_TARGET_RATIO, NONLINEAR_TARGET_ACCURACIES,
                            NONLINEAR_TARGET_RATIO, BenchConfig, BenchRecord, BenchResult, HorizonCurve, targets)
from .bench_reference import ExtendedModalReference, GridReference
from .bench_report import horizon_figure, markdown_table, work_precision_figure, write_outputs

#: The benchmark's public names (the records, references and rendering live in their own modules).
__all__ = ["LINEAR_TARGET_ACCURACIES", "LINEAR_TARGET_RATIO", "NONLINEAR_TARGET_ACCURACIES", "NONLINEAR_TARGET_RATIO",
           "BenchConfig", "BenchRecord", "BenchResult", "HorizonCurve", "targets", "ExtendedModalReference",
           "GridReference", "horizon_figure", "markdown_table", "work_precision_figure", "write_outputs",
           "energy_norm", "run_bench", "horizon_study", "with_derive_seconds"]


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
    from .plan_pilot import check_pilot, needs_pilot

    if needs_pilot(system):  # damped, forced, gravity, ground; long uniform chains: against the exact solution
        check_pilot(system, "bench")
        from .bench_pilot import run_pilot_bench

        return run_pilot_bench(system, x0, v0, t_end, dt_out, scene, config, progress, methods)
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
                     for name, cls_ in ADAPTIVE.items()
                     if use(name) and (cls_.supports_damping or not system.damped)]
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


def with_derive_seconds(result: BenchResult, seconds: float | None) -> BenchResult:
    return replace(result, derive_seconds=seconds)
