"""The benchmark's runs: one timed run through the method protocol, the tolerance sweep of an
adaptive method, the progress lines, and the energy norm of an error (shared by
:mod:`numeric.bench.workprecision` and :mod:`numeric.bench.pilot`)."""

from __future__ import annotations

import math
from typing import Callable

import numpy as np

from .records import BenchConfig, BenchRecord
from ..progress import Reporter
from ..run import registry
from ..run.grid import Grid
from ..run.protocol import Kind, Method, Options
from ..run.protocol import record
from ..system import System
from .timing import measure


def energy_norm(system: System, dx: np.ndarray, dv: np.ndarray) -> float:
    """``√(δvᵀMδv + δxᵀKδx)`` for one state difference (N,), K of the linear springs."""
    a, b = system.spring_ends[:, 0], system.spring_ends[:, 1]
    da = np.where(a >= 0, dx[np.maximum(a, 0)], 0.0)
    db = np.where(b >= 0, dx[np.maximum(b, 0)], 0.0)
    pot = float(np.sum(system.stiffness * (da - db) ** 2))
    return math.sqrt(max(float(np.sum(system.masses * dv**2)) + pot, 0.0))


def progress_reporter(enabled: bool) -> Reporter:
    """The benchmark's progress: one line per run and per phase on stderr (``bench: ...``)."""
    return Reporter("bench", 0, enabled=enabled, prefix="bench")


def report_run(bar: Reporter, rec: BenchRecord) -> None:
    """One progress line for a finished run: its number, error, seconds and evaluations."""
    bar.count(f"{rec.method} {rec.setting:<18} error {rec.error:9.2e}  {rec.seconds * 1e3:9.2f} ms  "
              f"{rec.force_evals:>9} evals")


def peer_filter(config: BenchConfig, methods) -> Callable[[Method], bool]:
    """Which methods a bench runs beside the named ones: a quick bench (tests) leaves out the compiled
    DOP853 peer unless it is named (its first compile costs more than the whole quick sweep)."""
    return lambda m: not (config.quick and methods is None and m.name == registry.COMPILED_PEER)


def timed_run(method: Method, system: System, x0: np.ndarray, v0: np.ndarray, grid: Grid, budget: float):
    """:func:`~numeric.bench.timing.measure` of one run through the protocol (its result: the recorded run).

    The warm-up is the same method on the first few steps of the grid: it compiles (or loads) a
    compiled loop, so no compile time enters a timing, however long the run."""
    short = Grid(grid.h, min(grid.steps, 2 * grid.record_every), grid.record_every)
    return measure(lambda: record(method, system, x0, v0, grid), budget=budget,
                   warmup=lambda: record(method, system, x0, v0, short))


def selected_in_order(selected: set, kind: Kind) -> list[Method]:
    """The selected methods of one kind, in the registry's order."""
    order = registry.names(kind)
    return sorted((m for m in selected if m.kind is kind), key=lambda m: order.index(m.name))


def adaptive_rtols(method: Method, config: BenchConfig) -> tuple[float, ...]:
    """The tolerances an adaptive method sweeps: DOP853 and its compiled peer get the finer list."""
    peers = (registry.REFERENCE_ADAPTIVE, registry.COMPILED_PEER)
    return config.dop853_rtols if method.name in peers else config.rtols


def adaptive_sweep(method: Method, rtols, cap: int, run: Callable[[float], BenchRecord], notes: list[str],
                   prog: Reporter, seconds_cap: float = float("inf")) -> list[BenchRecord]:
    """Records of ``run(rtol)`` for tightening tolerances, stopping after the first run over ``cap``
    force evaluations or ``seconds_cap`` seconds (a note says which tolerances were not run)."""
    out = []
    for rtol in rtols:
        rec = run(rtol)
        out.append(rec)
        if rec.force_evals > cap or rec.seconds > seconds_cap:
            skipped = [r for r in rtols if r < rtol]
            if skipped:
                why = (f"{rec.force_evals} evaluations > cap {cap}" if rec.force_evals > cap
                       else f"{rec.seconds:.1f} s > {seconds_cap:g} s")
                notes.append(f"{method.name}: stopped at rtol={rtol:.0e} ({why}); not run: rtol "
                             + ", ".join(f"{r:.0e}" for r in skipped))
                prog.total -= len(skipped)
            break
    return out


def compile_note() -> str:
    """The one line that reports the compiled loops' compile (or disk-cache load) time, kept out of every
    timing (each run is timed after a warm-up call)."""
    from ..compiled.run import compile_seconds

    return (f"compiled loops (small [masses] scenes): {compile_seconds():.1f} s to compile or load from the "
            f"disk cache, once, in no timing")


__all__ = ["compile_note", "energy_norm", "progress_reporter", "report_run", "timed_run", "selected_in_order", "adaptive_rtols",
           "adaptive_sweep"]
