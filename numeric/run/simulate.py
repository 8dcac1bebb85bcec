"""Run methods on a system and keep or stream their frames: the work behind ``springchain simulate``.

Everything goes through the run layer (:mod:`numeric.run`): names become
:class:`~numeric.run.protocol.Method` objects once, at the top of :func:`run_methods` and
:func:`stream_methods`; what is reported is :mod:`numeric.run.compare`'s, the NPZ :mod:`numeric.io.npz`'s,
the figures :mod:`numeric.plots.simulation`'.
"""

from __future__ import annotations

import contextlib
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from . import registry
from .grid import Grid
from .protocol import DEFAULT_ATOL, DEFAULT_RTOL, Kind, Method, Options, Recorded
from .recorder import MemoryRecorder
from ..system import System


def default_methods(system: System) -> list[str]:
    """The exact solution and Verlet where an exact solution applies, else Verlet alone."""
    if system.exact_available:
        return [registry.EXACT, registry.DEFAULT_STEP]
    return [registry.DEFAULT_STEP]


def unstable_defaults(system: System, methods: list[str], h: float) -> tuple[list[str], list[str]]:
    """Drop default step methods that would be unstable at ``h`` when an exact method stays.

    Returns the kept methods and one note per dropped method.
    """
    chosen = [registry.method(name) for name in methods]
    if not any(m.kind is Kind.EXACT for m in chosen) or len(chosen) < 2:
        return methods, []
    dropped = [m for m in chosen if m.kind is Kind.STEP and system.linear
               and not system.stable(h, m.traits.stability_limit)]
    if not dropped:
        return methods, []
    w = system.omega_max
    notes = [f"{m.name} not run by default: dt = {h:g} is beyond its stability limit "
             f"{m.traits.stability_limit:g}/ω_max = {m.traits.stability_limit / w:.6g} (ω_max = {w:.6g}); "
             "ask for it with a smaller dt" for m in dropped]
    return [m.name for m in chosen if m not in dropped], notes


#: Float64 error of an exact trajectory (relative to its amplitude) above which the run says so.
EXACT_LIMIT = 1e-9


def float64_limits(system: System, methods: list[str], t_end: float) -> list[str]:
    """One note when an exact method's float64 limits exceed :data:`EXACT_LIMIT` of the amplitude.

    Any exact solution carries ε·ω_max·t (ω itself is a float: its phase error grows with t) and
    ε·√(m_max/m_min) (the mass-weighted modal basis puts a light mass next to a heavy one at the
    heavy one's scale); past 1e-9 the positions are not the accurate numbers the rule promises, so
    the run names the quantity instead of printing them silently (returns [] otherwise).
    """
    exact = [name for name in methods if registry.method(name).kind is Kind.EXACT]
    if not exact or not system.linear or system.n == 0:
        return []
    eps = float(np.finfo(float).eps)
    phase = eps * float(system.omega_max) * float(t_end)
    m = np.asarray(system.masses, dtype=float)
    mass = eps * float(np.sqrt(np.max(m) / np.min(m)))
    if max(phase, mass) <= EXACT_LIMIT:
        return []
    return [f"{', '.join(exact)}: float64 limits exceed {EXACT_LIMIT:g} of the amplitude: "
            f"eps*omega_max*t = {phase:.1e} (omega_max = {float(system.omega_max):.6g} rad/s, t = {t_end:g} s), "
            f"eps*sqrt(m_max/m_min) = {mass:.1e}; positions are not certified to {EXACT_LIMIT:g} "
            "(shorten the horizon or reduce the mass contrast)"]


def applicable(system: System) -> str:
    """Which methods apply to the system, in words."""
    why = system.no_exact_solution
    if why:
        return f"integrators only (no exact solution: {why})"
    return f"{registry.EXACT} (exact) and every integrator"


@dataclass(frozen=True)
class Run(Recorded):
    """One method's recorded trajectory (a :class:`~numeric.run.protocol.Recorded`: ``t`` (S,),
    ``x``, ``v`` (S, N), ``force_evals``), its name, seconds, and whether it is the exact solution
    (what the others are compared with)."""

    method: str = ""
    seconds: float = 0.0
    exact: bool = False


def _methods(system: System, names: list[str], options: Options) -> list[Method]:
    """The named methods, every one checked against the system before anything runs.

    numba is imported here (when installed), outside every method's clock: its import (about a second)
    is the process's cost, not the first compiled method's, whose printed time it used to be.
    """
    chosen = [registry.method(name, options) for name in names]
    for m in chosen:
        m.check(system)
    if options.compiled:
        from ..compiled.fast_kernels import available

        available()
    return chosen


