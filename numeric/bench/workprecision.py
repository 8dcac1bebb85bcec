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
  (:mod:`numeric.bench.timing`); a run's seconds include its own set-up (the
  modal method's eigen-decomposition, expm's matrix exponential), not the
  error evaluation. Derive/codegen time is measured by the command and
  reported separately.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Callable

import numpy as np

from .runs import (adaptive_rtols, adaptive_sweep, compile_note, energy_norm, progress_reporter,
                          peer_filter, report_run, selected_in_order, timed_run)
from ..plan.planner import Planner, exact_method, with_tolerance
from ..plan.pilot import check_pilot, needs_pilot
from ..progress import Reporter
from ..run import registry
from ..run.grid import Grid
from ..run.protocol import Kind, Method, Options, SpectrumSource
from ..run.protocol import record
from ..system import System
from .timing import measure
from .records import (LINEAR_TARGET_ACCURACIES, LINEAR_TARGET_RATIO, NONLINEAR_TARGET_ACCURACIES,
                            NONLINEAR_TARGET_RATIO, BenchConfig, BenchRecord, BenchResult, HorizonCurve, targets)
from .pilot import run_pilot_bench
from .reference import ExtendedModalReference, GridReference
from .report import horizon_figure, markdown_table, work_precision_figure, write_outputs

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


@dataclass
class _Context:
    system: System
    x0: np.ndarray
    v0: np.ndarray
    t_end: float
    dt_out: float
    planner: Planner
    reference: object
    exact: bool
    spacing: float  # grid spacing for nonlinear scenes
    config: BenchConfig
    progress: Reporter
    e0: float = 0.0

    def ref(self, t):
        return self.reference.at(t)


def _record(ctx: _Context, method: Method, setting: str, dt, rtol, steps, timing, predicted) -> BenchRecord:
    run = timing.result
    xr, vr = ctx.ref(run.t)
    err = float(np.max(np.abs(run.x - xr)))
    fin = energy_norm(ctx.system, run.x[-1] - xr[-1], run.v[-1] - vr[-1])
    rec = BenchRecord(method.name, setting, dt, rtol, steps, err, _energy_errors(ctx.system, run.x, run.v, ctx.e0),
                      fin, timing.seconds, run.force_evals, predicted, timing.repeats)
    report_run(ctx.progress, rec)
    return rec


def _run_step(ctx: _Context, method: Method, steps: int, record_every: int = 1,
              h: float | None = None) -> BenchRecord:
    h = ctx.t_end / steps if h is None else h
    timing = timed_run(method, ctx.system, ctx.x0, ctx.v0, Grid(h, steps, record_every), ctx.config.timing_budget)
    predicted = None
    if method in ctx.planner.responses:
        predicted = ctx.planner.predict_error(method, steps)[0]
    elif method in ctx.planner.propagators:
        predicted = ctx.planner.propagator_error(steps)
    return _record(ctx, method, f"h={h:.4g}", h, None, steps, timing, predicted)


def _run_adaptive(ctx: _Context, method: Method, rtol: float) -> BenchRecord:
    grid = Grid.covering(ctx.t_end, ctx.spacing)
    timing = timed_run(with_tolerance(method, ctx.x0, ctx.v0, rtol), ctx.system, ctx.x0, ctx.v0, grid,
                       ctx.config.timing_budget)
    law = ctx.planner.adaptive.get(method)
    predicted = law.error(rtol, ctx.t_end) if law else None
    return _record(ctx, method, f"rtol={rtol:.2g}", None, rtol, None, timing, predicted)


def _run_modal(ctx: _Context, source: SpectrumSource = SpectrumSource.SVD) -> BenchRecord:
    """The exact method with its set-up, its spectrum from the SVD route or the generated closed forms."""
    grid = Grid.covering(ctx.t_end, ctx.dt_out)
    method = exact_method(source)
    timing = measure(lambda: record(method, ctx.system.fresh(), ctx.x0, ctx.v0, grid), budget=ctx.config.timing_budget)
    predicted = ctx.planner.exact_error(grid.steps)
    return _record(ctx, method, f"{source.value} spectrum", None, None, None, timing, predicted)


def _step_sweep(ctx: _Context, method: Method) -> list[int]:
    """Step counts of the sweep: the planner's steps for each target error, and the scene's dt."""
    cfg = ctx.config
    stages = max(method.traits.evals_per_step, 1.0)
    counts = {Grid.covering(ctx.t_end, ctx.dt_out).steps}
    for tol in cfg.target_errors:
        c = ctx.planner.plan_step(method, tol)
        if c.reachable and c.steps * stages <= cfg.eval_cap:
            counts.add(int(c.steps))
    n_min = ctx.planner.min_steps(method)
    return sorted(n for n in counts if n >= n_min and n * stages <= max(cfg.eval_cap, 1))


