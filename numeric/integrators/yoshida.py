"""Yoshida's fourth-order triple jump: velocity Verlet with steps γ₁h, γ₀h, γ₁h.

``γ₁ = 1/(2 − 2^{1/3})``, ``γ₀ = 1 − 2γ₁`` (so that ``2γ₁³ + γ₀³ = 0``).
H. Yoshida, Construction of higher order symplectic integrators,
Phys. Lett. A 150 (1990) 262–268; Hairer, Lubich & Wanner, Geometric
Numerical Integration (2006), II.4 eq. (4.4).
"""

from __future__ import annotations

from .coefficients import CompositionTable
from .splitting import SplittingMethod

_G1 = 1.0 / (2.0 - 2.0 ** (1.0 / 3.0))

#: Triple-jump weights.
YOSHIDA4 = CompositionTable("yoshida4", (_G1, 1.0 - 2.0 * _G1, _G1), order=4,
                            source="Yoshida, Phys. Lett. A 150 (1990) 262; HLW (2006) II.4 (4.4)")


class Yoshida4(SplittingMethod):
    """Fourth order, symplectic, symmetric; 3 force evaluations per step."""

    name = "yoshida4"
    table = YOSHIDA4.splitting()
