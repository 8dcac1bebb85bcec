"""What a simulation reports per method: differences from the exact run, energy drift, momentum.

The relative energy drift is written once, :func:`energy_drift`: ``max |E − E(0)|`` over a scale
that stays away from zero, the larger of ``max |E|`` and the largest kinetic energy (E may be ~0).
"""

from __future__ import annotations

import numpy as np

from ..progress import Reporter
from ..system import System


def energy_drift(e: np.ndarray, kinetic_max: float) -> dict[str, float]:
    """``energy_drift`` = max |E − E(0)| and ``energy_drift_relative`` (see the module docstring).

    Parameters
    ----------
    e : ndarray, shape (S,)
        Energy per recorded frame.
    kinetic_max : float
        Largest kinetic energy over the frames.
    """
    drift = float(np.max(np.abs(e - e[0])))
    scale = max(float(np.max(np.abs(e))), float(kinetic_max), 1e-300)
    return {"energy_drift": drift, "energy_drift_relative": drift / scale}


def compare(system: System, runs: dict) -> dict:
    """Largest differences from the exact run, energy drift and momentum change of every run.

    Parameters
    ----------
    runs : dict of str to numeric.run.simulate.Run
    """
    summary: dict = {"methods": {}}
    exact = next((r for r in runs.values() if r.exact), None)
    for name, run in runs.items():
        e = system.energy(run.x.T, run.v.T)
        p = system.momentum(run.v.T)
        rec = {"seconds": run.seconds, "force_evals": run.force_evals,
               **energy_drift(e, float(np.max(system.kinetic_energy(run.v.T)))),
               "momentum_change": float(np.max(np.abs(p - p[0])))}
        if exact is not None and run is not exact:
            rec["max_position_difference"] = float(np.max(np.abs(run.x - exact.x)))
            rec["max_velocity_difference"] = float(np.max(np.abs(run.v - exact.v)))
        summary["methods"][name] = rec
    return summary


def streamed_differences(arrays: dict, names: list[str], exact: str, frames: int,
                         progress: bool | None = None) -> dict[str, dict[str, float]]:
    """Largest differences of each streamed run from the exact one, one frame at a time (bounded memory).

    Parameters
    ----------
    arrays : mapping
        ``x_<name>``, ``v_<name>`` arrays of shape (S, N) (memory maps of a chunked NPZ).
    names : list of str
        The runs to compare (the exact one excluded).
    exact : str
        The exact run's name.
    """
    bar = Reporter("differences from exact", frames * len(names), enabled=progress)
    out = {}
    for name in names:
        dx = dv = 0.0
        for r in range(frames):
            dx = max(dx, float(np.max(np.abs(arrays[f"x_{name}"][r] - arrays[f"x_{exact}"][r]))))
            dv = max(dv, float(np.max(np.abs(arrays[f"v_{name}"][r] - arrays[f"v_{exact}"][r]))))
            bar.update(bar.done + 1)
        out[name] = {"max_position_difference": dx, "max_velocity_difference": dv}
    return out


__all__ = ["energy_drift", "compare", "streamed_differences"]
