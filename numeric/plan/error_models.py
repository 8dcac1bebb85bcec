"""Closed-form error models: what a step ``h`` costs in accuracy, before running anything.

Linear chains: exact per-mode propagators
-----------------------------------------
On an undamped linear chain every one-step method acts on each normal mode
``q̈ = −ω²q`` separately, through a 2×2 matrix that depends only on
``z = ωh``. :class:`OscillatorResponse` obtains that matrix *from the
integrator itself*: its step kernel is applied once to the scalar
oscillator with arrays of polynomials in ``z`` (step 1, acceleration
``−z²x``), so the entries come out as exact polynomials in ``z`` built from
the method's own coefficient table — no fitted or transcribed constants.
From the polynomials:

* the numerical rotation angle per step ``θ`` (``cos θ = trace/(2ρ)``,
  ``ρ = √det``), through the phase defect ``δ = θ − z`` computed without
  cancellation from the series ``trace/2 − cos z`` whose first ``p/2 + 1``
  terms vanish (checked: a table whose declared order is wrong raises);
* the amplitude factor per step ``ρ`` (exactly 1 for symplectic methods;
  ``1 − z⁶/72 + …`` for RK4);
* the shape distortion ``r = z·P_xv/(ρ sin θ) − 1`` (the numerical ellipse
  against the exact circle; bounded, does not grow).

:class:`LinearChainModel` then writes the numerical solution in closed form,
mode by mode (``P^i = ρ^i (cos iθ I + sin iθ J)``), and subtracts the exact
one with sum-to-product formulas (``cos iθ − cos iz = −2 sin(iψ) sin(iδ/2)``),
so the *position error at every step* is evaluated to roundoff accuracy
(:meth:`LinearChainModel.error`). This is not an approximation of the
method: up to roundoff it is exactly what running it produces. Where that
evaluation would be too long (many steps times many modes) the envelope
(:meth:`LinearChainModel.envelope`) bounds it from the same quantities:

    |e_j(t)| ≤ A_j (2 sin(min(|δ_j| t/h, π)/2) + |ρ_j^{t/h} − 1|) + distortion_j,

with ``A_j`` the modal amplitude of the initial condition, summed over
modes with the mode shapes' weights. For small ``z`` the phase defect is
``δ ≈ C z^{p+1}`` (:attr:`OscillatorResponse.leading_constant`), e.g.
``C = 1/24`` for velocity Verlet, which gives the textbook
``ω³h²t/24``.

Roundoff
--------
Each step adds rounding errors of relative size ε per stage; they
accumulate like a random walk: :func:`roundoff_floor` =
``ROUNDOFF_GAIN · ε · A · √(stages · steps)``, with ``A`` the largest
amplitude. The gain was measured on the bundled scenes (see bench).

Adaptive methods and nonlinear scenes: pilot-calibrated power laws
------------------------------------------------------------------
No closed form exists for an error-controlled solver's global error or for
a nonlinear scene, so :class:`PowerLaw` fits ``error = C·s^α`` (``s`` the
tolerance or the step) through two cheap pilot runs and scales it linearly
with the horizon (phase errors grow linearly in time). This is documented
as a calibrated model, not a closed form.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property

import numpy as np

from ..io.array_record import array_record
from ..integrators.base import Integrator, Problem

EPS = float(np.finfo(float).eps)

#: Rounding growth constant of :func:`roundoff_floor`. Measured on the seed scene (BM4, BM6, KL8, RK4 at
#: 5e3–2e5 steps, against the extended-precision reference): 0.6–10; 3 covers all but the worst case.
ROUNDOFF_GAIN = 3.0

#: Number of Taylor terms of cos z kept beyond the propagator's degree (enough for z ≤ 8).
_EXTRA_TERMS = 60


class _Poly:
    """A polynomial in ``z`` with float coefficients; just enough arithmetic to run a step kernel.

    Kernels combine arrays with floats by ``+``, ``-``, ``*``; on object
    arrays NumPy applies these to the elements, so a kernel run on arrays of
    ``_Poly`` returns the propagator's entries as polynomials.
    """

    __slots__ = ("c",)

    def __init__(self, coef):
        self.c = np.atleast_1d(np.asarray(coef, dtype=float))

    @staticmethod
    def _coef(other) -> np.ndarray:
        return other.c if isinstance(other, _Poly) else np.array([float(other)])

    def __add__(self, other):
        a, b = self.c, self._coef(other)
        out = np.zeros(max(a.shape[0], b.shape[0]))
        out[: a.shape[0]] += a
        out[: b.shape[0]] += b
        return _Poly(out)

    __radd__ = __add__

    def __neg__(self):
        return _Poly(-self.c)

    def __sub__(self, other):
        return self + (-_Poly(self._coef(other)))

    def __rsub__(self, other):
        return _Poly(self._coef(other)) + (-self)

    def __mul__(self, other):
        return _Poly(np.convolve(self.c, self._coef(other)))

    __rmul__ = __mul__


def _series(coef: np.ndarray, z: np.ndarray) -> np.ndarray:
    """Evaluate ``Σ c_k z^k`` (Horner) for an array z."""
    out = np.zeros_like(z, dtype=float)
    for c in coef[::-1]:
        out = out * z + c
    return out


def _cos_taylor(n: int) -> np.ndarray:
    """Taylor coefficients of cos z up to z^(n-1)."""
    c = np.zeros(n)
    for k in range(0, n, 2):
        c[k] = (-1.0) ** (k // 2) / math.factorial(k)
    return c


@array_record
class OscillatorResponse:
    """A one-step method's exact action on ``q̈ = −ω²q``, as polynomials in ``z = ωh``.

    The 2×2 step map on ``(x, v)`` is ``[[xx, h·xv], [vx/h, vv]]`` with
    ``xx, xv, vx, vv`` polynomials in ``z`` (coefficient arrays, ascending).

    Attributes
    ----------
    name : str
        The method's name (messages only).
    order : int
    symplectic : bool
    stages : float
        Force evaluations per step.
    stability_limit : float
        Largest stable ``z`` (from the integrator).
    xx, xv, vx, vv : ndarray
        Coefficients of the propagator entries.
    """

    name: str
    order: int
    symplectic: bool
    stages: float
    stability_limit: float
    xx: np.ndarray
    xv: np.ndarray
    vx: np.ndarray
    vv: np.ndarray

    @classmethod
    def from_integrator(cls, integrator: Integrator) -> "OscillatorResponse":
        """Run one step of ``integrator`` on the scalar oscillator with polynomial entries.

        Raises
        ------
        ValueError
            If the method is not a finite-order step method (e.g. an exact propagator).
        """
        if not math.isfinite(integrator.order):
            raise ValueError(f"{integrator.name}: an exact propagator has no truncation error model")
        z2 = _Poly([0.0, 0.0, 1.0])

        def acc(x):
            return -(x * z2)

        problem = Problem(acc)
        x0 = np.empty((1, 2), dtype=object)
        v0 = np.empty((1, 2), dtype=object)
        x0[0, 0], x0[0, 1] = _Poly(1.0), _Poly(0.0)
        v0[0, 0], v0[0, 1] = _Poly(0.0), _Poly(1.0)
        a0 = acc(x0) if integrator.init_evals else None
        x, v, _ = integrator.kernel(problem, 1.0)(x0, v0, a0, 0)
        return cls(integrator.name, int(integrator.order), bool(integrator.symplectic),
                   float(integrator.evals_per_step), float(integrator.stability_limit),
                   x[0, 0].c, x[0, 1].c, v[0, 0].c, v[0, 1].c)

    def __post_init__(self):
        # self-check: the declared order must show in the polynomials
        scale = 1.0 + float(np.max(np.abs(self.trace_defect)))
        for what, raw in (("trace/2 - cos z", self._raw_trace_defect), ("det - 1", self._raw_det_defect)):
            low = raw[: self.order + 2]
            if np.max(np.abs(low), initial=0.0) > 1e-11 * scale:
                k = int(np.argmax(np.abs(low)))
                raise ValueError(f"{self.name}: declared order {self.order} but the z^{k} coefficient of "
                                 f"{what} is {low[k]:.3g} (should vanish)")

    # -- polynomial identities -------------------------------------------------------------
    @cached_property
    def _raw_trace_defect(self) -> np.ndarray:
        n = max(self.xx.shape[0], self.vv.shape[0]) + _EXTRA_TERMS
        t = np.zeros(n)
        t[: self.xx.shape[0]] += 0.5 * self.xx
        t[: self.vv.shape[0]] += 0.5 * self.vv
        return t - _cos_taylor(n)

    @cached_property
    def _raw_det_defect(self) -> np.ndarray:
        det = (_Poly(self.xx) * _Poly(self.vv) - _Poly(self.xv) * _Poly(self.vx)).c.copy()
        det[0] -= 1.0
        return det

    @cached_property
    def trace_defect(self) -> np.ndarray:
        """Coefficients of ``trace/2 − cos z``, the terms up to ``z^{p+1}`` set to their exact 0."""
        d = self._raw_trace_defect.copy()
        d[: self.order + 2] = 0.0
        return d

    @cached_property
    def det_defect(self) -> np.ndarray:
        """Coefficients of ``det − 1``: identically 0 for a symplectic method (a product of shears)."""
        if self.symplectic:
            return np.zeros(1)
        d = self._raw_det_defect.copy()
        d[: self.order + 2] = 0.0
        return d

    @property
    def leading_constant(self) -> float:
        """``C`` in the phase defect per step ``θ − z ≈ C z^{p+1}`` (Verlet: 1/24)."""
        # cos θ − cos z ≈ −z·δ  and, for non-symplectic methods, the 1/ρ correction
        # (−(det−1)/2 at order z^{p+2}) adds to the trace defect.
        k = self.order + 2
        d = self.trace_defect[k] - 0.5 * (self.det_defect[k] if self.det_defect.shape[0] > k else 0.0)
        return float(-d)

    # -- per-step quantities on arrays of z ------------------------------------------------
    def log_amplitude(self, z: np.ndarray) -> np.ndarray:
        """``ln ρ`` per step (0 for symplectic methods)."""
        z = np.asarray(z, dtype=float)
        if self.symplectic:
            return np.zeros_like(z)
        return 0.5 * np.log1p(_series(self.det_defect, z))

    def stable(self, z: np.ndarray) -> np.ndarray:
        """Whether ``z`` is inside the (contiguous) stability interval."""
        return np.asarray(z, dtype=float) < self.stability_limit

    def angle_defect(self, z: np.ndarray) -> np.ndarray:
        """``δ = θ − z``, the phase error per step, for stable z (NaN outside).

        ``cos θ − cos z = D`` with ``D = (trace/2 − cos z) + (trace/2)(1/ρ − 1)``
        known without cancellation; ``δ`` solves ``−2 sin(z + δ/2) sin(δ/2) = D``
        by fixed-point iteration from ``δ₀ = −D/sin z`` (a few steps reach
        roundoff) while ``|D| ≤ 1e-4``; for a larger defect ``acos`` on the
        branch nearest z is accurate and is used instead.
        """
        z = np.asarray(z, dtype=float)
        half_trace = 0.5 * (_series(self.xx, z) + _series(self.vv, z))
        D = _series(self.trace_defect, z)
        if not self.symplectic:
            D = D + half_trace * np.expm1(-self.log_amplitude(z))
        with np.errstate(invalid="ignore", divide="ignore"):
            delta = -D / np.sin(z)
            for _ in range(8):
                arg = -D / (2.0 * np.sin(z + 0.5 * delta))
                delta = 2.0 * np.arcsin(np.clip(arg, -1.0, 1.0))
            # a large defect: acos is accurate there (absolute error ε/sin θ ≪ |δ|)
            bad = ~np.isfinite(delta) | (np.abs(D) > 1e-4)
            if np.any(bad):
                c = np.clip(np.cos(z[bad]) + D[bad], -1.0, 1.0)
                a = np.arccos(c)
                zb = np.mod(z[bad], 2 * math.pi)
                th = np.where(np.abs(a - zb) <= np.abs(2 * math.pi - a - zb), a, 2 * math.pi - a)
                delta[bad] = th - zb
        delta = np.where(z == 0.0, 0.0, delta)
        return np.where(self.stable(z), delta, np.nan)

    def distortion(self, z: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``(s, r)``: the numerical map is ``ρ(cos θ I + sin θ J)`` with
        ``(J u)_x = s·x + (1 + r)·v/ω``; exact: ``s = r = 0``."""
        z = np.asarray(z, dtype=float)
        rho = np.exp(self.log_amplitude(z))
        theta = z + self.angle_defect(z)
        st = np.sin(theta)
        with np.errstate(invalid="ignore", divide="ignore"):
            s = (_series(self.xx, z) - _series(self.vv, z)) / (2.0 * rho * st)
            r = z * _series(self.xv, z) / (rho * st) - 1.0
        small = z < 1e-8
        return np.where(small, 0.0, s), np.where(small, 0.0, r)


