"""Run methods on a system and compare them: the work behind ``springchain simulate``."""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from . import plots
from .driver import Progress
from .progress import phase
from .errors import RunRefused
from .files import atomic_path
from .integrators.base import Problem
from .integrators.verlet import VelocityVerlet
from .spectrum import Spectrum, spectrum, spectrum_from_closed_form
from .system import System

from .methods import EXACT, METHOD_NAMES

#: Index-dependent chains above this many masses get no default exact solution (dense modes).
DENSE_EXACT_MAX = 4000


def method_names() -> list[str]:
    """Every method selectable by name (``--method``), the exact one first."""
    return list(METHOD_NAMES)


def _long_dense_chain(system: System) -> bool:
    return bool(system.chain and not system.module.UNIFORM and system.n > DENSE_EXACT_MAX)


def default_methods(system: System) -> list[str]:
    """The exact solution and Verlet where an exact solution applies, else Verlet alone."""
    return [EXACT, "verlet"] if system.exact_available and not _long_dense_chain(system) else ["verlet"]


def unstable_defaults(system: System, methods: list[str], h: float) -> tuple[list[str], list[str]]:
    """Drop default step methods that would be unstable at ``h`` when the exact method stays.

    A cheap Gershgorin bound clears the usual case; only when it cannot, the exact ω_max is
    computed (dense systems). Returns the kept methods and one note per dropped method.
    """
    if EXACT not in methods or len(methods) < 2:
        return methods, []
    from .bounds import omega2_bound
    from .runners import RunContext

    bound = math.sqrt(omega2_bound(system.masses, system.spring_ends, system.stiffness))
    if bound * h < 2.0:
        return methods, []
    omega_max = RunContext(system).omega_max()
    if omega_max * h < 2.0:
        return methods, []
    kept = [m for m in methods if m == EXACT]
    notes = [f"{m} not run by default: dt = {h:g} is beyond its stability limit 2/ω_max = {2.0 / omega_max:.6g} "
             f"(ω_max = {omega_max:.6g}); ask for it with a smaller dt" for m in methods if m != EXACT]
    return kept, notes


def applicable(system: System) -> str:
    """Which methods apply to the system, in words."""
    if not system.exact_available:
        from .system import LOADED_CHAIN_EXACT_MAX

        why = ("cubic springs" if not system.linear else
               f"a loaded [chain] of more than {LOADED_CHAIN_EXACT_MAX} masses"
               if system.chain and not system.conservative and system.n > LOADED_CHAIN_EXACT_MAX else
               "non-harmonic forces or ground acceleration")
        return f"integrators only ({why}: no exact solution)"
    if _long_dense_chain(system):
        return f"integrators (an index-dependent chain has an exact solution up to {DENSE_EXACT_MAX} masses)"
    return "modal (exact) and every integrator"


@dataclass(frozen=True)
class Run:
    """One method's recorded trajectory. x, v : ndarray, shape (S, N)."""

    method: str
    t: np.ndarray = field(repr=False)
    x: np.ndarray = field(repr=False)
    v: np.ndarray = field(repr=False)
    seconds: float
    force_evals: int


def system_spectrum(system: System, source: str = "svd") -> Spectrum:
    """The system's modes: ``svd`` of the spring factor (accurate) or the generated ``closed-form``."""
    if source == "closed-form":
        return _closed_form_spectrum(system)
    return spectrum(system.masses, system.spring_ends, system.stiffness)


def _closed_form_spectrum(system: System) -> Spectrum:
    """The generated module's ω² and shapes (closed forms where they are cancellation-free, else
    its own spring-factor route), or a one-line refusal naming the first mode that is not finite,
    not ≥ 0, or a rigid mode that is not exactly 0 (e.g. parameter values beyond float range)."""
    mod = system.module
    n, rigid = system.masses.shape[0], int(mod.RIGID_MODES)
    try:
        with np.errstate(all="ignore"):
            w2 = np.asarray(mod.omega2(**system.params), dtype=float)
            shapes = np.asarray(mod.mode_shapes(**system.params), dtype=float)
    except (FloatingPointError, ArithmeticError, np.linalg.LinAlgError) as exc:
        raise RunRefused(f"spectrum 'closed-form': the modes cannot be evaluated to float64 accuracy at these "
                         f"parameter values ({exc}); accepted: spectrum 'svd'", quantity="spectrum") from None
    if w2.shape != (n,) or shapes.shape != (n, n):
        raise RunRefused(f"spectrum 'closed-form': the generated module returned {w2.shape[0]} modes for {n} "
                         f"masses; accepted: spectrum 'svd'", quantity="spectrum")
    order = np.argsort(w2, kind="stable")
    ws = w2[order].tolist()  # a few scalar tests (this is on the exact method's timed path)
    fine = (bool(np.isfinite(w2).all() and np.isfinite(shapes).all()) and all((shapes != 0.0).any(axis=0).tolist())
            and all(w >= 0 and (pos < rigid) == (w == 0.0) for pos, w in enumerate(ws)))  # NaN fails w >= 0
    if not fine:  # name the first mode (in ascending order) that is not right
        ss = shapes[:, order]
        bad = (~np.isfinite(w2[order]) | ~np.isfinite(ss).all(axis=0) | (w2[order] < 0)
               | ((np.arange(n) < rigid) != (w2[order] == 0.0)) | ~ss.any(axis=0))
        j = int(order[int(np.argmax(bad))])
        raise RunRefused(f"spectrum 'closed-form': mode {j} (omega2 = {w2[j]:.17g}) cannot be evaluated to "
                         f"float64 accuracy at these parameter values; accepted: spectrum 'svd'",
                         quantity="spectrum")
    return spectrum_from_closed_form(w2, shapes, system.masses, rigid)


