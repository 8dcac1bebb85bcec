"""Blanes–Moan optimised fourth-order Runge–Kutta–Nyström splitting (SRKN₆ᵇ).

S. Blanes and P. C. Moan, Practical symplectic partitioned Runge–Kutta and
Runge–Kutta–Nyström methods, J. Comput. Appl. Math. 142 (2002) 313–330,
Table 3, method SRKN₆ᵇ (order 4, 6 stages, for ``ẍ = f(x)``, starting with
a kick ``b₁``)::

    b₁ a₁ b₂ a₂ b₃ a₃ b₄ a₃ b₃ a₂ b₂ a₁ b₁
    a₃ = 1/2 − (a₁ + a₂),   b₄ = 1 − 2(b₁ + b₂ + b₃)

The same numbers are used by Principia (``BlanesMoan2002SRKN6B``) and by
Boost.Odeint-style implementations; the slope tests check order 4 on linear
and nonlinear chains.
"""

from __future__ import annotations

from .coefficients import SplittingTable
from .splitting import SplittingMethod

_B = (0.0829844064174052, 0.396309801498368, -0.0390563049223486)
_A = (0.245298957184271, 0.604872665711080)
_A3 = 0.5 - (_A[0] + _A[1])
_B4 = 1.0 - 2.0 * (_B[0] + _B[1] + _B[2])

BLANES_MOAN4 = SplittingTable(
    "blanes-moan4",
    kicks=(*_B, _B4, *_B[::-1]),
    drifts=(*_A, _A3, _A3, *_A[::-1]),
    order=4,
    source="Blanes & Moan, J. Comput. Appl. Math. 142 (2002) 313-330, Table 3, SRKN_6^b",
)


class BlanesMoan4(SplittingMethod):
    """Fourth order, symplectic, symmetric; 6 force evaluations per step, small error constant."""

    name = "blanes-moan4"
    table = BLANES_MOAN4
