"""The forms of a frequency response engineers read, from receptances of the accurate route.

Given receptances ``H(out, in)`` [m/N] of :mod:`numeric.frf.response` on a grid ω [rad/s]:

=========================  ==================================  ============
form                        value                               SI unit
=========================  ==================================  ============
receptance                  ``H``                               m/N
mobility                    ``iω H``                            (m/s)/N
accelerance                 ``−ω² H``                           (m/s^2)/N
dynamic stiffness           ``1 / H``                           N/m
transmissibility            ``Σ_a (k_a + iω c_a) H(out, a)``    1
relative transmissibility   ``ω² Σ_a m_a H(out, a)``            1
=========================  ==================================  ============

Transmissibility is the absolute motion of the output per motion of the base,
``X_out / X_g = Ẍ_out / Ẍ_g``: with relative coordinates ``z = x − x_g``, ``M ẍ + C ẋ + K x =
(K 1 + C 1 d/dt) x_g``, so it is the sum over the base's couplings ``k_a = (K 1)_a``,
``c_a = (C 1)_a`` (wall springs and dashpots, Rayleigh ``αm + βK1``, modal damping) of
receptances — no ``1 − (...)`` that cancels where the isolation is good. Relative transmissibility
``Z_out / X_g = ω² Σ_a m_a H(out, a)`` (``M z̈ + C ż + K z = −M 1 ẍ_g``) is equally free of
cancellation where it is small (low frequency); the two differ by exactly 1.
"""

from __future__ import annotations

import numpy as np

#: Form -> (SI unit, what the ratio is, whether the input is the base).
FORMS = {
    "receptance": ("m/N", "X_{out} / F_{in}", False),
    "mobility": ("(m/s)/N", "V_{out} / F_{in}", False),
    "accelerance": ("(m/s^2)/N", "A_{out} / F_{in}", False),
    "dynamic-stiffness": ("N/m", "F_{in} / X_{out}", False),
    "transmissibility": ("1", "X_{out} / X_{g} (absolute)", True),
    "relative-transmissibility": ("1", "Z_{out} / X_{g} (relative to the base)", True),
}
#: The SI numerator and denominator of each form (for output units).
RATIO = {"receptance": ("m", "N"), "mobility": ("m/s", "N"), "accelerance": ("m/s^2", "N"),
         "dynamic-stiffness": ("N", "m"), "transmissibility": ("1", "1"), "relative-transmissibility": ("1", "1")}


def from_receptance(form: str, omega: np.ndarray, H: np.ndarray) -> np.ndarray:
    """A force-input form from the receptance ``H`` (shape (W,)) on ``omega`` [rad/s], shape (W,)."""
    if form == "receptance":
        return H.copy()
    if form == "mobility":
        return 1j * omega * H
    if form == "accelerance":
        return -(omega * omega) * H
    if form == "dynamic-stiffness":
        return 1.0 / H
    raise ValueError(f"not a force-input form: {form!r}")


def ground_couplings(el) -> tuple[np.ndarray, np.ndarray]:
    """``(K 1, C 1)``: the stiffness and damping joining each mass to the base, shape (N,) each
    (internal elements cancel exactly: each adds and subtracts the same number)."""
    from .state_space import damping_of, stamp

    n = el.n
    K = stamp(n, el.spring_ends, el.stiffness)
    ones = np.ones(n)
    return np.asarray(K @ ones).reshape(-1), np.asarray(damping_of(el, K) @ ones).reshape(-1)


def transmissibility(omega: np.ndarray, H_cols: dict[int, np.ndarray], k1: np.ndarray, c1: np.ndarray) -> np.ndarray:
    """``Σ_a (k_a + iω c_a) H(out, a)`` over the masses ``a`` in ``H_cols`` (their receptances to the output)."""
    out = np.zeros(omega.shape[0], dtype=complex)
    for a, Ha in H_cols.items():
        out += (k1[a] + 1j * omega * c1[a]) * Ha
    return out


def relative_transmissibility(omega: np.ndarray, H_cols: dict[int, np.ndarray], masses: np.ndarray) -> np.ndarray:
    """``ω² Σ_a m_a H(out, a)`` over every mass ``a``."""
    acc = np.zeros(omega.shape[0], dtype=complex)
    for a, Ha in H_cols.items():
        acc += masses[a] * Ha
    return (omega * omega) * acc


def decibels(values: np.ndarray) -> np.ndarray:
    """``20 log10 |value|`` (dB re 1 of the value's unit); -inf at 0."""
    with np.errstate(divide="ignore"):
        return 20.0 * np.log10(np.abs(values))


__all__ = ["FORMS", "RATIO", "from_receptance", "ground_couplings", "transmissibility", "relative_transmissibility",
           "decibels"]
