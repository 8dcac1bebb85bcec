"""The energy balance of a scene with dampers, forces or ground motion: E(t) − E(0) = W(t).

``W(t) = ∫₀ᵗ P dt`` is the work done on the masses by the external forces (expressions, tables,
the ground's inertial force −m·a_g in relative coordinates) and by the dampers, with power
``P = Σ mᵢ vᵢ a_ext,i(t) − vᵀ C v``. Gravity and springs are in the potential energy, not here.
"""

from __future__ import annotations

import numpy as np

from ..system import System


def power(system: System, t: np.ndarray, v: np.ndarray) -> np.ndarray:
    """P(t) of the forces and dampers along a trajectory; t shape (S,), v shape (S, N) -> (S,)."""
    t = np.asarray(t, dtype=float)
    p = np.zeros(t.shape)
    if system.forced:
        a = system.applied_acceleration(t) - system.ground_acceleration(t)  # (N, S)
        p += np.einsum("n,sn,ns->s", system.masses, v, a)
    rate = system.damping_rate_matrix()  # -M^-1 C, dense or sparse (N, N)
    if rate is not None:
        p += np.einsum("sn,sn->s", v * system.masses, np.asarray((rate @ v.T).T))
    return p


def work(system: System, t: np.ndarray, v: np.ndarray) -> np.ndarray:
    """W(t), shape (S,): the cumulative trapezoid of :func:`power` on the recorded times (W(0) = 0)."""
    p = power(system, t, v)
    return np.concatenate([[0.0], np.cumsum(0.5 * (p[1:] + p[:-1]) * np.diff(t))])


__all__ = ["power", "work"]
