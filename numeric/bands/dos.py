"""The density of states of each band, exact: g_j(ω) = (1/π) Σ_{q*} 1/|v_j(q*)| over the q* ∈ (0, π) where
ω_j(q*) = ω (per cell and per rad/s: each band integrates to 1).

Not a histogram: for every ω of the grid, every solution q* of ω_j(q) = ω is found (band j is the j-th lowest
at each q; it is monotone between its extrema, which are located and refined first) by Newton's method on the
accurate branch with the analytic group velocity, kept inside its monotone bracket, and the group velocity
there gives the density. At a band edge v_j → 0 and g_j grows as 1/sqrt|ω − ω_edge| (the van Hove peaks):
the grid keeps strictly inside the bands.
"""

from __future__ import annotations

import itertools

import numpy as np

from .cell import Cell
from .spectrum import spectrum

#: q-samples on [0, π] that locate each band's monotone pieces.
SAMPLES = 257
#: Newton steps (each one accurate spectrum of the whole ω grid).
STEPS = 60


def _sorted_value(cell: Cell, q: np.ndarray, j: int) -> tuple[np.ndarray, np.ndarray]:
    s = spectrum(cell, q)
    return s.omega[:, j], s.velocity[:, j]


def band_pieces(cell: Cell, j: int, qs: np.ndarray, w: np.ndarray) -> list[tuple[float, float]]:
    """Monotone pieces [q_a, q_b] of band j, with the interior extrema refined."""
    from scipy.optimize import minimize_scalar

    from .edges import turns

    bounds = [0.0]
    for k, sign in turns(w):  # +1 a minimum, -1 a maximum
        res = minimize_scalar(lambda x, sign=sign: sign * _sorted_value(cell, np.array([x]), j)[0][0],
                              bounds=(qs[k - 1], qs[k + 1]), method="bounded", options={"xatol": 1e-12})
        bounds.append(float(res.x))
    bounds.append(float(np.pi))
    return [(a, b) for a, b in itertools.pairwise(bounds) if b > a]


def newton(cell: Cell, j: int, a: float, b: float, wa: float, wb: float, target: np.ndarray) -> np.ndarray:
    """q in [a, b] where band j (monotone there, ω = wa at a, wb at b) reaches each ω of ``target``: safeguarded
    Newton with the group velocity (bisection where a step leaves the bracket), iterating only on the q not yet
    converged."""
    up = wb > wa
    qa, qb = np.full(target.shape, a), np.full(target.shape, b)
    x = a + (b - a) * np.clip((target - wa) / (wb - wa), 0.0, 1.0) if wb != wa else np.full(target.shape, a)
    live = np.arange(target.shape[0])
    for _ in range(STEPS):
        f, v = _sorted_value(cell, x[live], j)
        r = f - target[live]
        below = (r < 0) == up  # the root lies beyond x (towards b)
        qa[live] = np.where(below, x[live], qa[live])
        qb[live] = np.where(below, qb[live], x[live])
        with np.errstate(divide="ignore", invalid="ignore"):
            step = x[live] - r / v
        lo, hi = np.minimum(qa[live], qb[live]), np.maximum(qa[live], qb[live])
        bad = ~np.isfinite(step) | (step <= lo) | (step >= hi)
        new = np.where(bad, 0.5 * (lo + hi), step)
        done = (np.abs(new - x[live]) <= 4 * np.finfo(float).eps * np.maximum(1.0, np.abs(new))) | (r == 0)
        x[live] = np.where(r == 0, x[live], new)
        live = live[~done]
        if live.size == 0:
            break
    return x


def density(cell: Cell, omega: np.ndarray) -> np.ndarray:
    """g_j(ω) of every band at every ω, shape (W, p) [cells⁻¹ (rad/s)⁻¹].

    Parameters
    ----------
    omega : ndarray, shape (W,)
        Angular frequencies [rad/s] (values on a band edge give inf there).
    """
    omega = np.asarray(omega, dtype=float).reshape(-1)
    qs = np.linspace(0.0, np.pi, SAMPLES)
    grid = spectrum(cell, qs)
    out = np.zeros((omega.shape[0], cell.p))
    for j in range(cell.p):
        for a, b in band_pieces(cell, j, qs, grid.omega[:, j]):
            (wa, wb), _ = _sorted_value(cell, np.array([a, b]), j)
            lo, hi = min(wa, wb), max(wa, wb)
            inside = np.flatnonzero((omega > lo) & (omega < hi))
            if inside.size == 0 or hi <= lo:
                continue
            target = omega[inside]
            # start from the straight line through the ends, then safeguarded Newton in the bracket [a, b]
            x = newton(cell, j, a, b, wa, wb, target)
            _, v = _sorted_value(cell, x, j)
            with np.errstate(divide="ignore"):
                out[inside, j] += 1.0 / (np.pi * np.abs(v))
    return out


__all__ = ["SAMPLES", "density"]
