"""What an engineer reads off a trajectory of a shear building: drifts, spring forces, base shear.

One pass over the spring list (vectorised over frames and springs, no loop over masses).
"""

from __future__ import annotations

import numpy as np

from .system import System


def spring_series(system: System, x: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Drifts, spring forces and base shear of a trajectory.

    Parameters
    ----------
    system : System
    x : ndarray, shape (S, N)
        Positions (relative to the ground).

    Returns
    -------
    drift : ndarray, shape (S, springs)
        ``x_b − x_a`` of each spring ``between = [a, b]`` (a wall is 0): the inter-storey drift.
    force : ndarray, shape (S, springs)
        Spring tension ``k·d + k3·d³`` with d the drift (the storey shear of a shear building) [N].
    base_shear : ndarray, shape (S,)
        Force of the wall springs on the ground, positive in +x [N].
    """
    ends = system.spring_ends
    x = np.asarray(x, dtype=float)
    xa = np.where(ends[:, 0] >= 0, x[:, np.maximum(ends[:, 0], 0)], 0.0)
    xb = np.where(ends[:, 1] >= 0, x[:, np.maximum(ends[:, 1], 0)], 0.0)
    drift = xb - xa
    force = drift * system.stiffness[None, :]
    if system.cubic_stiffness is not None:
        force = force + system.cubic_stiffness[None, :] * drift**3
    sign = np.where(ends[:, 0] < 0, 1.0, 0.0) - np.where(ends[:, 1] < 0, 1.0, 0.0)
    return drift, force, force @ sign


__all__ = ["spring_series"]
