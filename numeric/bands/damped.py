"""Damped bands: complex ω_j(q) = ω_d + iσ of each band (u ∝ e^{iωt}, decaying by e^{−σt}), and ζ per band.

* Rayleigh damping only (C = αM + βK(q)): every band keeps its eigenvector and s = iω solves
  s² + (α + βω²_j) s + ω²_j = 0, so σ_j = (α + β ω²_j)/2, ω_d = sqrt((ω_j − σ_j)(ω_j + σ_j)) (no cancellation)
  and ζ_j = σ_j/ω_j, from the accurate ω²_j(q) — closed form per band;
* dashpots: the quadratic eigenproblem (K(q) + sC(q) + s²M)u = 0 is solved per q in float64 (companion
  form, LAPACK's eig); each band is the root pair nearest to the undamped ω_j by modulus (an overdamped pair
  of real roots s₁, s₂: ω_n = sqrt(s₁s₂), ζ = −(s₁ + s₂)/(2ω_n)).

ζ is undefined where ω_n = 0 (the acoustic band at q = 0): NaN there (null in JSON).
"""

from __future__ import annotations

import numpy as np

from ..io.array_record import array_record
from .cell import Cell
from .spectrum import Spectrum


@array_record
class Damped:
    """Complex frequencies of each band.

    Attributes
    ----------
    omega_n : ndarray, shape (Q, p)
        Undamped-like natural frequency |s| [rad/s].
    omega_d : ndarray, shape (Q, p)
        Damped frequency Re ω [rad/s] (0 for an overdamped band).
    sigma : ndarray, shape (Q, p)
        Decay rate Im ω = ζ ω_n [1/s].
    zeta : ndarray, shape (Q, p)
        Damping ratio per band (NaN where ω_n = 0).
    """

    omega_n: np.ndarray
    omega_d: np.ndarray
    sigma: np.ndarray
    zeta: np.ndarray

    @property
    def omega(self) -> np.ndarray:
        """Complex ω = ω_d + iσ, shape (Q, p)."""
        return self.omega_d + 1j * self.sigma


def bloch(p: int, ends: np.ndarray, reach: np.ndarray, values: np.ndarray, q: np.ndarray) -> np.ndarray:
    """K(q) or C(q) of elements ``(ends, reach, values)`` in float64, shape (Q, p, p) (for the dashpot route)."""
    A = np.zeros((q.shape[0], p, p), dtype=complex)
    for (a, b), r, w in zip(ends.tolist(), reach.tolist(), values.tolist()):
        if a < 0 or b < 0:
            c = b if a < 0 else a
            A[:, c, c] += w
        elif a == b:
            A[:, a, a] += 4 * w * np.sin(r * q / 2) ** 2
        else:
            e = np.exp(1j * r * q)
            A[:, a, a] += w
            A[:, b, b] += w
            A[:, a, b] -= w * e
            A[:, b, a] -= w * e.conj()
    return A


def damped(cell: Cell, spec: Spectrum) -> Damped:
    """The damped bands at the q of ``spec`` (its branches in the same order)."""
    lam = spec.omega2
    if cell.proportional:
        alpha, beta = cell.rayleigh
        wn = np.sqrt(lam)
        sigma = 0.5 * (alpha + beta * lam)
        wd = np.sqrt(np.maximum((wn - sigma) * (wn + sigma), 0.0))
        with np.errstate(divide="ignore", invalid="ignore"):
            zeta = np.where(wn > 0, sigma / wn, np.nan)
        return Damped(wn, wd, np.where(wn > sigma, sigma, _slow(sigma, lam)), zeta)
    return _quadratic(cell, spec)


def _slow(sigma: np.ndarray, lam: np.ndarray) -> np.ndarray:
    """The slower decay rate of an overdamped band, λ/(σ + sqrt(σ² − λ)) (no cancellation)."""
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(sigma > 0, lam / (sigma + np.sqrt(np.maximum(sigma * sigma - lam, 0.0))), 0.0)


def _quadratic(cell: Cell, spec: Spectrum) -> Damped:
    q = np.abs(spec.q)
    p = cell.p
    K = bloch(p, cell.ends, cell.reach, cell.stiffness, q)
    C = bloch(p, cell.damper_ends, cell.damper_reach, cell.damping, q)
    alpha, beta = cell.rayleigh
    C = C + alpha * np.diag(cell.masses)[None] + beta * K
    Minv = 1.0 / cell.masses
    A = np.zeros((q.shape[0], 2 * p, 2 * p), dtype=complex)
    A[:, :p, p:] = np.eye(p)
    A[:, p:, :p] = -Minv[None, :, None] * K
    A[:, p:, p:] = -Minv[None, :, None] * C
    s = np.linalg.eigvals(A)
    wn, zeta = np.zeros((q.shape[0], p)), np.full((q.shape[0], p), np.nan)
    for k in range(q.shape[0]):
        bands = _pairs(s[k], p)
        order = np.argsort([b[0] for b in bands])
        target = np.argsort(np.argsort(spec.omega2[k]))  # the ascending rank of each branch of spec
        for j in range(p):
            w, z = bands[order[target[j]]]
            wn[k, j], zeta[k, j] = w, z
    sigma = np.where(np.isfinite(zeta), zeta * wn, 0.0)
    wd = np.where(np.isfinite(zeta) & (zeta < 1), wn * np.sqrt(np.maximum((1 - zeta) * (1 + zeta), 0.0)), 0.0)
    return Damped(wn, wd, sigma, zeta)


def _pairs(s: np.ndarray, p: int) -> list[tuple[float, float]]:
    """(ω_n, ζ) of each band from the 2p roots s: conjugate pairs, and real roots paired by size."""
    scale = max(float(np.max(np.abs(s))), np.finfo(float).tiny)
    real = np.abs(s.imag) <= 1e-12 * scale
    out = [(float(abs(x)), float(-x.real / abs(x))) for x in s[~real] if x.imag > 0]
    r = np.sort(s[real].real)[::-1]  # nearest 0 first
    for a, b in zip(r[0::2], r[1::2]):
        w = float(np.sqrt(max(a * b, 0.0)))
        out.append((w, float(-(a + b) / (2 * w)) if w > 0 else float("nan")))
    while len(out) < p:
        out.append((0.0, float("nan")))
    return out[:p]


__all__ = ["Damped", "bloch", "damped"]
