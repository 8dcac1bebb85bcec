"""A one-sided input PSD G(f) [units²/Hz] given at breakpoints, and its exact integrals.

Between breakpoints G is a power law (a straight line on log–log axes, the convention of random
vibration test specifications: ``G = G_a (f/f_a)^α``) or, with ``interpolation="linear"``, a
straight line on linear axes; zero outside ``[f_0, f_last]``. The integrals the modal response
needs, ``J(λ) = ∫ G(f) / (i2πf − λ) df`` for a pole λ in the open left half plane, are evaluated
in closed form per segment (logarithms, and Gauss's hypergeometric 2F1 for a non-integer slope)
in mpmath at :data:`DPS` digits — no frequency sampling, no quadrature error.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ..errors import RunRefused

#: mpmath digits of the segment integrals (the closed forms subtract values at the two ends).
DPS = 40
#: Most breakpoints accepted.
MAX_POINTS = 10_000
INTERPOLATIONS = ("loglog", "linear")


@dataclass(frozen=True)
class InputPSD:
    """A validated one-sided PSD.

    Attributes
    ----------
    f : ndarray, shape (K,)
        Breakpoint frequencies [Hz], strictly increasing, > 0 (>= 0 for linear interpolation).
    G : ndarray, shape (K,)
        One-sided PSD at ``f`` [SI units²/Hz], >= 0 (> 0 for log–log interpolation).
    interpolation : str
        ``"loglog"`` or ``"linear"``.
    """

    f: np.ndarray = field(repr=False)
    G: np.ndarray = field(repr=False)
    interpolation: str = "loglog"

    @classmethod
    def checked(cls, f, G, interpolation: str = "loglog", what: str = "input PSD") -> "InputPSD":
        """An InputPSD from arrays, or :class:`RunRefused` in one line naming ``what``."""
        if interpolation not in INTERPOLATIONS:
            raise RunRefused(f"{what}: interpolation {interpolation!r}; accepted: {', '.join(INTERPOLATIONS)}",
                             quantity="interpolation")
        try:
            f = np.asarray(f, dtype=float).reshape(-1)
            G = np.asarray(G, dtype=float).reshape(-1)
        except (TypeError, ValueError):
            raise RunRefused(f"{what}: not numbers; accepted: frequencies [Hz] and PSD values", quantity="input") from None
        accepted = ("at least 2 rows of frequency [Hz] strictly increasing and PSD >= 0, finite"
                    + (", both > 0 for log-log interpolation" if interpolation == "loglog" else ""))
        if f.shape != G.shape or not 2 <= f.shape[0] <= MAX_POINTS:
            raise RunRefused(f"{what}: {f.shape[0]} frequencies and {G.shape[0]} values; accepted: {accepted} "
                             f"(at most {MAX_POINTS})", quantity="input")
        if not (np.all(np.isfinite(f)) and np.all(np.isfinite(G))) or np.any(G < 0) or np.any(f < 0):
            raise RunRefused(f"{what}: a value that is negative or not finite; accepted: {accepted}", quantity="input")
        if not np.all(np.diff(f) > 0):
            r = int(np.argmax(~(np.diff(f) > 0))) + 1
            raise RunRefused(f"{what}: frequencies not strictly increasing at row {r + 1} ({f[r]:g} Hz after "
                             f"{f[r - 1]:g} Hz); accepted: {accepted}", quantity="input")
        if interpolation == "loglog" and (np.any(f <= 0) or np.any(G <= 0)):
            raise RunRefused(f"{what}: a zero frequency or PSD value cannot be interpolated on log-log axes; "
                             f"accepted: {accepted}, or interpolation 'linear'", quantity="input")
        if not np.any(G > 0):
            raise RunRefused(f"{what}: the PSD is 0 everywhere; accepted: {accepted}", quantity="input")
        return cls(f, G, interpolation)

    @property
    def slopes(self) -> np.ndarray:
        """Log–log slopes α of the segments, shape (K-1,) (``loglog`` only)."""
        return np.log(self.G[1:] / self.G[:-1]) / np.log(self.f[1:] / self.f[:-1])

    def value(self, f) -> np.ndarray:
        """G at frequencies ``f`` [Hz] (0 outside the breakpoints), shape of f."""
        f = np.asarray(f, dtype=float)
        out = np.zeros(f.shape)
        inside = (f >= self.f[0]) & (f <= self.f[-1])
        x = f[inside]
        if self.interpolation == "linear":
            out[inside] = np.interp(x, self.f, self.G)
        else:
            out[inside] = np.exp(np.interp(np.log(x), np.log(self.f), np.log(self.G)))
        return out

    def mean_square(self) -> float:
        """``∫ G df`` over the band (exact per segment): the input's mean square."""
        a, b, Ga, Gb = self.f[:-1], self.f[1:], self.G[:-1], self.G[1:]
        if self.interpolation == "linear":
            return float(np.sum(0.5 * (Ga + Gb) * (b - a)))
        alpha = self.slopes
        out = 0.0
        for fa, fb, ga, al in zip(a, b, Ga, alpha):
            if abs(al + 1) < 1e-12:
                out += ga * fa * math.log(fb / fa)
            else:
                out += ga * fa * math.expm1((al + 1) * math.log(fb / fa)) / (al + 1)
        return out

    def pole_integrals(self, poles: np.ndarray) -> np.ndarray:
        """``J(λ) = ∫ G(f) / (i2πf − λ) df`` for each pole (Re λ < 0), shape (P,), complex."""
        import mpmath

        poles = np.asarray(poles, dtype=complex).reshape(-1)
        out = np.empty(poles.shape[0], dtype=complex)
        with mpmath.workdps(DPS):
            two_pi_i = 2 * mpmath.pi * 1j
            segs = self._segments(mpmath)
            for r, lam in enumerate(poles.tolist()):
                z = mpmath.mpc(lam.real, lam.imag) / two_pi_i  # the pole in the f plane (Im z > 0)
                total = mpmath.mpc(0)
                for seg in segs:
                    total += seg(z)
                out[r] = complex(total / two_pi_i)
        return out

    def _segments(self, mpmath):
        """One function ``z -> ∫_a^b G(f)/(f − z) df`` per segment, in mpmath."""
        mp = mpmath.mpf
        segs = []
        for j in range(self.f.shape[0] - 1):
            a, b = mp(float(self.f[j])), mp(float(self.f[j + 1]))
            ga, gb = mp(float(self.G[j])), mp(float(self.G[j + 1]))
            if self.interpolation == "linear":
                q = (gb - ga) / (b - a)
                p = ga - q * a
                segs.append(lambda z, a=a, b=b, p=p, q=q: q * (b - a) + (p + q * z) * _log_ratio(mpmath, b - z, a - z))
                continue
            alpha = mpmath.log(gb / ga) / mpmath.log(b / a)
            scale = ga / a**alpha  # G = scale * f^alpha
            segs.append(lambda z, a=a, b=b, s=scale, al=alpha: s * _power_segment(mpmath, a, b, al, z))
        return segs


def _log_ratio(mpmath, u, v):
    """``log u − log v`` for u, v in the open lower half plane (no branch cut between them)."""
    return mpmath.log(u) - mpmath.log(v)


def _power_segment(mpmath, a, b, alpha, z):
    """``∫_a^b f^α / (f − z) df`` (0 < a < b, Im z > 0) in closed form."""
    if abs(alpha) < mpmath.mpf(10) ** (-30):
        return _log_ratio(mpmath, b - z, a - z)
    if abs(alpha + 1) < mpmath.mpf(10) ** (-30):
        return (_log_ratio(mpmath, b - z, a - z) - mpmath.log(b / a)) / z

    def F(x):  # an antiderivative for any α ≠ −1: −x^{α+1}/((α+1) z) · 2F1(1, α+1; α+2; x/z)
        return -x ** (alpha + 1) / ((alpha + 1) * z) * mpmath.hyp2f1(1, alpha + 1, alpha + 2, x / z)

    return F(b) - F(a)


__all__ = ["InputPSD", "DPS", "INTERPOLATIONS"]
