"""Kahan–Li eighth-order symmetric composition of velocity Verlet (s17odr8a, 17 stages).

W. Kahan and R.-C. Li, Composition constants for raising the orders of
unconventional schemes for ordinary differential equations, Math. Comp. 66
(1997) 1089–1099; coefficients as tabulated in Hairer, Lubich & Wanner,
Geometric Numerical Integration (2006), V.3.2 (p = 8, s = 17). The table
checks ``Σγ = 1``, palindromy and ``Σγ³ = Σγ⁵ = Σγ⁷ = 0``; the slope tests
check order 8.
"""

from __future__ import annotations

from .coefficients import CompositionTable
from .splitting import SplittingMethod

_HALF = (0.13020248308889008087881763, 0.56116298177510838456196441,
         -0.38947496264484728640807860, 0.15884190655515560089621075,
         -0.39590389413323757733623154, 0.18453964097831570709183254,
         0.25837438768632204729397911, 0.29501172360931029887096624)
_MID = -0.60550853383003451169892108

KAHAN_LI8 = CompositionTable("kahan-li8", (*_HALF, _MID, *_HALF[::-1]), order=8,
                             source="Kahan & Li, Math. Comp. 66 (1997) 1089-1099, s17odr8a; HLW (2006) V.3.2")


class KahanLi8(SplittingMethod):
    """Eighth order, symplectic, symmetric; 17 force evaluations per step."""

    name = "kahan-li8"
    table = KAHAN_LI8.splitting()