@array_record
class LinearChainModel:
    """The initial condition of an undamped linear chain in modal coordinates.

    Attributes
    ----------
    omega : ndarray, shape (M,)
        Elastic angular frequencies (rigid modes dropped: every method here
        propagates them exactly, ``x + t v`` with zero force).
    shapes : ndarray, shape (N, M)
        ``M^-1/2 E``: physical displacement per unit modal coordinate.
    q0, g0 : ndarray, shape (M, B)
        Initial modal displacement and ``q̇0/ω`` (both in modal length units).
    """

    omega: np.ndarray
    shapes: np.ndarray
    q0: np.ndarray
    g0: np.ndarray

    @classmethod
    def from_spectrum(cls, spectrum, x0: np.ndarray, v0: np.ndarray) -> "LinearChainModel":
        """Project (x0, v0), shape (N,) or (N, B), on the elastic modes of a :class:`~numeric.modes.spectrum.Spectrum`."""
        x0 = np.asarray(x0, dtype=float)
        v0 = np.asarray(v0, dtype=float)
        if x0.ndim == 1:
            x0, v0 = x0[:, None], v0[:, None]
        r = np.sqrt(spectrum.masses)[:, None]
        elastic = spectrum.omega > 0
        E = spectrum.vectors[:, elastic]
        w = spectrum.omega[elastic]
        q0 = E.T @ (r * x0)
        p0 = E.T @ (r * v0)
        return cls(w, E / r, q0, p0 / w[:, None])

    @property
    def amplitudes(self) -> np.ndarray:
        """``A_j = √(q0² + (q̇0/ω)²)``, shape (M, B)."""
        return np.hypot(self.q0, self.g0)

    @property
    def omega_max(self) -> float:
        return float(self.omega.max()) if self.omega.size else 0.0

    @property
    def size(self) -> float:
        """The largest physical amplitude a mode can reach, ``max_k Σ_j |S_kj| A_j`` (a length)."""
        return float(np.max(np.abs(self.shapes) @ self.amplitudes)) if self.omega.size else 0.0

    def _per_step(self, response: OscillatorResponse, h: float):
        z = self.omega * h
        delta = response.angle_defect(z)
        lam = response.log_amplitude(z)
        s, r = response.distortion(z)
        return z, delta, lam, s, r

    def envelope(self, response: OscillatorResponse, h: float, steps: int | np.ndarray) -> np.ndarray:
        """Upper bound of the largest position error over steps ``0..steps``, shape like ``steps``.

        ``inf`` for an unstable step. See the module docstring.
        """
        n = np.atleast_1d(np.asarray(steps, dtype=float))
        z, delta, lam, s, r = self._per_step(response, h)
        if np.any(np.isnan(delta)):
            return np.full(n.shape, np.inf) if np.ndim(steps) else np.inf
        A = self.amplitudes                                  # (M, B)
        phase = 2.0 * np.sin(0.5 * np.minimum(np.abs(delta)[:, None] * n[None, :], math.pi))  # (M, S)
        decay = np.abs(np.expm1(lam[:, None] * n[None, :]))
        dist = np.abs(s[:, None] * self.q0 + r[:, None] * self.g0)          # (M, B)
        per_mode = (A[:, :, None] * (phase + decay)[:, None, :] + dist[:, :, None])  # (M, B, S)
        bound = np.tensordot(np.abs(self.shapes), per_mode, axes=1)        # (N, B, S)
        out = bound.max(axis=(0, 1))
        return out if np.ndim(steps) else float(out[0])

    def error(self, response: OscillatorResponse, h: float, steps: int, stride: int = 1,
              chunk: int = 1 << 15) -> float:
        """The largest position error over the steps ``0, stride, 2·stride, …, steps``, exactly.

        Evaluates the method's closed-form numerical solution against the exact
        one mode by mode (cost ``O(steps/stride · N · M)``). ``inf`` if unstable.
        """
        z, delta, lam, s, r = self._per_step(response, h)
        if np.any(np.isnan(delta)):
            return math.inf
        psi = z + 0.5 * delta
        theta = z + delta
        idx = np.arange(0, steps + 1, stride, dtype=float)
        if idx[-1] != steps:
            idx = np.append(idx, float(steps))
        worst = 0.0
        q0, g0 = self.q0[:, None, :], self.g0[:, None, :]      # (M, 1, B)
        d2 = (s[:, None] * self.q0 + r[:, None] * self.g0)[:, None, :]
        for lo in range(0, idx.shape[0], chunk):
            i = idx[lo:lo + chunk][None, :]                  # (1, S)
            sd = np.sin(0.5 * delta[:, None] * i)            # (M, S)
            rot = 2.0 * sd[:, :, None] * (-np.sin(psi[:, None] * i)[:, :, None] * q0
                                          + np.cos(psi[:, None] * i)[:, :, None] * g0)
            ct, stn = np.cos(theta[:, None] * i), np.sin(theta[:, None] * i)
            rho_i = np.exp(lam[:, None] * i)
            amp = np.expm1(lam[:, None] * i)[:, :, None] * (ct[:, :, None] * q0 + stn[:, :, None] * g0)
            e = rot + amp + (rho_i * stn)[:, :, None] * d2  # (M, S, B)
            x = np.tensordot(self.shapes, e, axes=1)         # (N, S, B)
            worst = max(worst, float(np.max(np.abs(x))))
        return worst


