"""Absolute motion of scenes with ``[ground]``: coordinates are relative to the ground, so the
absolute acceleration is the relative one plus ``a_g`` and the absolute displacement ``x + x_g``."""

from __future__ import annotations

import numpy as np

from ..system import System


def absolute_keys(system: System) -> tuple[str, ...]:
    """The absolute quantities a run of ``system`` records: ``aabs`` (and ``xabs`` when the ground
    displacement is known); none without ``[ground]``."""
    if system.ground is None:
        return ()
    return ("aabs", "xabs") if system.ground_displacement else ("aabs",)


def absolute_motion(system: System, t: np.ndarray, x: np.ndarray, v: np.ndarray) -> dict[str, np.ndarray]:
    """Absolute motion of a scene with ``[ground]`` (empty dict without it).

    The absolute acceleration is ``aabs = a(x) − M⁻¹C v + M⁻¹F(t)`` (every force but the ground's
    ``−m a_g``). The absolute displacement ``xabs = x + x_g(t)`` is given only when ``x_g`` is known
    in closed form (an acceleration expression integrated with ``x_g(0) = v_g(0) = 0``).

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
    if system.ground_displacement:
        out["xabs"] = x + system.ground_motion(t)[:, None]
    return out


def absolute_npz_arrays(system: System, t: np.ndarray, x: dict, v: dict) -> dict[str, np.ndarray]:
    """``aabs_<method>`` (and ``xabs_<method>`` when the ground displacement is known) of every run."""
    out = {}
    for name in x:
        for key, arr in absolute_motion(system, t, x[name], v[name]).items():
            out[f"{key}_{name}"] = arr
    return out


__all__ = ["absolute_keys", "absolute_motion", "absolute_npz_arrays"]