def run_methods(system: System, x0: np.ndarray, v0: np.ndarray, h: float, steps: int,
                methods: list[str], record_every: int = 1, spectrum_source: str = "svd",
                progress: bool | None = None, rtol: float = DEFAULT_RTOL, atol: float = DEFAULT_ATOL,
                settings: tuple = ()) -> dict[str, Run]:
    """Run each named method from (x0, v0) on the grid t = i·h, i = 0..steps, keeping the frames.

    Parameters
    ----------
    x0, v0 : ndarray, shape (N,)
    methods : list of str
        Registered names (:func:`numeric.run.registry.names`).
    settings : tuple of (str, float)
        Settings of the methods that take them (:attr:`Options.settings`, e.g. HHT's alpha).

    Returns
    -------
    dict of str to Run
    """
    chosen = _methods(system, methods, Options(rtol, atol, spectrum_source, progress, settings))
    grid = Grid(h, steps, record_every)
    out: dict[str, Run] = {}
    for m in chosen:
        rec = MemoryRecorder(grid.frames, system.n)
        t0 = time.perf_counter()
        with quiet_floats():  # a run that diverges is said in a note (non_finite_notes)
            evals = m.run(system, x0, v0, grid, rec)
        out[m.name] = Run(grid.t, rec.x, rec.v, evals, m.name, time.perf_counter() - t0, m.kind is Kind.EXACT)
    return out


def quiet_floats(enabled: bool = True):
    """NumPy's floating-point warnings off within the block (``enabled``): a run that diverges is said once,
    in its :func:`divergence_note`, not by a warning on every array computed from it."""
    return np.errstate(divide="ignore", invalid="ignore", over="ignore") if enabled else contextlib.nullcontext()


def divergence_note(name: str, t: np.ndarray, finite: np.ndarray, what: str = "state") -> str | None:
    """The one line for a run whose recorded ``what`` (per frame: ``finite``, shape (S,)) leaves the finite
    numbers, naming the first such frame's time; None when every frame is finite."""
    if finite.all():
        return None
    j = int(np.argmin(finite))
    return (f"{name}: the {what} is not finite at t = {t[j]:.6g} s (frame {j}, the first recorded frame that is "
            "not: the force divided by zero or overflowed on the way); its frames and energies from there on "
            "are inf/nan")


def non_finite_notes(runs: dict[str, Run]) -> list[str]:
    """One line per run whose frames leave the finite numbers (:func:`divergence_note`)."""
    notes = [divergence_note(name, run.t, np.isfinite(run.x).all(axis=1) & np.isfinite(run.v).all(axis=1))
             for name, run in runs.items()]
    return [n for n in notes if n]


def stream_methods(system: System, x0: np.ndarray, v0: np.ndarray, h: float, steps: int,
                   methods: list[str], record_every: int, out: Path, scene_name: str,
                   snapshots: int = 5, figures: bool = True, progress: bool | None = None,
                   settings: tuple = ()) -> dict:
    """Run long simulations writing frames straight to ``out/<name>.npz`` (bounded memory).

    Keeps only the energy per frame and a few profile snapshots in memory.
    Returns a summary like :func:`numeric.run.compare.compare`'s, plus the paths written.
    """
    from ..exact.absolute import absolute_keys
    from ..io.chunked import ChunkedNPZ
    from .compare import energy_drift, streamed_differences
    from ..progress import phase
    from .recorder import StreamRecorder

    chosen = _methods(system, methods, Options(progress=progress, settings=settings))
    grid = Grid(h, steps, record_every)
    t = grid.t
    keep = set(np.linspace(0, len(t) - 1, min(snapshots, len(t))).round().astype(int).tolist())
    summary: dict = {"methods": {}, "diverged": []}
    recorders: dict[str, StreamRecorder] = {}
    npz = out / f"{scene_name}.npz"
    extra = [f"{q}_{m}" for m in methods for q in absolute_keys(system)]
    with ChunkedNPZ(npz, t, system.n, methods, progress=progress, extra=extra) as writer:
        for m in chosen:
            rec = recorders[m.name] = StreamRecorder(writer, system, m.name, t, keep)
            t0 = time.perf_counter()
            with quiet_floats():
                evals = m.run(system, x0, v0, grid, rec)
            seconds = time.perf_counter() - t0
            note = divergence_note(m.name, t, np.isfinite(rec.energy), "energy")
            with quiet_floats(bool(note)):
                summary["methods"][m.name] = {"seconds": seconds, "force_evals": evals,
                                              **energy_drift(rec.energy, float(np.max(rec.kinetic)))}
            if note:
                summary["diverged"].append(note)
        exact = next((m for m in chosen if m.kind is Kind.EXACT), None)
        if exact is not None:
            others = [m.name for m in chosen if m is not exact]
            diffs = streamed_differences(writer.arrays, others, exact.name, len(t), progress)
            for name, rec in diffs.items():
                summary["methods"][name].update(rec)
    paths = []
    if figures:
        from ..plots.simulation import write_stream_figures

        with phase("figures", enabled=progress):
            paths = write_stream_figures(out, scene_name, t, recorders, system.energy_conserved)
    summary["npz"] = str(npz)
    summary["figures"] = [str(p) for p in paths]
    return summary


__all__ = ["Run", "default_methods", "unstable_defaults", "applicable", "run_methods", "stream_methods",
           "non_finite_notes", "divergence_note", "quiet_floats"]
