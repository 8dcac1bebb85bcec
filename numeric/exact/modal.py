"""The exact solution of an undamped linear chain, mode by mode.

In mass-weighted modal coordinates each mode is ``q̈ = -ω² q``, solved by

    q(t) = q0 cos(ωt) + q̇0 · t·sinc(ωt)          (t·sinc(ωt) = sin(ωt)/ω, = t at ω = 0)
    q̇(t) = -q0 · ω²t·sinc(ωt) + q̇0 cos(ωt)

which never divides by ω: a rigid-body mode (ω = 0 exactly, by structure)
is the uniform drift ``x_cm(0) + v_cm·t`` with no special case. The elastic
modes are orthogonal to the rigid ones to roundoff (see
:mod:`numeric.modes.spectrum`), so they carry no momentum and do not move the
centre of mass of a free piece.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property, lru_cache

import numpy as np

from .special import tsinc
from ..modes.spectrum import Spectrum

__all__ = ["ModalSolution", "cos_tsinc", "tsinc"]


#: Below this many times the direct evaluation is as cheap as the split one.
_SPLIT_MIN = 64


_EPS = float(np.finfo(float).eps)


@lru_cache(maxsize=8)
def _steps(s: int) -> np.ndarray:
    """0, 1, …, s−1 as floats (read-only; a grid's length repeats across runs)."""
    out = np.arange(s, dtype=float)
    out.flags.writeable = False
    return out


def _uniform_split(t: np.ndarray) -> tuple[int, float] | None:
    """``(B, h)`` when t (S,) is a uniform grid ``t_0 + i·h`` to rounding (the simulation's grid)."""
    s = t.shape[0]
    if s < _SPLIT_MIN:
        return None
    t0, t1 = float(t[0]), float(t[-1])
    h = (t1 - t0) / (s - 1)
    if not h > 0:
        return None
    dev = t - _steps(s) * h
    dev -= t0
    if max(dev.max(), -dev.min()) > 4.0 * _EPS * max(abs(t0), abs(t1)):
        return None
    return int(np.sqrt(s)) + 1, float(h)


def _tsinc_table(tau: np.ndarray, w: np.ndarray, sin: np.ndarray) -> np.ndarray:
    """``τ·sinc(ωτ) = sin(ωτ)/ω`` (N, T) from sines (N, T), ``τ`` (T,) itself where ω = 0 (rigid modes)."""
    zero = w == 0.0
    if not zero.any():
        return sin / w[:, None]
    out = sin / np.where(zero, 1.0, w)[:, None]
    out[zero] = tau
    return out


def cos_tsinc(t: np.ndarray, w: np.ndarray) -> np.ndarray:
    """``[cos(ωt); t·sinc(ωt)]``, shape (2N, S) (modes along the rows), for t (S,) and ω (N,) ≥ 0.

    ``t·sinc(ωt) = sin(ωt)/ω``, and exactly ``t`` for a rigid mode (ω = 0 by structure): the
    two functions of the modal solution. On a uniform grid ``t_i = t_0 + i·h`` (the
    simulation's grid) the S × N pairs come from two short tables by the angle-addition
    formulas, ``t_i = a + b`` with ``a = t_{jB}``, ``b = r·h``, ``i = jB + r``, B ≈ √S:

        cos(ωt)     = cos(ωa) cos(ωb) − sin(ωa) sin(ωb)
        t·sinc(ωt)  = [a·sinc(ωa)] cos(ωb) + cos(ωa) [b·sinc(ωb)]

    (the second stays exact at ω = 0: a + b). That is 2√S·N sine/cosine pairs and a few S·N
    multiplications instead of S·N pairs. Each phase is rounded as the direct ``ω t_i`` is and
    each entry is a sum of two products, so the result stays within a few ulps of the direct
    one (absolute, in units of 1 and of t). Other grids take the direct route.
    """
    cs, s = _cos_tsinc_padded(t, w)
    return cs[:, :s]


def _cos_tsinc_padded(t: np.ndarray, w: np.ndarray) -> tuple[np.ndarray, int]:
    """:func:`cos_tsinc` as a C-contiguous (2N, P) array whose first ``s = t.shape[0]`` columns are the
    times ``t`` (P ≥ s: a uniform grid's last block runs on past the last time), and ``s``."""
    n, s = w.shape[0], t.shape[0]
    split = _uniform_split(t)
    if split is None:
        ph = np.multiply.outer(w, t)
        z = np.exp(1j * ph)
        return np.concatenate((z.real, _tsinc_table(t, w, z.imag))), s
    b, h = split
    blocks = -(-s // b)
    # the block starts a = t_{jB} and the offsets r·h in one row of times: one cos, one sin, one table
    ab = np.concatenate((t[::b], _steps(s)[:b] * h))                  # (blocks + B,)
    ph = np.multiply.outer(w, ab)
    c, sn = np.cos(ph), np.sin(ph)
    ts = _tsinc_table(ab, w, sn)
    hc, tc = c[:, :blocks, None], c[:, None, blocks:]                  # (N, blocks, 1), (N, 1, B)
    out = np.empty((2, n, blocks, b))
    np.multiply(hc, tc, out=out[0])
    out[0] -= sn[:, :blocks, None] * sn[:, None, blocks:]  # the sines themselves: ω² would overflow at huge ω
    np.multiply(ts[:, :blocks, None], tc, out=out[1])
    out[1] += hc * ts[:, None, blocks:]
    return out.reshape(2 * n, blocks * b), s


@dataclass(frozen=True)
class ModalSolution:
    """Exact trajectory from initial displacements and velocities.

    Attributes
    ----------
    spectrum : Spectrum
    q0, p0 : ndarray, shape (N,) or (N, B)
        Initial modal coordinates and velocities (mass-weighted).
    """

    spectrum: Spectrum
    q0: np.ndarray = field(repr=False)
    p0: np.ndarray = field(repr=False)

    @classmethod
    def from_initial(cls, spectrum: Spectrum, x0: np.ndarray, v0: np.ndarray) -> "ModalSolution":
        """The solution through displacements ``x0`` and velocities ``v0``, shape (N,) or (N, B)."""
        r = spectrum.root_masses
        E = spectrum.vectors
        if np.ndim(x0) == 1:  # one state: plain matrix-vector products
            return cls(spectrum, E.T @ (r * x0), E.T @ (r * v0))
        r = r.reshape(r.shape + (1,) * (np.ndim(x0) - 1))
        return cls(spectrum, np.tensordot(E.T, r * x0, axes=1), np.tensordot(E.T, r * v0, axes=1))

    def _modal(self, t):
        """Modal coordinates, velocities and ω reshaped for broadcasting against t of shape (S,)."""
        t = np.asarray(t, dtype=float)
        w = self.spectrum.omega
        extra = (1,) * (self.q0.ndim - 1)
        tt = t.reshape(t.shape + (1,) + extra)
        ww = w.reshape(w.shape + extra)
        phase = ww * tt
        z = np.exp(1j * phase)  # cos and sin in one pass
        c = z.real
        # t·sinc(ωt) = t·sin(ωt)/(ωt), = t where ωt = 0 (ω = 0 exactly for rigid modes)
        with np.errstate(invalid="ignore", divide="ignore"):
            s = np.where(phase != 0.0, z.imag / np.where(phase != 0.0, phase, 1.0), 1.0) * tt
        q = self.q0 * c + self.p0 * s
        p = -self.q0 * (ww**2) * s + self.p0 * c
        return t, q, p, ww

    def _physical(self, t: np.ndarray, y: np.ndarray) -> np.ndarray:
        """``M^-1/2 E y`` with the mode axis of y (just after the time axes) contracted."""
        extra = (1,) * (self.q0.ndim - 1)
        E = self.spectrum.vectors
        r = np.sqrt(self.spectrum.masses).reshape((-1,) + extra)
        if self.q0.ndim == 1 and t.ndim <= 1:  # (S, N) or (N,): one matrix product
            return (y @ E.T) / r
        return np.moveaxis(np.tensordot(E, y, axes=([1], [t.ndim])), 0, t.ndim) / r

    def at(self, t) -> tuple[np.ndarray, np.ndarray]:
        """Positions and velocities at times ``t``.

        Parameters
        ----------
        t : float or ndarray, shape (S,)

        Returns
        -------
        x, v : ndarray, shape (N, ...) for scalar t, or (S, N, ...) for an array of times
        """
        if self.q0.ndim == 1 and np.ndim(t) == 1:
            return self._trajectory(np.asarray(t, dtype=float))
        t, q, p, _ = self._modal(t)
        return self._physical(t, q), self._physical(t, p)

    @cached_property
    def _maps(self) -> np.ndarray:
        """``G`` (2N, 2N) with ``[x v] = [cos(ωt) | t·sinc(ωt)] G`` for one initial state.

        Rows 0..N-1 multiply cos(ω_j t): ``q0_j e_jᵀ/√m`` into x and ``p0_j e_jᵀ/√m`` into v;
        rows N..2N-1 multiply t·sinc(ω_j t): ``p0_j e_jᵀ/√m`` into x and ``-ω_j² q0_j e_jᵀ/√m`` into v.
        """
        Et = self.spectrum.shapes_t
        q0, p0, w2 = self.q0[:, None], self.p0[:, None], self.spectrum.omega2[:, None]
        n, m = Et.shape
        g = np.empty((2 * n, 2 * m))
        np.multiply(q0, Et, out=g[:n, :m])
        np.multiply(p0, Et, out=g[:n, m:])
        g[n:, :m] = g[:n, m:]
        np.multiply(-w2 * q0, Et, out=g[n:, m:])
        return g

    def _trajectory(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """x, v of shape (S, N) at times t (S,): the cos and t·sinc of :func:`cos_tsinc` and one matrix product.

        t·sinc(ωt) = sin(ωt)/ω for ω > 0; rigid modes (ω = 0 exactly, by structure) get t.
        """
        cs, s = _cos_tsinc_padded(t, self.spectrum.omega)  # (2N, P), P ≥ S, contiguous
        n = self.spectrum.omega.shape[0]
        g = self._maps
        # x and v each as one product with the (contiguous) table: (P, N) blocks whose first S rows are
        # contiguous, so a recorder copies them in one pass
        return (cs.T @ g[:, :n])[:s], (cs.T @ g[:, n:])[:s]

    def acceleration_at(self, t) -> np.ndarray:
        """Accelerations ``ẍ = -M^-1/2 E Ω² q`` at times ``t`` (analytic, no differencing).

        Parameters
        ----------
        t : float or ndarray, shape (S,)

        Returns
        -------
        a : ndarray, shape as ``x`` from :meth:`at`
        """
        t, q, _, ww = self._modal(t)
        return self._physical(t, -(ww**2) * q)

    @property
    def energy(self) -> np.ndarray:
        """The conserved energy ``½ Σ (q̇0² + ω² q0²)``, shape () or (B,)."""
        w2 = self.spectrum.omega2.reshape((-1,) + (1,) * (self.q0.ndim - 1))
        return 0.5 * np.sum(self.p0**2 + w2 * self.q0**2, axis=0)
