"""Closed forms of one mode that never divide by zero: the singular-point-safe scalar kernels.

Every exact solution in springchain reduces to a few one-degree-of-freedom
responses. Their textbook formulas divide by ω (rigid modes), by ω² − Ω²
(resonance) or by √(ζ² − 1) (critical damping), and subtract nearly equal
exponentials (strong overdamping). Here each is written through functions
that are entire in the offending parameter (``sinc``, ``sinhc``, series of
positive terms, the slow root in its cancellation-free form), so the exact
singular point and its neighbourhood (relative distance 1e-8, 1e-12, 1e-15)
are computed to a few ulps, as far as the conditioning of the function
itself allows.

All functions are NumPy ufunc-style: arguments broadcast against each other
and the result has the broadcast shape. Frequencies are angular (rad/s) and
non-negative unless stated.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

#: Below this ``max(ω, Ω)·t`` the forced responses use their Taylor series in t
#: (alternating, terms decreasing, 24 terms give full precision up to 2).
_SERIES_LIMIT = 2.0
_SERIES_TERMS = 24
#: Above this ``b·t`` (``b`` the half distance of the real roots) the overdamped
#: response is written with the two exponentials of the roots (no cancellation
#: beyond a factor 1/(1 − e⁻²)); below it with ``cosh`` and ``sinhc`` of ``b·t``.
_ROOT_SPLIT = 1.0


def omega_from_omega2(omega2: np.ndarray) -> np.ndarray:
    """``ω = √max(ω², 0)``: roundoff below zero is a rigid mode, never a NaN (an ndarray of the
    shape of ``omega2``)."""
    return np.sqrt(np.maximum(np.asarray(omega2, dtype=float), 0.0))


def sinc(x: np.ndarray) -> np.ndarray:
    """Unnormalised ``sinc(x) = sin(x)/x``, 1 at x = 0.

    ``sin(x)/x`` is accurate for every non-zero float (``sin`` of a tiny
    argument is the argument itself), so only x = 0 is special. Elementwise: an ndarray of
    the shape of ``x``.
    """
    return _over_x(np.sin, x)


def _over_x(f, x) -> np.ndarray:
    """``f(x)/x`` with its limit 1 at x = 0 (for f = sin, sinh: accurate at every other float)."""
    x = np.asarray(x, dtype=float)
    zero = x == 0.0
    safe = np.where(zero, 1.0, x)
    return np.where(zero, 1.0, f(safe) / safe)


def sinhc(x: np.ndarray) -> np.ndarray:
    """``sinhc(x) = sinh(x)/x``, 1 at x = 0 (``sinh`` is accurate near 0, so no series is needed);
    elementwise, an ndarray of the shape of ``x``."""
    return _over_x(np.sinh, x)


def tsinc(omega: np.ndarray, t: np.ndarray) -> np.ndarray:
    """``sin(ω t)/ω`` written as ``t·sinc(ωt)``: finite and exact at ω = 0 (= t).

    Parameters
    ----------
    omega, t : array_like (broadcast)

    Returns
    -------
    ndarray
    """
    t = np.asarray(t, dtype=float)
    return t * sinc(np.asarray(omega, dtype=float) * t)


# -- undamped mode under harmonic forcing -------------------------------------------------------------
def undamped_forced_cos(omega: np.ndarray, Omega: np.ndarray, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Response of ``ẍ + ω² x = cos(Ω t)`` from rest, exact at resonance Ω = ω.

    ``x = (cos Ωt − cos ωt)/(ω² − Ω²)`` is written as the product

        x = (t²/2) · sinc(σ t) · sinc(δ t),   σ = (ω + Ω)/2,  δ = (ω − Ω)/2,

    which is ``t sin(ωt)/(2ω)`` at Ω = ω, ``(1 − cos ωt)/ω²`` at Ω = 0 and
    ``t²/2`` at ω = Ω = 0. ``δ`` is computed exactly when Ω is close to ω
    (Sterbenz), so there is no cancellation anywhere.

    Parameters
    ----------
    omega : array_like
        Natural frequency ω ≥ 0.
    Omega : array_like
        Drive frequency Ω (any sign: the response is even in Ω).
    t : array_like
        Time since the force was switched on (x(0) = ẋ(0) = 0).

    Returns
    -------
    x, v : ndarray
        Displacement and velocity, broadcast shape of the inputs.
        ``v = (t/2)·[cos(σt) sinc(δt) + cos(δt) sinc(σt)]``.
    """
    omega, Omega, t = (np.asarray(a, dtype=float) for a in (omega, Omega, t))
    sigma = 0.5 * (omega + Omega)
    delta = 0.5 * (omega - Omega)
    ss, sd = sinc(sigma * t), sinc(delta * t)
    x = 0.5 * t * t * ss * sd
    v = 0.5 * t * (np.cos(sigma * t) * sd + np.cos(delta * t) * ss)
    return x, v


