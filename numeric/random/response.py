"""Stationary random response: the RMS of every output by the exact modal integral, and response PSDs.

For an output ``H_y(s) = D_y + Σ_r R_yr/(s − λ_r)`` (:mod:`.modal_form`) under a one-sided input PSD
``G(f)`` (:mod:`.psd_input`), the mean square ``σ_y² = ∫ G(f) |H_y(i2πf)|² df`` is, exactly,

    σ_y² = D_y² ∫G df + 2 Re(D_y Σ_r R_yr J_r) + Re Σ_{r,s} R_yr conj(R_ys) (J_r + conj(J_s)) / (−λ_r − conj(λ_s))

with ``J_r = ∫ G(f)/(i2πf − λ_r) df`` in closed form per segment (the product of two partial
fractions is one partial fraction: ``1/((iω−λ_r)(−iω−λ̄_s)) = [1/(iω−λ_r) + 1/(−iω−λ̄_s)]/(−λ_r−λ̄_s)``).
No frequency grid enters the RMS: a resonance narrower than any grid is integrated exactly. The
response PSD ``G_y(f) = |H_y(i2πf)|² G(f)`` is evaluated on a grid refined at every resonance, for
figures and tables only.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .modal_form import PoleResidue
from .psd_input import InputPSD

#: Base grid points of the response PSD curves, and points added around each resonance.
GRID_POINTS = 800
REFINE_POINTS = 40


@dataclass(frozen=True)
class RandomResponse:
    """RMS values and response PSDs of a scene under a random input.

    Attributes
    ----------
    names, kinds, units : tuple of str, length Y
        Output names, kinds (displacement, velocity, acceleration, spring force) and SI units.
    rms : ndarray, shape (Y,)
        Root mean square of each output (SI), from the exact integral.
    f : ndarray, shape (W,)
        Frequencies [Hz] of the PSD curves.
    psd : ndarray, shape (Y, W)
        One-sided response PSDs [unit²/Hz].
    input_psd : ndarray, shape (W,)
        The input PSD on ``f``.
    input_rms : float
        RMS of the input (``√∫G df``).
    """

    names: tuple
    kinds: tuple
    units: tuple
    rms: np.ndarray = field(repr=False)
    f: np.ndarray = field(repr=False)
    psd: np.ndarray = field(repr=False)
    input_psd: np.ndarray = field(repr=False)
    input_rms: float = 0.0


def mean_square(model: PoleResidue, G: InputPSD) -> np.ndarray:
    """``σ_y² = ∫ G(f) |H_y(i2πf)|² df`` of every output, exactly (see the module docstring), shape (Y,)."""
    lam = model.poles
    J = G.pole_integrals(lam)
    W = (J[:, None] + np.conj(J)[None, :]) / (-(lam[:, None] + np.conj(lam)[None, :]))
    R = model.residues
    pair = np.real(np.einsum("yr,rs,ys->y", R, W, np.conj(R)))
    D = model.direct
    out = pair + 2.0 * np.real(D * (R @ J))
    if np.any(D != 0):
        out = out + D * D * G.mean_square()
    return np.maximum(out, 0.0)


def grid(model: PoleResidue, G: InputPSD, points: int = GRID_POINTS) -> np.ndarray:
    """Frequencies [Hz] over the input's band: log-spaced (linear from 0), refined at each resonance."""
    lo, hi = G.f[0], G.f[-1]
    base = np.geomspace(max(lo, hi * 1e-12), hi, points) if lo > 0 else np.concatenate([[0.0], np.geomspace(hi * 1e-6, hi, points)])
    extra = []
    u = np.geomspace(0.02, 20.0, REFINE_POINTS // 2)
    for w, z in zip(model.omega_n, model.zeta):
        fn = w / (2 * np.pi)
        width = max(min(z, 0.5), 1e-6)
        extra.append(fn * np.concatenate([1 - width * u[u * width < 0.9], [1.0], 1 + width * u]))
    out = np.union1d(base, np.concatenate(extra)) if extra else base
    return np.union1d(out[(out >= lo) & (out <= hi)], G.f)


def random_response(model: PoleResidue, G: InputPSD) -> RandomResponse:
    """RMS of every output of ``model`` under ``G`` (exact) and the response PSDs on :func:`grid`."""
    f = grid(model, G)
    H = model.response(2 * np.pi * f)
    Gf = G.value(f)
    return RandomResponse(model.names, model.kinds, model.units, np.sqrt(mean_square(model, G)), f,
                          np.abs(H) ** 2 * Gf[None, :], Gf, float(np.sqrt(G.mean_square())))


__all__ = ["RandomResponse", "random_response", "mean_square", "grid"]