def _grid_sweep(ctx: _Context, method: Method) -> list[tuple[int, int, int]]:
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
    traits = method.traits
    w = ctx.planner.model.omega_max * 1.25  # nonlinear stiffening margin over the linearization
    h = 0.9 * min(traits.stability_limit, 2.0) / w  # an unconditionally stable step starts at ω·h = 1.8
    k = int(round(spacing / ctx.dt_out))
    out = {(n_grid * k, k, 1)}
    while True:
        if h >= spacing:
            j = int(math.floor(h / spacing))
            cand = (n_grid // j, 1, j)
        else:
            m = math.ceil(spacing / h)
            cand = (n_grid * m, m, 1)
        if cand[0] * traits.evals_per_step > cfg.eval_cap:
            break
        out.add(cand)
        h /= 2.0 ** (1.0 / 3.0)
    return sorted(c for c in out if c[0] * traits.evals_per_step <= cfg.eval_cap
                  and w * spacing * c[2] / c[1] < 0.9 * traits.stability_limit)


def run_bench(system: System, x0: np.ndarray, v0: np.ndarray, t_end: float, dt_out: float, scene: str = "",
              config: BenchConfig | None = None, progress: bool = True,
              methods: tuple[str, ...] | None = None, settings: tuple = ()) -> BenchResult:
    """Run the whole sweep (call inside :func:`~numeric.bench.timing.single_threaded_blas`).

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
    settings : tuple of (str, float), optional
        Method settings (HHT's ``alpha``), checked by the caller.
    """
    config = config or BenchConfig()
    if t_end > 100.0:  # caps are per 100 time units: a longer horizon sweeps the same steps
        config = replace(config, eval_cap=int(config.eval_cap * t_end / 100.0),
                         adaptive_cap=int(config.adaptive_cap * t_end / 100.0))
    x0 = np.asarray(x0, dtype=float)
    v0 = np.asarray(v0, dtype=float)
    exact = bool(system.springs_only and system.exact_available)
    if needs_pilot(system):  # damped, forced, gravity, ground; long uniform chains: against the exact solution
        check_pilot(system, "bench")
        return run_pilot_bench(system, x0, v0, t_end, dt_out, scene, config, progress, methods, settings)
    prog = progress_reporter(progress)
    notes: list[str] = []
    selected = {m for m in registry.methods(options=Options(progress=False, settings=settings), only=methods)
                if peer_filter(config, methods)(m)}
    only = frozenset(m.name for m in selected)  # the planner models these only
    prog.say(f"measuring costs and building models for {scene or 'the scene'} (t = 0 … {t_end:g})")
    if exact:
        reference = ExtendedModalReference.from_system(system, x0, v0)
        spacing = dt_out
        planner = Planner.for_system(system, x0, v0, t_end, dt_out,
                                     reference=lambda t: reference.at(t)[0], settings=settings, only=only)
    else:
        lin = system.spectrum
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
        reference = GridReference.kahan_li(system, x0, v0, t_end, spacing, m_fine, m_coarse, prog.say)
        notes.append(f"no exact solution: error measured at the recorded steps on the grid t = k·{spacing:g} "
                     f"(steps h = j·{spacing:g} record every step, h = {spacing:g}/m every m-th)")
        planner = Planner.for_system(system, x0, v0, t_end, spacing,
                                     reference=lambda t: reference.at(t)[0], settings=settings, only=only)
    ctx = _Context(system, x0, v0, t_end, dt_out, planner, reference, exact, spacing, config, prog,
                   float(system.energy(x0[:, None], v0[:, None])[0]))

    jobs: list[Callable[[], BenchRecord]] = []
    if exact and any(m.kind is Kind.EXACT for m in selected):
        jobs.append(lambda: _run_modal(ctx, SpectrumSource.SVD))
        if system.provided.closed_form:
            jobs.append(lambda: _run_modal(ctx, SpectrumSource.CLOSED_FORM))
    for m in planner.step_methods:
        if m not in selected:
            continue
        if exact:
            for n in _step_sweep(ctx, m):
                jobs.append(lambda m=m, n=n: _run_step(ctx, m, n))
        else:
            for steps, stride, j in _grid_sweep(ctx, m):
                jobs.append(lambda m=m, n=steps, k=stride, j=j: _run_step(ctx, m, n, k, h=spacing * j / k))
    for m in planner.propagators:
        if m in selected:
            jobs.append(lambda m=m: _run_step(ctx, m, Grid.covering(t_end, dt_out).steps))
    adaptive_jobs = [(m, adaptive_rtols(m, config)) for m in selected_in_order(selected, Kind.ADAPTIVE)
                     if m.refusal(system) is None]
    prog.total = len(jobs) + sum(len(r) for _, r in adaptive_jobs)
    records = [job() for job in jobs]
    for m, rtols in adaptive_jobs:
        records += adaptive_sweep(m, rtols, config.adaptive_cap, lambda rtol, m=m: _run_adaptive(ctx, m, rtol),
                                  notes, prog, config.adaptive_seconds_cap)
    horizons: tuple[HorizonCurve, ...] = ()
    if exact and methods is None:
        horizons, hnotes = horizon_study(ctx)
        notes.extend(hnotes)
    desc = reference.description
    notes.append(compile_note())
    return BenchResult(scene, t_end, exact, desc, tuple(records), horizons, tuple(notes))



# -- error against horizon ---------------------------------------------------------------------------
def horizon_methods() -> tuple[str, ...]:
    """The step methods of the error-vs-horizon study, read from the registry: the explicit fixed-step
    integrators (run by the plain step method: the implicit Newmark family has its own), with a finite
    stability limit (the exact propagators, expm and chebyshev, have none), one per scheme (an integrator
    that subclasses a listed one follows it: verlet-kahan is verlet with compensated sums)."""
    out: list[tuple[str, type]] = []
    for name in registry.names(Kind.STEP):
        e = registry.entry(name)
        cls = e.load()
        if e.runner is None and math.isfinite(cls.stability_limit) \
                and not any(issubclass(cls, listed) for _, listed in out):
            out.append((name, cls))
    return tuple(name for name, _ in out)


def __getattr__(name: str):
    if name == "HORIZON_METHODS":  # the study's methods (imports the step integrators on first access)
        return horizon_methods()
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")



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
    quiet = Options(progress=False)

    def running_errors(run):
        xr, _ = ctx.reference.at(run.t)
        err = np.maximum.accumulate(np.max(np.abs(run.x - xr), axis=1))
        e = ctx.system.energy(run.x.T, run.v.T)
        return err, np.maximum.accumulate(np.abs(e - ctx.e0) / abs(ctx.e0))

    for m in registry.methods(Kind.STEP, quiet, only=horizon_methods()):
        traits = m.traits
        h = traits.evals_per_step / cfg.horizon_work
        if ctx.planner.model.omega_max * h >= traits.stability_limit:
            continue
        t_cap = max([T for T in cfg.horizons_measured if T / h * traits.evals_per_step <= cfg.horizon_eval_cap]
                    or [cfg.horizons_measured[0]])
        g = Grid.covering(t_cap, h)
        g = Grid(g.h, g.steps, max(1, g.steps // 100_000))
        ctx.progress.say(f"horizon: {m.name} at h = {g.h:.4g} up to t = {t_cap:g} ({g.steps} steps)")
        tr = record(m, ctx.system, ctx.x0, ctx.v0, g)
        err, een = running_errors(tr)
        Ts = np.array([T for T in cfg.horizons_measured if T <= t_cap])
        at = np.searchsorted(tr.t, Ts * (1 - 1e-12))
        resp = ctx.planner.responses[m]
        model = np.array([ctx.planner.model.envelope(resp, g.h, int(round(T / g.h))) for T in model_t])
        curves.append(HorizonCurve(m.name, f"h={g.h:.4g}", Ts, err[at], een[at], model_t, model,
                                   "closed-form envelope"))
        if t_cap < cfg.horizons_measured[-1]:
            notes.append(f"horizon study: {m.name} measured up to t = {t_cap:g} (cap {cfg.horizon_eval_cap} "
                         f"force evaluations); longer horizons from the model")
    # the reference adaptive method (DOP853) at one tolerance
    rtol = cfg.horizon_dop853_rtol
    dop = with_tolerance(registry.method(registry.REFERENCE_ADAPTIVE), ctx.x0, ctx.v0, rtol)
    Ts = np.array([T for T in cfg.horizons_measured if T <= cfg.horizon_dop853_cap])
    t_cap = float(Ts[-1])
    ctx.progress.say(f"horizon: {dop.name} at rtol {rtol:.0e} up to t = {t_cap:g}")
    res = record(dop, ctx.system, ctx.x0, ctx.v0, Grid.covering(t_cap, ctx.dt_out))
    err, een = running_errors(res)
    at = np.searchsorted(res.t, Ts * (1 - 1e-12))
    rate = float(err[-1] / t_cap)
    curves.append(HorizonCurve(dop.name, f"rtol={rtol:.0e}", Ts, err[at], een[at], model_t, rate * model_t,
                               "measured, extrapolated ∝ T"))
    if t_cap < cfg.horizons_model[-1]:
        notes.append(f"horizon study: {dop.name} (rtol {rtol:.0e}, {res.force_evals} evaluations for t = {t_cap:g}) "
                     f"measured up to t = {t_cap:g} only (cost ∝ T); beyond, its error is extrapolated ∝ T")
    return tuple(curves), notes


def with_derive_seconds(result: BenchResult, seconds: float | None) -> BenchResult:
    return replace(result, derive_seconds=seconds)