def roundoff_floor(size: float, stages: float, steps: float) -> float:
    """Accumulated rounding error of ``steps`` steps of ``stages`` stages on a state of ``size``."""
    return ROUNDOFF_GAIN * EPS * size * math.sqrt(max(stages, 1.0) * max(steps, 1.0))


@dataclass(frozen=True)
class PowerLaw:
    """``y = c · s^alpha · (t / t_ref)``: a pilot-calibrated error (or cost) law.

    Attributes
    ----------
    c, alpha : float
    t_ref : float
        Horizon of the pilot runs; ``y`` grows linearly with the horizon.
    """

    c: float
    alpha: float
    t_ref: float

    @classmethod
    def through(cls, s1: float, y1: float, s2: float, y2: float, t_ref: float,
                alpha_bounds: tuple[float, float] = (-20.0, 20.0)) -> "PowerLaw":
        """The law through two pilot points (exponent clipped to ``alpha_bounds``)."""
        alpha = math.log(y2 / y1) / math.log(s2 / s1)
        alpha = min(max(alpha, alpha_bounds[0]), alpha_bounds[1])
        c = math.exp(0.5 * (math.log(y1) + math.log(y2) - alpha * (math.log(s1) + math.log(s2))))
        return cls(c, alpha, t_ref)

    def __call__(self, s: float, t: float) -> float:
        return self.c * s ** self.alpha * (t / self.t_ref)

    def solve(self, y: float, t: float) -> float:
        """The ``s`` with ``law(s, t) = y`` (inf when it lies beyond floating point, e.g. a
        method exact on the scene, such as a single free mass)."""
        try:
            return (y * self.t_ref / (t * self.c)) ** (1.0 / self.alpha)
        except (OverflowError, ZeroDivisionError):
            return math.inf
