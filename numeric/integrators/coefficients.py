"""Coefficient tables as frozen, self-checking data.

Two kinds of table:

* :class:`SplittingTable` — a kick–drift (``BAB``) splitting of ``ẍ = f(x)``::

      v += b₀ h f(x);  x += a₀ h v;  v += b₁ h f(x);  …;  x += a_{m-1} h v;  v += b_m h f(x)

  ``m`` drifts and ``m + 1`` kicks; the last kick's force is the next step's
  first (first same as last), so a step costs ``m`` force evaluations.

* :class:`CompositionTable` — weights ``γ₁ … γ_s`` of a composition of a
  symmetric second-order method (velocity Verlet): ``Φ_h = V_{γ_s h} ∘ … ∘ V_{γ₁ h}``.
  :meth:`CompositionTable.splitting` writes it as a :class:`SplittingTable`
  (drifts ``γ_j``, kicks ``(γ_{j-1} + γ_j)/2``).

Both check themselves when built and raise :class:`ValueError` naming the
table: weights sum to one, shapes agree, symmetric tables are palindromic,
and a composition of declared order ``p`` meets the power-sum conditions
``Σ γ_j^q = 0`` for odd ``3 ≤ q < p`` (necessary for a symmetric composition
of order ``p``; the full order is verified by the slope tests).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from functools import cached_property

import numpy as np

#: Tolerance of the identities (the published coefficients carry 15–26 digits).
TOL = 1e-14


def _palindromic(seq: tuple[float, ...], tol: float) -> bool:
    a = np.asarray(seq)
    return bool(np.all(np.abs(a - a[::-1]) <= tol * max(1.0, float(np.max(np.abs(a))))))


@dataclass(frozen=True)
class SplittingTable:
    """Kick weights ``b`` (m+1) and drift weights ``a`` (m) of a ``BAB`` splitting.

    Attributes
    ----------
    name : str
        Used in error messages.
    kicks : tuple of float, length m + 1
    drifts : tuple of float, length m
    order : int
        Declared order.
    symmetric : bool
        Palindromic (time-reversible); checked.
    source : str
        Where the numbers come from.
    """

    name: str
    kicks: tuple[float, ...]
    drifts: tuple[float, ...]
    order: int
    symmetric: bool = True
    source: str = field(default="", compare=False)

    def __post_init__(self):
        kicks = tuple(float(c) for c in self.kicks)
        drifts = tuple(float(c) for c in self.drifts)
        object.__setattr__(self, "kicks", kicks)
        object.__setattr__(self, "drifts", drifts)
        where = f"splitting table {self.name!r}"
        if len(drifts) < 1 or len(kicks) != len(drifts) + 1:
            raise ValueError(f"{where}: needs m >= 1 drifts and m + 1 kicks, got {len(drifts)} and {len(kicks)}")
        if not all(math.isfinite(c) for c in kicks + drifts):
            raise ValueError(f"{where}: coefficients must be finite")
        if abs(math.fsum(kicks) - 1.0) > TOL:
            raise ValueError(f"{where}: kick (velocity) weights sum to {math.fsum(kicks)!r}, not 1")
        if abs(math.fsum(drifts) - 1.0) > TOL:
            raise ValueError(f"{where}: drift (position) weights sum to {math.fsum(drifts)!r}, not 1")
        if self.symmetric and not (_palindromic(kicks, TOL) and _palindromic(drifts, TOL)):
            raise ValueError(f"{where}: declared symmetric but the weights are not palindromic")
        if self.order < 1:
            raise ValueError(f"{where}: order must be >= 1, got {self.order}")
        if self.symmetric and self.order % 2:
            raise ValueError(f"{where}: a symmetric method has even order, got {self.order}")

    @property
    def stages(self) -> int:
        """Force evaluations per step (first same as last)."""
        return len(self.drifts)

    @property
    def nodes(self) -> tuple[float, ...]:
        """Times of the kicks as fractions of the step, ``c_j = a₀ + … + a_{j-1}``, length m + 1."""
        return tuple(float(c) for c in np.concatenate([[0.0], np.cumsum(self.drifts)]))

    def propagator(self, z: float) -> np.ndarray:
        """One step on ``ẍ = -ω²x`` with ``z = ωh``: the 2×2 map of ``(ωx, v)``."""
        P = np.eye(2)
        kick = lambda c: np.array([[1.0, 0.0], [-c * z, 1.0]])  # noqa: E731
        drift = lambda c: np.array([[1.0, c * z], [0.0, 1.0]])  # noqa: E731
        P = kick(self.kicks[0]) @ P
        for a, b in zip(self.drifts, self.kicks[1:]):
            P = kick(b) @ (drift(a) @ P)
        return P

    def half_traces(self, z: np.ndarray) -> np.ndarray:
        """``trace(P(z))/2`` of :meth:`propagator` for many ``z`` at once (shape of ``z``): the map's
        entries as arrays, one kick or drift at a time."""
        z = np.asarray(z, dtype=float)
        p00, p01, p10, p11 = np.ones_like(z), np.zeros_like(z), np.zeros_like(z), np.ones_like(z)
        p10, p11 = p10 - self.kicks[0] * z * p00, p11 - self.kicks[0] * z * p01
        for a, b in zip(self.drifts, self.kicks[1:]):
            p00, p01 = p00 + a * z * p10, p01 + a * z * p11
            p10, p11 = p10 - b * z * p00, p11 - b * z * p01
        return 0.5 * (p00 + p11)

    @cached_property
    def stability_limit(self) -> float:
        """Largest ``z = ωh`` with every ``z' < z`` stable on the harmonic oscillator.

        The one-step map has determinant 1; it is stable while ``|trace/2| ≤ 1``.
        Found by a scan of step 1e-3 (:meth:`half_traces` on blocks of the grid) refined by bisection.
        """
        def unstable(z):
            return abs(self.half_traces(z)) > 1.0 + 1e-13

        dz, block = 1e-3, 4096
        last = math.ceil(50.0 * self.stages / dz)  # the scan ends at z = 50 × stages
        k = 1
        while k <= last:
            grid = np.arange(k, min(k + block, last + 1)) * dz
            bad = np.flatnonzero(unstable(grid))
            if bad.size:
                lo, hi = grid[bad[0]] - dz, grid[bad[0]]
                for _ in range(50):
                    mid = 0.5 * (lo + hi)
                    lo, hi = (lo, mid) if unstable(mid) else (mid, hi)
                return float(lo)
            k += block
        return math.inf


@dataclass(frozen=True)
class CompositionTable:
    """Weights ``γ`` of a composition of velocity Verlet (a symmetric second-order method).

    Attributes
    ----------
    name : str
    weights : tuple of float, length s
    order : int
        Declared order (even).
    source : str
    """

    name: str
    weights: tuple[float, ...]
    order: int
    source: str = field(default="", compare=False)

    def __post_init__(self):
        w = tuple(float(c) for c in self.weights)
        object.__setattr__(self, "weights", w)
        where = f"composition table {self.name!r}"
        if len(w) < 1 or not all(math.isfinite(c) for c in w):
            raise ValueError(f"{where}: needs at least one finite weight")
        if abs(math.fsum(w) - 1.0) > TOL:
            raise ValueError(f"{where}: weights sum to {math.fsum(w)!r}, not 1")
        if not _palindromic(w, TOL):
            raise ValueError(f"{where}: weights are not palindromic (the composition would not be symmetric)")
        if self.order < 2 or self.order % 2:
            raise ValueError(f"{where}: order of a symmetric composition must be even and >= 2, got {self.order}")
        for q in range(3, self.order, 2):
            s = self.power_sum(q)
            if abs(s) > TOL * max(1.0, math.fsum(abs(c) ** q for c in w)):
                raise ValueError(f"{where}: order {self.order} needs sum(w**{q}) = 0, got {s:.3g}")

    def power_sum(self, q: int) -> float:
        """``Σ γ_j^q`` (exactly summed)."""
        return math.fsum(c**q for c in self.weights)

    def splitting(self) -> SplittingTable:
        """The same method as a kick–drift table: drifts ``γ_j``, kicks ``γ₁/2, (γ₁+γ₂)/2, …, γ_s/2``."""
        w = self.weights
        kicks = (0.5 * w[0], *(0.5 * (w[j - 1] + w[j]) for j in range(1, len(w))), 0.5 * w[-1])
        return SplittingTable(self.name, kicks, w, self.order, True, self.source)
