"""The exact solution of an undamped linear chain, mode by mode.

In mass-weighted modal coordinates each mode is ``q̈ = -ω² q``, solved by

    q(t) = q0 cos(ωt) + q̇0 · t·sinc(ωt)          (t·sinc(ωt) = sin(ωt)/ω, = t at ω = 0)
    q̇(t) = -q0 · ω²t·sinc(ωt) + q̇0 cos(ωt)

which never divides by ω: a rigid-body mode (ω = 0 exactly, by structure)
is the uniform drift ``x_cm(0) + v_cm·t`` with no special case.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .spectrum import Spectrum


def tsinc(omega: np.ndarray, t: np.ndarray) -> np.ndarray:
    """``sin(ω t)/ω`` written as ``t·sinc(ωt)``: finite and exact at ω = 0."""
    return t * np.sinc(omega * t / np.pi)


@dataclass(frozen=True)
class ModalSolution:
    """Exact trajectory from initial displacements and velocities.

    Parameters
    ----------
    spectrum : Spectrum
    x0, v0 : ndarray, shape (N,) or (N, B)
    """

    spectrum: Spectrum
    q0: np.ndarray = field(repr=False)
    p0: np.ndarray = field(repr=False)

    @classmethod
    def from_initial(cls, spectrum: Spectrum, x0: np.ndarray, v0: np.ndarray) -> "ModalSolution":
        r = np.sqrt(spectrum.masses)
        r = r.reshape(r.shape + (1,) * (np.ndim(x0) - 1))
        E = spectrum.vectors
        return cls(spectrum, np.tensordot(E.T, r * x0, axes=1), np.tensordot(E.T, r * v0, axes=1))

    def at(self, t) -> tuple[np.ndarray, np.ndarray]:
        """Positions and velocities at times ``t``.

        Parameters
        ----------
        t : float or ndarray, shape (S,)

        Returns
        -------
        x, v : ndarray, shape (N, ...) for scalar t, or (S, N, ...) for an array of times
        """
        t = np.asarray(t, dtype=float)
        w = self.spectrum.omega
        extra = (1,) * (self.q0.ndim - 1)
        tt = t.reshape(t.shape + (1,) + extra)
        ww = w.reshape(w.shape + extra)
        c = np.cos(ww * tt)
        s = tsinc(ww, tt)
        q = self.q0 * c + self.p0 * s
        p = -self.q0 * (ww**2) * s + self.p0 * c
        E = self.spectrum.vectors
        r = np.sqrt(self.spectrum.masses).reshape((-1,) + extra)
        x = np.moveaxis(np.tensordot(E, q, axes=([1], [t.ndim])), 0, t.ndim) / r
        v = np.moveaxis(np.tensordot(E, p, axes=([1], [t.ndim])), 0, t.ndim) / r
        return x, v
