"""Complex values past float64's range as a mantissa and a binary exponent (``value = mantissa · 2**expo``):
the frequency response below 2.2e-308 keeps its digits and its phase (the open chain's sweep and the
extended-precision solves carry them; the response prints |H| below the range as 0 with a note).
"""

from __future__ import annotations

import numpy as np


def split(H: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Float64 H as ``(mantissa, expo)`` (exact: a power of two taken out; 0 and non-finite kept)."""
    a = np.maximum(np.abs(H.real), np.abs(H.imag))
    ok = np.isfinite(a) & (a > 0)
    expo = np.where(ok, np.frexp(np.where(ok, a, 1.0))[1], 0).astype(np.int64)
    with np.errstate(all="ignore"):
        return np.ldexp(H.real, -expo) + 1j * np.ldexp(H.imag, -expo), expo


def unscale(mantissa: np.ndarray, expo: np.ndarray) -> np.ndarray:
    """``mantissa · 2**expo`` as float64 complex, shape (W,) (subnormal or 0 below the range, inf above)."""
    expo = np.asarray(expo, dtype=np.int64)
    with np.errstate(all="ignore"):
        return np.ldexp(mantissa.real, expo) + 1j * np.ldexp(mantissa.imag, expo)


def mp_split(value, mpmath) -> tuple[complex, int]:
    """An mpmath complex as ``(mantissa, k)``, ``value = mantissa · 2**k``, the mantissa's larger part in
    [1/2, 1) (0: ``(0, 0)``)."""
    value = mpmath.mpc(value)
    a = max(abs(value.real), abs(value.imag))
    if a == 0:
        return 0j, 0
    k = int(mpmath.frexp(a)[1])
    return complex(mpmath.ldexp(value.real, -k), mpmath.ldexp(value.imag, -k)), k


__all__ = ["split", "unscale", "mp_split"]
