"""The one a-priori bound on the largest frequency, used wherever a step is checked or a
polynomial degree chosen without an eigen-solve."""

from __future__ import annotations

import numpy as np


def omega2_bound(masses: np.ndarray, spring_ends: np.ndarray, stiffness: np.ndarray) -> float:
    """A rigorous upper bound on ω²_max: Gershgorin on ``M⁻¹K``, ``max_i 2 Σ_{s∋i} |k_s| / m_i``.

    Parameters
    ----------
    masses : ndarray, shape (N,)
    spring_ends : ndarray of int, shape (S, 2)
        Mass indices of each spring's ends; -1 is a wall.
    stiffness : ndarray, shape (S,)

    Returns
    -------
    float
        ≥ the largest ω² of ``K φ = ω² M φ`` (0 for N = 0). O(N + S), no N × N.
    """
    masses = np.asarray(masses, dtype=float)
    ends = np.asarray(spring_ends).reshape(-1, 2)
    k = np.abs(np.asarray(stiffness, dtype=float))
    load = np.zeros(masses.shape[0])
    for col in (0, 1):
        idx = ends[:, col]
        inside = idx >= 0
        load += np.bincount(idx[inside], weights=k[inside], minlength=masses.shape[0])
    return float(np.max(2.0 * load / masses)) if masses.size else 0.0


def chain_omega2_bound(n: int, inv_mass, k_inner, k_left: float, k_right: float, ring: bool = False) -> float:
    """The same bound for a chain stored as a stencil: mass i feels ``k_{i-1} + k_i`` (walls included).

    Parameters
    ----------
    n : int
        Number of masses.
    inv_mass : float or ndarray, shape (N,)
        1/m (a uniform chain may pass one value).
    k_inner : float or ndarray, shape (N-1,)
        Springs between neighbours (a uniform chain may pass one value).
    k_left, k_right : float
        Wall springs at the ends (0 for a free end); with ``ring`` the right one closes the ring.
    """
    if n <= 0:
        return 0.0
    inv = np.broadcast_to(np.asarray(inv_mass, dtype=float).reshape(-1)[: n], (n,)) \
        if np.size(inv_mass) in (1, n) else np.asarray(inv_mass, dtype=float)
    k = np.abs(np.broadcast_to(np.asarray(k_inner, dtype=float).reshape(-1)[: max(n - 1, 0)] if n > 1
                               else np.zeros(0), (max(n - 1, 0),)))
    load = np.zeros(n)
    load[:-1] += k
    load[1:] += k
    load[0] += abs(k_left) + (abs(k_right) if ring else 0.0)
    load[-1] += abs(k_right)
    return float(np.max(2.0 * load * inv))
