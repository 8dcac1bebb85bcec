"""Pairing measured modes with a model's, and the weighted residuals of :mod:`.fit` with their Jacobian.

Pairing (at the starting parameters, kept during the fit): the assignment that minimises the summed
cost ``|log(ω_j/ω̃_r)| + (1 − MAC_jr)`` (the MAC term only for rows with a measured shape), over the
model's elastic modes: with shapes this is pairing by MAC, without them by frequency.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..sensitivity.mac import mac_matrix
from .measured import Measured


@dataclass(frozen=True)
class Pairing:
    """Measured row r ↔ model mode ``modes[r]`` (a position among all modes, ascending ω²).

    Attributes
    ----------
    modes : ndarray of int, shape (R,)
    mac : ndarray, shape (R,)
        MAC of each pair (NaN for rows without a measured shape).
    """

    modes: np.ndarray = field(repr=False)
    mac: np.ndarray = field(repr=False)


def pair(measured: Measured, positions: np.ndarray, omega: np.ndarray, sensor_shapes: np.ndarray | None) -> Pairing:
    """Pair every measured row with a distinct elastic model mode.

    Parameters
    ----------
    measured : Measured
    positions : ndarray of int, shape (J,)
        The model's elastic modes (positions).
    omega : ndarray, shape (J,)
        Their ω (> 0).
    sensor_shapes : ndarray, shape (D, J) or None
        Their shapes at the measured sensors.
    """
    from scipy.optimize import linear_sum_assignment

    cost = np.abs(np.log(omega[None, :] / measured.omega[:, None]))
    mac_all = np.full(cost.shape, np.nan)
    if sensor_shapes is not None and measured.shapes is not None:
        rows = measured.with_shapes()
        if rows.size:
            mac_all[rows] = mac_matrix(measured.shapes[:, rows], sensor_shapes)
            cost[rows] += 1.0 - mac_all[rows]
    r, c = linear_sum_assignment(cost)
    modes = np.empty(measured.rows, dtype=np.intp)
    modes[r] = positions[c]
    mac = np.full(measured.rows, np.nan)
    mac[r] = mac_all[r, c]
    return Pairing(modes, mac)


def weighted(measured: Measured, values: np.ndarray, omega2: np.ndarray, d_omega2: np.ndarray,
             shapes: np.ndarray | None, d_shapes: np.ndarray | None, known_noise: bool) -> tuple[np.ndarray, np.ndarray]:
    """Weighted residuals and their Jacobian with respect to ``θ = log p``.

    Parameters
    ----------
    measured : Measured
    values : ndarray, shape (P,)
        Parameter values p.
    omega2 : ndarray, shape (R,)
        Model ω² of the mode paired with each measured row.
    d_omega2 : ndarray, shape (P, R)
    shapes : ndarray, shape (D, R) or None
        Model shapes at the sensors.
    d_shapes : ndarray, shape (P, D, R) or None
    known_noise : bool
        Weights from the file's standard deviations, else relative frequency errors and unit shape weights.

    Returns
    -------
    r : ndarray, shape (m,)
    J : ndarray, shape (m, P)
    """
    p = np.asarray(values, dtype=float)
    omega = np.sqrt(omega2)
    sigma = measured.omega_std if known_noise else measured.omega
    r = [(omega - measured.omega) / sigma]
    J = [(p[:, None] * d_omega2 / (2.0 * omega[None, :])).T / sigma[:, None]]  # elastic modes: ω > 0
    if shapes is not None and measured.shapes is not None:
        for row in measured.with_shapes():
            psi = measured.shapes[:, row]
            psi = psi / np.max(np.abs(psi))  # the measured shape, 1 in magnitude at its largest sensor
            phi = shapes[:, row]
            dphi = d_shapes[:, :, row] * p[:, None]  # ∂φ/∂θ, (P, D)
            s = measured.shape_std[row] if known_noise else 1.0
            # ψ − α φ with the modal scale factor α = φᵀψ/φᵀφ: the part of ψ no multiple of φ explains
            nn = phi @ phi
            alpha = (phi @ psi) / nn
            r.append((psi - alpha * phi) / s)
            d_alpha = (dphi @ psi - 2 * alpha * (dphi @ phi)) / nn  # (P,)
            J.append(-(dphi * alpha + d_alpha[:, None] * phi[None, :]).T / s)
    return np.concatenate(r), np.vstack(J)


__all__ = ["Pairing", "pair", "weighted"]