def check_stable(omega_max: float, h: float, method: str, limit: float = 2.0) -> None:
    """Refuse a step at or beyond the stability edge ``ω_max·h < limit``."""
    if omega_max * h >= limit:
        raise RunRefused(f"dt = {h:g} is at or beyond {method}'s stability limit: ω_max = {omega_max:.6g}, "
                         f"so dt must be < {limit:g}/ω_max = {limit / omega_max:.6g}; use a smaller dt "
                         f"(the scene's simulation.dt or the run's) or the exact method 'modal' (any dt)",
                         quantity="dt")


class FusedChainVerlet(VelocityVerlet):
    """Velocity Verlet on a ``[chain]`` scene through the fused single-pass kernel
    (:mod:`numeric.fast`: numba when installed, else the NumPy stencil). Same scheme,
    same name; frames are copied by the recorder, so the in-place kernel is safe."""

    def __init__(self, system: System):
        self.system = system

    def kernel(self, problem: Problem, h: float):
        from .fast import chain_verlet_kernel

        return chain_verlet_kernel(self.system.module, self.system.params, self.system.n, h, inplace=True)


def run_methods(system: System, x0: np.ndarray, v0: np.ndarray, h: float, steps: int,
                methods: list[str], record_every: int = 1, spectrum_source: str = "svd",
                progress: bool | None = None, rtol: float = 1e-10, atol: float = 1e-12) -> dict[str, Run]:
    """Run each named method from (x0, v0) on the grid t = i·h, i = 0..steps, keeping the frames.

    Parameters
    ----------
    x0, v0 : ndarray, shape (N,)
    methods : list of str
        Names from :func:`method_names`.

    Returns
    -------
    dict of str to Run
    """
    from .runners import Grid, MemoryRecorder, RunContext, method

    ctx = RunContext(system, spectrum_source, rtol, atol, progress)
    grid = Grid(h, steps, record_every)
    chosen = [method(name) for name in methods]
    for m in chosen:  # refuse before running anything
        m.check(system)
    out: dict[str, Run] = {}
    for m in chosen:
        rec = MemoryRecorder(grid.indices.shape[0], system.n)
        t0 = time.perf_counter()
        evals = m.run(ctx, x0, v0, grid, rec)
        out[m.name] = Run(m.name, grid.t, rec.x, rec.v, time.perf_counter() - t0, evals)
    return out


def _energy_scale(system: System, e: np.ndarray, v: np.ndarray) -> float:
    """A scale for relative energy errors: max |E| or the largest kinetic energy (E may be ~0)."""
    kinetic = 0.5 * np.tensordot(system.masses, v**2, axes=(0, 0))
    return float(max(np.max(np.abs(e)), np.max(kinetic), 1e-300))


def compare(system: System, runs: dict[str, Run]) -> dict:
    """Largest differences from the exact run, energy drift and momentum change of every run."""
    summary: dict = {"methods": {}}
    exact = runs.get(EXACT)
    for name, run in runs.items():
        e = system.energy(run.x.T, run.v.T)
        p = system.momentum(run.v.T)
        rec = {
            "seconds": run.seconds,
            "force_evals": run.force_evals,
            "energy_drift": float(np.max(np.abs(e - e[0]))),
            "energy_drift_relative": float(np.max(np.abs(e - e[0])) / _energy_scale(system, e, run.v.T)),
            "momentum_change": float(np.max(np.abs(p - p[0]))),
        }
        if exact is not None and name != EXACT:
            rec["max_position_difference"] = float(np.max(np.abs(run.x - exact.x)))
            rec["max_velocity_difference"] = float(np.max(np.abs(run.v - exact.v)))
        summary["methods"][name] = rec
    return summary


