"""Blanes–Moan optimised sixth-order Runge–Kutta–Nyström splitting (SRKN₁₁ᵇ).

S. Blanes and P. C. Moan, Practical symplectic partitioned Runge–Kutta and
Runge–Kutta–Nyström methods, J. Comput. Appl. Math. 142 (2002) 313–330,
Table 3, method SRKN₁₁ᵇ (order 6, 11 stages, for ``ẍ = f(x)``, starting with
a kick ``b₁``)::

    b₁ a₁ b₂ a₂ b₃ a₃ b₄ a₄ b₅ a₅ b₆ a₆ b₆ a₅ b₅ a₄ b₄ a₃ b₃ a₂ b₂ a₁ b₁
    b₆ = 1/2 − (b₁ + … + b₅),   a₆ = 1 − 2(a₁ + … + a₅)

The same numbers are used by Principia (``BlanesMoan2002SRKN11B``); the
slope tests check order 6 on linear and nonlinear chains.
"""

from __future__ import annotations

import math

from .coefficients import SplittingTable
from .splitting import SplittingMethod

_B = (0.0414649985182624, 0.198128671918067, -0.0400061921041533,
      0.0752539843015807, -0.0115113874206879)
_A = (0.123229775946271, 0.290553797799558, -0.127049212625417,
      -0.246331761062075, 0.357208872795928)
_B6 = 0.5 - math.fsum(_B)
_A6 = 1.0 - 2.0 * math.fsum(_A)

BLANES_MOAN6 = SplittingTable(
    "blanes-moan6",
    kicks=(*_B, _B6, _B6, *_B[::-1]),
    drifts=(*_A, _A6, *_A[::-1]),
    order=6,
    source="Blanes & Moan, J. Comput. Appl. Math. 142 (2002) 313-330, Table 3, SRKN_11^b",
)


class BlanesMoan6(SplittingMethod):
    """Sixth order, symplectic, symmetric; 11 force evaluations per step."""

    name = "blanes-moan6"
    table = BLANES_MOAN6
