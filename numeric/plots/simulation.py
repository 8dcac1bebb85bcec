"""The figures ``springchain simulate`` writes: positions, velocities, differences from the exact
run, a driven scene's frequency response and the energy (in-memory runs); profile snapshots and
the energy (streamed ``[chain]`` runs)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from . import figures as plots
from ..system import System


def write_figures(out: Path, scene_name: str, names, system: System, runs: dict) -> list[Path]:
    """Figures of in-memory runs (``numeric.run.simulate.Run`` by method name); returns the paths written."""
    t = next(iter(runs.values())).t
    paths = []

    def save(fig, suffix: str) -> None:
        paths.append(out / f"{scene_name}-{suffix}.png")
        plots.save(fig, paths[-1])

    title = " vs ".join(runs)
    save(plots.trajectories(t, {m: r.x for m, r in runs.items()}, names, "position x", "m",
                            f"{scene_name}: positions ({title})"), "positions")
    save(plots.trajectories(t, {m: r.v for m, r in runs.items()}, names, "velocity v", "m/s",
                            f"{scene_name}: velocities ({title})"), "velocities")
    exact = next((r for r in runs.values() if r.exact), None)
    for name, run in runs.items():
        if exact is not None and run is not exact:
            save(plots.differences(t, run.x - exact.x, run.v - exact.v, names, name), f"{name}-minus-exact")
    if system.harmonic_forcing and system.exact_available:
        from ..exact.linear import frequency_response

        omegas, fc, fs, _ = system.forcing_harmonics()
        if omegas.size:
            spec = system.spectrum
            force = np.abs(fc[0] + 1j * fs[0])
            top = 1.5 * max(spec.omega_max, float(np.max(omegas)))
            drive = np.linspace(top / 2000, top, 2000)
            amp = np.abs(frequency_response(system, drive, force))
            save(plots.frequency_response(drive, amp, names, spec.omega[spec.rigid:], omegas), "frequency-response")
    energies = {m: system.energy(r.x.T, r.v.T) for m, r in runs.items()}
    conserved = system.energy_conserved
    ref = exact if exact is not None else next(iter(runs.values()))  # the work along the exact run, else the first
    work = None
    if not conserved:
        from ..run.energy_balance import work as work_done

        work = work_done(system, t, ref.v)
    save(plots.energy(t, energies, float(next(iter(energies.values()))[0]), conserved=conserved, work=work), "energy")
    return paths


def write_stream_figures(out: Path, scene_name: str, t: np.ndarray, recorders: dict,
                         conserved: bool = True) -> list[Path]:
    """Profile snapshots per method and the energy of streamed runs
    (:class:`~numeric.run.recorder.StreamRecorder` by method name; ``conserved``: whether the energy is)."""
    paths = []
    for name, rec in recorders.items():
        paths.append(out / f"{scene_name}-{name}-profiles.png")
        plots.save(plots.profiles(rec.snapshots), paths[-1])
    energies = {name: rec.energy for name, rec in recorders.items()}
    paths.append(out / f"{scene_name}-energy.png")
    plots.save(plots.energy(t, energies, float(next(iter(energies.values()))[0]), conserved=conserved), paths[-1])
    return paths


__all__ = ["write_figures", "write_stream_figures"]
