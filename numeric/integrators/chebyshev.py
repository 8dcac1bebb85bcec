"""Chebyshev polynomial propagator for long linear chains (matrix–vector products only).

With ``L = M⁻¹K`` (so ``L u = −a(u)``, the generated acceleration) the exact step is

    x' = cos(h√L) x + sin(h√L)/√L v,      v' = −√L sin(h√L) x + cos(h√L) v.

On ``λ ∈ [0, R²]`` (``R² ≥ ω²_max``, a Gershgorin bound) put ``λ = R²(1 + y)/2``
and ``ξ = √((1 + y)/2)``, so ``T₂ₖ(ξ) = T_k(y)``. The Jacobi–Anger expansions
``cos(zξ) = J₀(z) + 2Σ(−1)ᵏJ₂ₖ(z)T₂ₖ(ξ)`` and ``sin(zξ) = 2Σ(−1)ᵏJ₂ₖ₊₁(z)T₂ₖ₊₁(ξ)``
with ``z = hR`` then give each of the three functions as a Chebyshev series
in ``y`` with Bessel coefficients (Kosloff et al.'s rapid expansion method):

* ``cos(h√λ) = Σ c_k T_k(y)``,  ``c₀ = J₀(z)``, ``c_k = 2(−1)ᵏ J₂ₖ(z)``;
* ``sin(h√λ)/√λ = (2/R) Σ (−1)ᵏ J₂ₖ₊₁(z) V_k(y)`` (``V_k = T₂ₖ₊₁(ξ)/ξ``, third kind),
  rewritten in ``T_k`` with ``V_k = (−1)ᵏT₀ + 2Σ_{j=1..k}(−1)^{k−j}T_j``;
* ``−√λ sin(h√λ) = −R Σ (−1)ᵏ J₂ₖ₊₁(z) (T_{k+1}(y) + T_k(y))`` (``2ξT₂ₖ₊₁ = T₂ₖ₊₂ + T₂ₖ``).

A step runs one three-term recurrence ``Z_{k+1} = 2YZ_k − Z_{k−1}`` on the
stacked ``[x | v]`` with ``Y u = −(2/R²) a(u) − u``, so it needs only the
acceleration (a stencil for long chains), about ``hR/2`` of them per step,
and is exact up to the series' truncation at roundoff level for any ``h``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from scipy.special import jv

from .base import Problem, StepKernel, finite_positive
from .propagator import LinearPropagator

#: Coefficients below this fraction of the largest are dropped.
TRUNCATION = 1e-17


@dataclass(frozen=True)
class ChebyshevCoefficients:
    """Series in ``T_k(y)``, ``y = 2λ/R² − 1``, of the exact step's three functions.

    Attributes
    ----------
    h : float
        Step.
    radius2 : float
        ``R²``, the upper end of the λ interval.
    cos, sinc, wsin : ndarray, shape (K + 1,)
        Coefficients of ``cos(h√λ)``, ``sin(h√λ)/√λ`` and ``−√λ sin(h√λ)``.
    """

    h: float
    radius2: float
    cos: np.ndarray = field(repr=False)
    sinc: np.ndarray = field(repr=False)
    wsin: np.ndarray = field(repr=False)

    def __post_init__(self):
        where = f"Chebyshev coefficients (h={self.h:g}, R²={self.radius2:g})"
        if not (self.cos.shape == self.sinc.shape == self.wsin.shape and self.cos.ndim == 1):
            raise ValueError(f"{where}: the three series must have the same length")
        # identities at the ends of the interval: λ = 0 (y = -1) and λ = R² (y = 1)
        R = math.sqrt(self.radius2)
        alt = (-1.0) ** np.arange(self.cos.shape[0])
        checks = {
            "cos at λ=0": (alt @ self.cos, 1.0, 1.0),
            "sin(h√λ)/√λ at λ=0": (alt @ self.sinc, self.h, self.h),
            "−√λ sin(h√λ) at λ=0": (alt @ self.wsin, 0.0, R),
            "cos at λ=R²": (self.cos.sum(), math.cos(self.h * R), 1.0),
            "sin(h√λ)/√λ at λ=R²": (self.sinc.sum(), math.sin(self.h * R) / R if R > 0 else self.h, self.h),
            "−√λ sin(h√λ) at λ=R²": (self.wsin.sum(), -R * math.sin(self.h * R), R),
        }
        k = self.cos.shape[0]
        for what, (got, want, scale) in checks.items():
            if abs(got - want) > 1e-13 * k * scale:
                raise ValueError(f"{where}: {what} is {got!r}, expected {want!r}")

    @property
    def degree(self) -> int:
        return int(self.cos.shape[0] - 1)

    @classmethod
    def from_bessel(cls, h: float, radius2: float) -> "ChebyshevCoefficients":
        """Bessel-coefficient series, truncated where the coefficients fall below roundoff."""
        h, radius2 = float(h), float(radius2)
        R = math.sqrt(radius2)
        z = h * R
        kmax = int(math.ceil((z + 10.0 * z ** (1.0 / 3.0) + 60.0) / 2.0))
        k = np.arange(kmax + 1)
        sign = (-1.0) ** k
        j_even = jv(2 * k, z)
        j_odd = jv(2 * k + 1, z)
        c = 2.0 * sign * j_even
        c[0] = j_even[0]
        # sin(h√λ)/√λ: (2/R) Σ_k (-1)^k J_{2k+1} V_k;  T_j coefficient = ε_j (2/R) (-1)^j Σ_{k>=j} J_{2k+1}
        tail = np.cumsum(j_odd[::-1])[::-1]
        g = (2.0 / R) * sign * tail * np.where(k == 0, 1.0, 2.0) if R > 0 else np.zeros(kmax + 1)
        # -√λ sin(h√λ) = -R Σ_k (-1)^k J_{2k+1} (T_{k+1} + T_k)
        b = -R * sign * j_odd
        w = b.copy()
        w[1:] += b[:-1]
        if R == 0:  # no springs: the free flight x' = x + h v
            c, g, w = np.zeros(1) + 1.0, np.full(1, h), np.zeros(1)
        else:
            scale = np.maximum.reduce([np.abs(c) / 1.0, np.abs(g) / h, np.abs(w) / R])
            keep = np.flatnonzero(scale > TRUNCATION)
            top = int(keep[-1]) + 1 if keep.size else 1
            if top >= kmax:
                raise ValueError(f"Chebyshev coefficients (h={h:g}, R²={radius2:g}): series not converged "
                                 f"within {kmax} terms")
            c, g, w = c[:top], g[:top], w[:top]
        return cls(h, radius2, c, g, w)


class ChebyshevPropagator(LinearPropagator):
    """Exact-to-roundoff propagator of a linear chain from acceleration evaluations only.

    Force evaluations are counted in units of one evaluation on an (N, B)
    batch: a step applies the acceleration ``K`` times to the stacked (N, 2B)
    ``[x | v]``, which counts as ``2K``.
    """

    name = "chebyshev"
    evals_per_step = math.nan  # depends on h·ω_max: see evals_for

    def refusal(self, problem: Problem) -> str | None:
        why = super().refusal(problem)
        if why is None and np.any(problem.linear.stiffness < 0):
            return f"method {self.name!r} needs non-negative spring constants"
        return why

    def coefficients(self, problem: Problem, h: float) -> ChebyshevCoefficients:
        return ChebyshevCoefficients.from_bessel(h, problem.linear.omega2_bound())

    def evals_for(self, problem: Problem, h: float) -> float:
        return 2.0 * self.coefficients(problem, h).degree

    def kernel(self, problem: Problem, h: float) -> StepKernel:
        h = finite_positive(h)
        self.check(problem)
        co = self.coefficients(problem, h)
        acc = problem.acceleration
        r2 = co.radius2
        if co.degree == 0:
            def step(x, v, a, i):
                return x + h * v, v, None
            return step
        scale = -2.0 / r2
        terms = list(zip(co.cos[1:], co.wsin[1:], co.sinc[1:]))

        def step(x, v, a, i):
            b = x.shape[1]
            z0 = np.concatenate((x, v), axis=1)           # [x | v], (N, 2B)
            z1 = scale * acc(z0) - z0                    # Y z0
            s1 = co.cos[0] * z0                          # [Cx | Cv]
            s2x = co.wsin[0] * x                          # W x
            s2v = co.sinc[0] * v                          # G v
            zp, zc = z0, z1
            for k, (ck, wk, gk) in enumerate(terms, start=1):
                s1 = s1 + ck * zc
                s2x = s2x + wk * zc[:, :b]
                s2v = s2v + gk * zc[:, b:]
                if k < len(terms):
                    zn = 2.0 * (scale * acc(zc) - zc) - zp
                    zp, zc = zc, zn
            return s1[:, :b] + s2v, s2x + s1[:, b:], None
        return step