def _forced_sin_series(omega, Omega, t):
    """``x = Ω t³ Σ_n (−1)ⁿ H_n / (2n+3)!`` with ``H_n = Σ_j (ωt)^{2j} (Ωt)^{2(n−j)}`` (all terms ≥ 0)."""
    a = (omega * t) ** 2
    b = (Omega * t) ** 2
    H = np.ones(np.broadcast(a, b).shape)
    a_pow = np.ones_like(H)
    total = H / 6.0
    fact = 6.0
    for n in range(1, _SERIES_TERMS):
        a_pow = a_pow * a
        H = b * H + a_pow
        fact *= (2 * n + 2) * (2 * n + 3)
        total = total + (-1.0) ** n * H / fact
    return Omega * t**3 * total


def undamped_forced_sin(omega: np.ndarray, Omega: np.ndarray, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Response of ``ẍ + ω² x = sin(Ω t)`` from rest, exact at Ω = ω and at ω = 0.

    The textbook ``(ω sin Ωt − Ω sin ωt)/(ω(ω² − Ω²))`` divides by ω and by
    ω² − Ω². Three forms, each free of cancellation where it is used:

    * near resonance (Ω/2 < ω < 2Ω): ``x = t·[sinc(ωt) − cos(σt) sinc(δt)]/(ω + Ω)``
      with σ, δ as in :func:`undamped_forced_cos` (at Ω = ω:
      ``(sin ωt − ωt cos ωt)/(2ω²)``);
    * far from it: ``x = Ω·(t·sinc(ωt) − t·sinc(Ωt))/((Ω − ω)(Ω + ω))``, whose
      denominator is at least 3/4 of the larger square (this covers ω = 0:
      ``(Ωt − sin Ωt)/Ω²``);
    * short times, ``max(ω, Ω)·t ≤ 2``, where both brackets above cancel: the
      Taylor series in t, ``Ω t³ Σ (−1)ⁿ H_n/(2n+3)!``, whose ``H_n`` are sums of
      positive terms.

    Parameters
    ----------
    omega, Omega, t : array_like
        As for :func:`undamped_forced_cos` (t ≥ 0); the response is odd in Ω.

    Returns
    -------
    x, v : ndarray
        Displacement and velocity; ``v = Ω · x_cos`` with ``x_cos`` from
        :func:`undamped_forced_cos` (the derivative of the sine response is Ω
        times the cosine response).
    """
    omega, Omega, t = (np.asarray(a, dtype=float) for a in (omega, Omega, t))
    omega, Omega, t = np.broadcast_arrays(omega, Omega, t)
    sign = np.where(Omega < 0, -1.0, 1.0)
    W = np.abs(Omega)
    x_cos, _ = undamped_forced_cos(omega, W, t)
    v = W * x_cos
    big = np.maximum(omega, W) * t
    series = big <= _SERIES_LIMIT
    near = ~series & (2.0 * omega > W) & (omega < 2.0 * W)
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        sigma = 0.5 * (omega + W)
        delta = 0.5 * (omega - W)
        x_near = t * (sinc(omega * t) - np.cos(sigma * t) * sinc(delta * t)) / (omega + W)
        x_far = W * (t * sinc(omega * t) - t * sinc(W * t)) / ((W - omega) * (W + omega))
        x_series = _forced_sin_series(omega, W, np.where(series, t, 0.0))
    x = np.where(series, x_series, np.where(near, x_near, x_far))
    return sign * x, sign * v


# -- one damped mode, free response ---------------------------------------------------------------------
class FreeResponse(NamedTuple):
    """The fundamental solutions of one damped mode and their time derivatives.

    A mode with initial displacement x0 and velocity v0 is
    ``x(t) = x0·g0 + v0·g1``, ``ẋ(t) = x0·dg0 + v0·dg1``.

    Attributes
    ----------
    g0 : ndarray
        Response to x(0) = 1, ẋ(0) = 0.
    g1 : ndarray
        Response to x(0) = 0, ẋ(0) = 1.
    dg0, dg1 : ndarray
        Their time derivatives.
    """

    g0: np.ndarray
    g1: np.ndarray
    dg0: np.ndarray
    dg1: np.ndarray


def _damped(a, bsq, w2, t) -> FreeResponse:
    """``ẍ + 2a ẋ + w2·x = 0`` with ``bsq = a² − w2`` supplied accurately by the caller."""
    a, bsq, w2, t = np.broadcast_arrays(*(np.asarray(z, dtype=float) for z in (a, bsq, w2, t)))
    b = np.sqrt(np.abs(bsq))
    bt = b * t
    under = bsq < 0.0
    split = ~under & (bt > _ROOT_SPLIT)
    with np.errstate(over="ignore", under="ignore", invalid="ignore", divide="ignore"):
        decay = np.exp(-a * t)
        # oscillating (b² < 0) or near-critical (b·t ≤ 1): cos/cosh and t·sinc/t·sinhc of b·t
        bt_small = np.where(split, 0.0, bt)
        c = np.where(under, np.cos(bt_small), np.cosh(bt_small))
        s = t * np.where(under, sinc(bt_small), sinhc(bt_small))
        g1_a = decay * s
        g0_a = decay * (c + a * s)
        dg1_a = decay * (c - a * s)
        # well overdamped: the exponentials of the roots, slow root -w2/(a + b) without cancellation
        apb = a + b
        safe_b = np.where(split, b, 1.0)
        slow = np.exp(-(w2 / np.where(split, apb, 1.0)) * t)
        fast = np.exp(-apb * t)
        amb = w2 / np.where(split, apb, 1.0)  # a − b, cancellation-free
        g1_b = (slow - fast) / (2.0 * safe_b)
        g0_b = (apb * slow - amb * fast) / (2.0 * safe_b)
        dg1_b = (apb * fast - amb * slow) / (2.0 * safe_b)
    g1 = np.where(split, g1_b, g1_a)
    g0 = np.where(split, g0_b, g0_a)
    dg1 = np.where(split, dg1_b, dg1_a)
    return FreeResponse(g0, g1, -w2 * g1, dg1)


def damped_free(omega: np.ndarray, zeta: np.ndarray, t: np.ndarray) -> FreeResponse:
    """Free response of ``ẍ + 2ζω ẋ + ω² x = 0``: under-, critically and over-damped alike.

    With ``a = ζω`` and ``b² = a² − ω² = ω²(ζ − 1)(ζ + 1)`` (computed in that
    product form, so ζ = 1 ± 1e-15 keeps its digits):

    * ``b² < 0`` or ``b·t ≤ 1``: ``g1 = e^{−at}·t·S``, ``g0 = e^{−at}(C + a·t·S)``,
      ``ġ1 = e^{−at}(C − a·t·S)`` with ``C, S = cos, sinc`` of ``|b|t`` (under-damped)
      or ``cosh, sinhc`` (over-damped); both tend to ``e^{−at}(1 + at)`` etc. at
      ζ = 1, continuously from either side.
    * ``b·t > 1``: the roots ``λ_s = −ω²/(a + b)`` (slow, without the cancellation
      of ``−a + b`` at large ζ) and ``λ_f = −(a + b)``:
      ``g1 = (e^{λ_s t} − e^{λ_f t})/(2b)``,
      ``g0 = ((a + b) e^{λ_s t} − (a − b) e^{λ_f t})/(2b)`` with ``a − b = ω²/(a + b)``.

    Always ``ġ0 = −ω² g1``.

    Parameters
    ----------
    omega : array_like
        Undamped frequency ω ≥ 0.
    zeta : array_like
        Damping ratio ζ ≥ 0 (1e8 is fine).
    t : array_like
        Time, t ≥ 0.

    Returns
    -------
    FreeResponse
        ``(g0, g1, dg0, dg1)``, broadcast shape of the inputs.

    See Also
    --------
    damped_free_rate : the same with the decay rate instead of ζ (for ω = 0 with damping).
    """
    omega, zeta = np.asarray(omega, dtype=float), np.asarray(zeta, dtype=float)
    return _damped(zeta * omega, omega * omega * ((zeta - 1.0) * (zeta + 1.0)), omega * omega, t)


def damped_free_rate(omega: np.ndarray, gamma: np.ndarray, t: np.ndarray) -> FreeResponse:
    """Free response of ``ẍ + 2γ ẋ + ω² x = 0`` (γ = ζω), valid at ω = 0.

    Same forms as :func:`damped_free` with ``a = γ`` and ``b² = (γ − ω)(γ + ω)``.
    At ω = 0 and γ > 0 (a rigid mode with mass-proportional damping)
    ``g1 = (1 − e^{−2γt})/(2γ)`` and ``g0 = 1``.

    Parameters
    ----------
    omega : array_like
        Undamped frequency ω ≥ 0.
    gamma : array_like
        Half the damping rate, γ ≥ 0.
    t : array_like
        Time, t ≥ 0.

    Returns
    -------
    FreeResponse
    """
    omega, gamma = np.asarray(omega, dtype=float), np.asarray(gamma, dtype=float)
    return _damped(gamma, (gamma - omega) * (gamma + omega), omega * omega, t)