def absolute_motion(system: System, t: np.ndarray, x: np.ndarray, v: np.ndarray) -> dict[str, np.ndarray]:
    """Absolute motion of a scene with ``[ground]`` (empty dict without it).

    Coordinates are relative to the ground, so the absolute acceleration is the relative one
    plus ``a_g``: ``aabs = a(x) − M⁻¹C v + M⁻¹F(t)`` (every force but the ground's ``−m a_g``).
    The absolute displacement ``xabs = x + x_g(t)`` is given only when ``x_g`` is known in
    closed form (an acceleration expression integrated with ``x_g(0) = v_g(0) = 0``).

    Parameters
    ----------
    t : ndarray, shape (S,)
    x, v : ndarray, shape (S, N)

    Returns
    -------
    dict with ``"aabs"`` and possibly ``"xabs"``, each shape (S, N)
    """
    if system.ground is None:
        return {}
    a = np.asarray(system.acceleration_fn(np.ascontiguousarray(x.T)), dtype=float)
    Ad = system.damping_rate_matrix()
    if Ad is not None:
        a = a + Ad @ v.T
    out = {"aabs": (a + system.applied_acceleration(t)).T}
    if getattr(system.module, "GROUND_DISPLACEMENT", False):
        out["xabs"] = x + system.module.ground_motion(t, **system.params)[1][:, None]
    return out


def absolute_npz_arrays(system: System, t: np.ndarray, x: dict, v: dict) -> dict[str, np.ndarray]:
    """``aabs_<method>`` (and ``xabs_<method>`` when the ground displacement is known) of every run."""
    out = {}
    for name in x:
        for key, arr in absolute_motion(system, t, x[name], v[name]).items():
            out[f"{key}_{name}"] = arr
    return out


def write_npz(path: Path, runs: dict[str, Run]) -> None:
    """NPZ with ``t`` (S,) and ``x_<method>``, ``v_<method>`` (S, N), written atomically."""
    first = next(iter(runs.values()))
    save_npz(path, first.t, {m: r.x for m, r in runs.items()}, {m: r.v for m, r in runs.items()})


def save_npz(path: Path, t: np.ndarray, x: dict[str, np.ndarray], v: dict[str, np.ndarray],
             extra: dict[str, np.ndarray] | None = None) -> None:
    """NPZ with ``t`` (S,) and ``x_<method>``, ``v_<method>`` (S, N) (and ``extra`` arrays such as
    ``aabs_<method>``), written atomically."""
    arrays = {"t": t}
    for name in x:
        arrays[f"x_{name}"] = x[name]
        arrays[f"v_{name}"] = v[name]
    arrays.update(extra or {})
    with atomic_path(path, suffix=".npz") as tmp:
        with open(tmp, "wb") as fh:
            np.savez(fh, **arrays)


def write_figures(out: Path, scene_name: str, names, system: System, runs: dict[str, Run]) -> list[Path]:
    """Positions, velocities, differences from exact, and energy; returns the paths written."""
    t = next(iter(runs.values())).t
    paths = []
    fig = plots.trajectories(t, {m: r.x for m, r in runs.items()}, names, "position x", "m",
                             f"{scene_name}: positions (" + " vs ".join(runs) + ")")
    paths.append(out / f"{scene_name}-positions.png")
    plots.save(fig, paths[-1])
    fig = plots.trajectories(t, {m: r.v for m, r in runs.items()}, names, "velocity v", "m/s",
                             f"{scene_name}: velocities (" + " vs ".join(runs) + ")")
    paths.append(out / f"{scene_name}-velocities.png")
    plots.save(fig, paths[-1])
    if EXACT in runs:
        for name, run in runs.items():
            if name == EXACT:
                continue
            fig = plots.differences(t, run.x - runs[EXACT].x, run.v - runs[EXACT].v, names, name)
            paths.append(out / f"{scene_name}-{name}-minus-exact.png")
            plots.save(fig, paths[-1])
    if system.forced and system.exact_available and hasattr(system.module, "forcing_harmonics"):
        from .linear_exact import frequency_response

        omegas, fc, fs, _ = (np.asarray(a, dtype=float) for a in system.module.forcing_harmonics(**system.params))
        if omegas.size:
            spec = system_spectrum(system)
            force = np.abs(fc[0] + 1j * fs[0])
            top = 1.5 * max(spec.omega_max, float(np.max(omegas)))
            drive = np.linspace(top / 2000, top, 2000)
            amp = np.abs(frequency_response(system, drive, force))
            fig = plots.frequency_response(drive, amp, names, spec.omega[spec.rigid:], omegas)
            paths.append(out / f"{scene_name}-frequency-response.png")
            plots.save(fig, paths[-1])
    energies = {m: system.energy(r.x.T, r.v.T) for m, r in runs.items()}
    e0 = float(next(iter(energies.values()))[0])
    conserved = not (system.damped or system.forced)
    from .energy_balance import work

    ref = runs.get(EXACT, next(iter(runs.values())))  # the work along the exact run, else the first
    fig = plots.energy(t, energies, e0, conserved=conserved, work=None if conserved else work(system, t, ref.v))
    paths.append(out / f"{scene_name}-energy.png")
    plots.save(fig, paths[-1])
    return paths


