"""The complex band structure: for ω in a gap, the attenuation per cell Im q(ω) of the evanescent wave.

At a frequency ω (λ = ω²) the Bloch condition det(K(q) − λM) = 0 has no real q in a gap; its complex roots
q = Re q + iκ give waves that decay by e^{−κ} per cell, the slowest one (smallest κ) what a finite chain
transmits. det(K(q) − λM) is a trigonometric polynomial Σ_{r ≤ R} α_r cos(rq) (R = the sum of the springs'
reaches: the degree of the cell's transfer matrix), known at any q from the accurate branches as
Π_m m · Π_j (ω²_j(q) − λ) — a product, no sum of signed terms.

* R = 1 (every chain whose only link to the next cell is one spring; diatomic, triatomic, mass-in-mass):
  with P_0, P_π its values at q = 0 and π (the same sign in a gap), cos q = −(P_0 + P_π)/(P_0 − P_π) and
  κ = ln((√|P_0| + √|P_π|)/|√|P_0| − √|P_π||) — closed form, no cancellation at the band edges; Re q = 0 when
  the q = 0 side is nearer a band (|P_0| < |P_π|), π otherwise.
* R > 1 (next-nearest neighbours): its values at the R + 1 Chebyshev–Lobatto points cos q_m = cos(πm/R)
  give its Chebyshev coefficients exactly; the roots x = cos q give z = x ± sqrt(x² − 1) = e^{iq}, κ = |ln|z||
  (the roots of the transfer matrix's characteristic polynomial).

Inside a band κ = 0.
"""

from __future__ import annotations

import numpy as np

from .cell import Cell
from .spectrum import spectrum

#: |ln|z|| below this counts as a propagating root (κ = 0).
PROPAGATING = 1e-9


def degree(cell: Cell) -> int:
    """R: the degree in e^{iq} of det(K(q) − λM), at most the sum of the springs' reaches."""
    inner = (cell.ends >= 0).all(axis=1)
    return max(1, int(np.abs(cell.reach[inner]).sum()))


def attenuation(cell: Cell, omega: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``(kappa, re_q)``: Im q and Re q of the slowest-decaying wave at each ω (kappa 0 inside a band).

    Parameters
    ----------
    omega : ndarray, shape (W,)
        Angular frequencies [rad/s].
    """
    omega = np.asarray(omega, dtype=float).reshape(-1)
    lam = omega * omega
    R = degree(cell)
    qm = np.pi * np.arange(R + 1) / R
    w2 = spectrum(cell, qm).omega2  # (R+1, p), ascending
    diff = w2[None, :, :] - lam[:, None, None]  # (W, R+1, p)
    with np.errstate(divide="ignore"):
        logp = np.sum(np.log(np.abs(diff)), axis=2)  # log |P_m| (the products overflow at a large contrast)
    sign = np.prod(np.sign(diff), axis=2)
    top = np.max(np.where(np.isfinite(logp), logp, -np.inf), axis=1, keepdims=True)
    top = np.where(np.isfinite(top), top, 0.0)
    P = sign * np.exp(logp - top)  # P_m / max_m |P_m|: the common factor cancels in every use
    if R == 1:
        return _one_link(P[:, 0], P[:, 1])
    kappa = np.zeros(omega.shape[0])
    re_q = np.zeros(omega.shape[0])
    xm = np.cos(qm)
    for w in range(omega.shape[0]):
        coef = np.polynomial.chebyshev.chebfit(xm, P[w], R)
        roots = np.polynomial.chebyshev.chebroots(coef)
        x = roots.astype(complex)
        root = np.sqrt(x * x - 1)
        z = np.where((x.conj() * root).real >= 0, x + root, x - root)  # |z| >= 1: no cancellation
        k = np.log(np.abs(z))
        best = int(np.argmin(k))
        kappa[w] = 0.0 if k[best] < PROPAGATING else k[best]
        re_q[w] = abs(float(np.angle(z[best])))
    return kappa, re_q


def _one_link(p0: np.ndarray, ppi: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    a, b = np.sqrt(np.abs(p0)), np.sqrt(np.abs(ppi))
    gap = (p0 * ppi > 0) & (a != b)
    with np.errstate(divide="ignore", invalid="ignore"):
        kappa = np.where(gap, np.log((a + b) / np.abs(a - b)), 0.0)
    re_q = np.where(gap & (np.abs(p0) >= np.abs(ppi)), np.pi, 0.0)
    return kappa, re_q


__all__ = ["PROPAGATING", "attenuation", "degree"]
