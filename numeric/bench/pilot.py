"""``springchain bench`` for scenes measured against an exact reference without a closed-form
error model: damped, forced, gravity and ground scenes (augmented matrix exponential) and
``[chain]`` scenes above :data:`numeric.plan.planner.MAX_MASSES` masses (chain transform); see
:mod:`numeric.plan.pilot`.

Records have the fields of :class:`~numeric.bench.records.BenchRecord`. ``error`` is the
largest position error over the recorded steps against the exact solution (every step, or
every r-th step when ``steps × N`` would not fit: see ``REFERENCE_FLOATS``); ``energy_error``
is ``max |E − E_exact| / max |E_exact|`` (the energy is not conserved in these scenes, so it
is compared with the exact solution's, not with E(0)); ``predicted_error`` is the
pilot-calibrated law's.
"""

from __future__ import annotations

import math

import numpy as np

from .runs import adaptive_rtols, adaptive_sweep, energy_norm, progress_reporter, report_run, \
    peer_filter, selected_in_order, timed_run
from .records import BenchConfig, BenchRecord, BenchResult
from ..plan.planner import with_tolerance
from ..plan.pilot import REFERENCE_FLOATS, ExactReference, PilotPlanner, reference_grid
from ..run.grid import Grid
from ..run.protocol import Kind, Method, Options
from ..run import registry
from ..system import System


def _energy_error(system: System, x, v, xr, vr) -> float:
    e = system.energy(x.T, v.T)
    er = system.energy(xr.T, vr.T)
    return float(np.max(np.abs(e - er)) / max(float(np.max(np.abs(er))), 1e-300))


def _record(system, method: Method, setting, dt, rtol, steps, x, v, xr, vr, timing, predicted) -> BenchRecord:
    err = float(np.max(np.abs(x - xr)))
    fin = energy_norm(system, x[-1] - xr[-1], v[-1] - vr[-1])
    return BenchRecord(method.name, setting, dt, rtol, steps, err, _energy_error(system, x, v, xr, vr), fin,
                       timing.seconds, timing.result.force_evals, predicted, timing.repeats)


def run_pilot_bench(system: System, x0: np.ndarray, v0: np.ndarray, t_end: float, dt_out: float,
                    scene: str = "", config: BenchConfig | None = None, progress: bool = True,
                    methods: tuple[str, ...] | None = None, settings: tuple = ()) -> BenchResult:
    """The work–precision sweep against the exact solution (call inside ``single_threaded_blas``)."""
    config = config or BenchConfig()
    prog = progress_reporter(progress)
    x0 = np.asarray(x0, dtype=float)
    v0 = np.asarray(v0, dtype=float)
    n = system.n
    prog.say(f"calibrating the planner against the exact solution for {scene or 'the scene'} (t = 0 … {t_end:g})")
    planner = PilotPlanner.for_system(system, x0, v0, t_end, dt_out, adaptive=False, methods=methods,
                                       settings=settings)
    ref = ExactReference(system, x0, v0)
    records: list[BenchRecord] = []
    notes = [f"no closed-form error model for this scene: step methods are planned by pilot runs against "
             f"the exact solution; the exact solution over the output grid took about "
             f"{planner.exact_seconds:.3g} s"]
    if system.damped:
        own = [m.name for m in planner.laws if not m.splits(system)]
        notes.append("damping: every step method runs inside the damping splitting (order at most 2)"
                     + (f", but {', '.join(own)}, which integrate it in their step" if own else ""))
    for m, law in planner.laws.items():
        stages = max(m.traits.evals_per_step, 1.0)
        counts = {Grid.covering(t_end, dt_out).steps}
        for tol in config.target_errors:
            c = planner.plan_step(m, tol)
            if c.reachable:
                counts.add(int(c.steps))
        lo = math.ceil(t_end / law.h_max * (1 - 1e-12))
        for steps in sorted(s for s in counts if s >= lo and s * stages <= config.eval_cap):
            grid = Grid(t_end / steps, steps, max(1, math.ceil(steps * n / REFERENCE_FLOATS)))
            timing = timed_run(m, system, x0, v0, grid, config.timing_budget)
            run = timing.result
            # the final frame is off the reference grid when the stride does not divide the steps
            keep = slice(0, -1) if grid.steps % grid.record_every and run.t.shape[0] > 2 else slice(None)
            xr, vr = ref.at(run.t[keep])
            rec = _record(system, m, f"h={grid.h:.4g}", grid.h, None, steps, run.x[keep], run.v[keep], xr, vr, timing,
                          law.error(grid.h, t_end))
            report_run(prog, rec)
            records.append(rec)
    grid = reference_grid(t_end, dt_out, n)
    xr, vr = ref.at(grid.t)
    size = max(float(np.max(np.abs(xr))), 1e-300)
    selected = set(filter(peer_filter(config, methods), registry.methods(Kind.ADAPTIVE, Options(progress=False),
                                                                         only=methods)))
    for m in selected_in_order(selected, Kind.ADAPTIVE):
        if m.refusal(system):
            continue

        def run(rtol, m=m):
            timing = timed_run(with_tolerance(m, x0, v0, rtol, size), system, x0, v0, grid, config.timing_budget)
            rec = _record(system, m, f"rtol={rtol:.2g}", None, rtol, None, timing.result.x, timing.result.v, xr, vr,
                          timing, None)
            report_run(prog, rec)
            return rec

        records += adaptive_sweep(m, adaptive_rtols(m, config), config.adaptive_cap, run, notes, prog,
                                  config.adaptive_seconds_cap)
    from .runs import compile_note

    notes.append(compile_note())
    return BenchResult(scene, t_end, False, ref.description, tuple(records), (), tuple(notes))


__all__ = ["run_pilot_bench"]