class _StreamRecorder:
    """Writes one method's frames into the chunked NPZ; keeps the energy per frame and a few profiles."""

    def __init__(self, writer, system: System, name: str, t: np.ndarray, keep: set[int]):
        self.writer, self.system, self.name, self.t, self.keep = writer, system, name, t, keep
        self.energy = np.empty(t.shape[0])
        self.snapshots: dict[float, np.ndarray] = {}

    def frame(self, row: int, x: np.ndarray, v: np.ndarray) -> None:
        n = self.system.n
        x1, v1 = np.reshape(x, (-1, 1))[:n], np.reshape(v, (-1, 1))[:n]
        self.writer.frame(self.name, row, x1, v1)
        for key, arr in absolute_motion(self.system, self.t[row:row + 1], x1.T, v1.T).items():
            self.writer.store(f"{key}_{self.name}", row, arr[0])
        self.energy[row] = float(self.system.energy(x1, v1)[0])
        if row in self.keep:
            self.snapshots[float(self.t[row])] = np.array(x1[:, 0])


def stream_methods(system: System, x0: np.ndarray, v0: np.ndarray, h: float, steps: int,
                   methods: list[str], record_every: int, out: Path, scene_name: str,
                   snapshots: int = 5, figures: bool = True, progress: bool | None = None) -> dict:
    """Run long simulations writing frames straight to ``out/<name>.npz`` (bounded memory).

    Keeps only the energy per frame and a few profile snapshots in memory.
    Returns a summary like :func:`compare`'s, plus the paths written.
    """
    from .chunked import ChunkedNPZ
    from .runners import Grid, RunContext, method

    ctx = RunContext(system, progress=progress)
    grid = Grid(h, steps, record_every)
    t = grid.t
    chosen = [method(name) for name in methods]
    for m in chosen:
        m.check(system)
    keep = set(np.linspace(0, len(t) - 1, min(snapshots, len(t))).round().astype(int).tolist())
    summary: dict = {"methods": {}}
    recorders: dict[str, _StreamRecorder] = {}
    npz = out / f"{scene_name}.npz"
    ground = ("aabs", "xabs") if getattr(system.module, "GROUND_DISPLACEMENT", False) else ("aabs",)
    extra = [f"{q}_{m}" for m in methods for q in ground] if system.ground is not None else []
    with ChunkedNPZ(npz, t, system.n, methods, progress=progress, extra=extra) as writer:
        for m in chosen:
            rec = recorders[m.name] = _StreamRecorder(writer, system, m.name, t, keep)
            t0 = time.perf_counter()
            evals = m.run(ctx, x0, v0, grid, rec)
            e = rec.energy
            summary["methods"][m.name] = {
                "seconds": time.perf_counter() - t0, "force_evals": evals,
                "energy_drift": float(np.max(np.abs(e - e[0]))),
                "energy_drift_relative": float(np.max(np.abs(e - e[0])) / max(np.max(np.abs(e)), 1e-300)),
            }
        if EXACT in methods:  # differences from exact, one frame at a time (bounded memory)
            compare_bar = Progress(len(t) * (len(methods) - 1), "differences from exact", enabled=progress)
            for name in methods:
                if name == EXACT:
                    continue
                dx = dv = 0.0
                for r in range(len(t)):
                    dx = max(dx, float(np.max(np.abs(writer.arrays[f"x_{name}"][r] - writer.arrays[f"x_{EXACT}"][r]))))
                    dv = max(dv, float(np.max(np.abs(writer.arrays[f"v_{name}"][r] - writer.arrays[f"v_{EXACT}"][r]))))
                    compare_bar.update(compare_bar.done + 1)
                summary["methods"][name]["max_position_difference"] = dx
                summary["methods"][name]["max_velocity_difference"] = dv
    paths = []
    if figures:
        with phase("figures", enabled=progress):
            for name, rec in recorders.items():
                fig = plots.profiles(rec.snapshots)
                paths.append(out / f"{scene_name}-{name}-profiles.png")
                plots.save(fig, paths[-1])
            energies = {name: rec.energy for name, rec in recorders.items()}
            fig = plots.energy(t, energies, float(next(iter(energies.values()))[0]),
                               conserved=not (system.damped or system.forced))
            paths.append(out / f"{scene_name}-energy.png")
            plots.save(fig, paths[-1])
    summary["npz"] = str(npz)
    summary["figures"] = [str(p) for p in paths]
    return summary
