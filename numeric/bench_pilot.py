"""``springchain bench`` for scenes measured against an exact reference without a closed-form
error model: damped, forced, gravity and ground scenes (augmented matrix exponential) and
``[chain]`` scenes above :data:`numeric.plan.MAX_MASSES` masses (chain transform); see
:mod:`numeric.plan_pilot`.

Records have the fields of :class:`~numeric.bench_records.BenchRecord`. ``error`` is the
largest position error over the recorded steps against the exact solution (every step, or
every r-th step when ``steps × N`` would not fit: see ``REFERENCE_FLOATS``); ``energy_error``
is ``max |E − E_exact| / max |E_exact|`` (the energy is not conserved in these scenes, so it
is compared with the exact solution's, not with E(0)); ``predicted_error`` is the
pilot-calibrated law's.
"""

from __future__ import annotations

import math

import numpy as np

from .bench_records import BenchConfig, BenchRecord, BenchResult
from .integrators import ADAPTIVE, INTEGRATORS
from .integrators.base import Problem
from .plan import adaptive_atol
from .plan_pilot import REFERENCE_FLOATS, adaptive_applies, ExactReference, PilotPlanner, _grid, full_problem, wrapped
from .system import System
from .timing import measure
from .driver import integrate, step_grid


def _energy_error(system: System, x, v, xr, vr) -> float:
    e = system.energy(x.T, v.T)
    er = system.energy(xr.T, vr.T)
    return float(np.max(np.abs(e - er)) / max(float(np.max(np.abs(er))), 1e-300))


def _record(system, method, setting, dt, rtol, steps, x, v, xr, vr, timing, evals, predicted) -> BenchRecord:
    from .bench import energy_norm

    err = float(np.max(np.abs(x - xr)))
    fin = energy_norm(system, x[-1] - xr[-1], v[-1] - vr[-1])
    return BenchRecord(method, setting, dt, rtol, steps, err, _energy_error(system, x, v, xr, vr), fin,
                       timing.seconds, int(evals), predicted, timing.repeats)


def run_pilot_bench(system: System, x0: np.ndarray, v0: np.ndarray, t_end: float, dt_out: float,
                    scene: str = "", config: BenchConfig | None = None, progress: bool = True,
                    methods: tuple[str, ...] | None = None) -> BenchResult:
    """The work–precision sweep against the exact solution (call inside ``single_threaded_blas``)."""
    from . import progress as prog

    config = config or BenchConfig()
    say = (lambda text: prog.line(text, prefix="bench")) if progress else (lambda text: None)
    x0 = np.asarray(x0, dtype=float)
    v0 = np.asarray(v0, dtype=float)
    n = system.n
    say(f"calibrating the planner against the exact solution for {scene or 'the scene'} (t = 0 … {t_end:g})")
    planner = PilotPlanner.for_system(system, x0, v0, t_end, dt_out, adaptive=False, methods=methods)
    ref = ExactReference(system, x0, v0)
    problem = Problem.from_system(system)
    records: list[BenchRecord] = []
    notes = [f"no closed-form error model for this scene: step methods are planned by pilot runs against "
             f"the exact solution; the exact solution over the output grid took about "
             f"{planner.exact_seconds:.3g} s"]
    if system.damped:
        notes.append("damping: every step method runs inside the damping splitting (order at most 2), but the "
                     "implicit newmark, newmark-linear and hht, which integrate it in their step")
    for name in planner.laws:
        integ_cls = INTEGRATORS[name]
        stages = max(integ_cls.evals_per_step, 1.0)
        counts = {step_grid(t_end, dt_out)[1]}
        for tol in config.target_errors:
            c = planner.plan_step(name, tol)
            if c.reachable:
                counts.add(int(c.steps))
        lo = math.ceil(t_end / planner.laws[name].h_max * (1 - 1e-12))
        for steps in sorted(s for s in counts if s >= lo and s * stages <= config.eval_cap):
            h = t_end / steps
            every = max(1, math.ceil(steps * n / REFERENCE_FLOATS))
            integ = wrapped(system, integ_cls())
            timing = measure(lambda: integrate(integ, problem, x0, v0, h, steps, every), budget=config.timing_budget)
            tr = timing.result
            if tr.t.shape[0] < 2 or abs(tr.t[-1] - tr.t[-2] - every * h) > 1e-9 * h * every:
                keep = slice(0, -1) if tr.t.shape[0] > 2 else slice(None)  # the final (off-grid) frame
            else:
                keep = slice(None)
            t = tr.t[keep]
            xr, vr = ref.at(t)
            rec = _record(system, name, f"h={h:.4g}", h, None, steps, tr.x[keep, :n, 0], tr.v[keep, :n, 0],
                          xr, vr, timing, tr.force_evals, planner.laws[name].error(h, t_end))
            say(f"{name:<14} h={h:.4g}  error {rec.error:9.2e}  {rec.seconds * 1e3:9.2f} ms")
            records.append(rec)
    grid = _grid(t_end, dt_out, n)
    t = grid.t
    xr, vr = ref.at(t)
    size = max(float(np.max(np.abs(xr))), 1e-300)
    fp = full_problem(system)
    for name, cls_ in ADAPTIVE.items():
        if (methods and name not in methods) or not adaptive_applies(name, system):
            continue
        rtols = config.dop853_rtols if name == "dop853" else config.rtols
        for rtol in rtols:
            method = cls_()
            atol = adaptive_atol(x0, v0, rtol, size)
            timing = measure(lambda: method.solve(fp, x0, v0, t, rtol, atol), budget=config.timing_budget)
            res = timing.result
            rec = _record(system, name, f"rtol={rtol:.2g}", None, rtol, None, res.x[..., 0], res.v[..., 0],
                          xr, vr, timing, res.force_evals, None)
            say(f"{name:<14} rtol={rtol:.2g}  error {rec.error:9.2e}  {rec.seconds * 1e3:9.2f} ms")
            records.append(rec)
            if rec.force_evals > config.adaptive_cap:
                skipped = [r for r in rtols if r < rtol]
                if skipped:
                    notes.append(f"{name}: stopped at rtol={rtol:.0e} ({rec.force_evals} evaluations > cap "
                                 f"{config.adaptive_cap})")
                break
    return BenchResult(scene, t_end, False, ref.description, tuple(records), (), tuple(notes))


__all__ = ["run_pilot_bench"]
