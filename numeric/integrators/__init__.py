"""Integrators, one module each, behind :class:`~numeric.integrators.base.Integrator`.

Fixed-step methods (``INTEGRATORS``) take a step ``h``; the adaptive methods
(``ADAPTIVE``: SciPy's peers and the embedded Runge–Kutta–Nyström pairs of
:mod:`~numeric.integrators.nystrom`) take tolerances and have their own small
interface (:class:`~numeric.integrators.ivp.AdaptiveMethod`).
"""

from .base import Integrator, LinearChain, Problem, State
from .blanes_moan4 import BlanesMoan4
from .blanes_moan6 import BlanesMoan6
from .chebyshev import ChebyshevPropagator
from .dprkn6 import DPRKN6
from .dprkn8 import DPRKN8
from .dprkn12 import DPRKN12
from .expm import MatrixExponential
from .ivp import DOP853, LSODA, RK45, AdaptiveMethod, AdaptiveResult
from .kahan_li import KahanLi8
from .newmark import HHTAlpha, NewmarkAverage, NewmarkLinear
from .rk4 import RK4
from .verlet import VelocityVerlet
from .verlet_compensated import CompensatedVerlet
from .yoshida import Yoshida4

#: The one table from command-line names to fixed-step integrator classes.
INTEGRATORS: dict[str, type[Integrator]] = {
    cls.name: cls
    for cls in (VelocityVerlet, CompensatedVerlet, Yoshida4, BlanesMoan4, BlanesMoan6, KahanLi8, RK4,
                MatrixExponential, ChebyshevPropagator, NewmarkAverage, NewmarkLinear, HHTAlpha)
}

#: Command-line names of the adaptive (tolerance-driven) methods.
ADAPTIVE: dict[str, type[AdaptiveMethod]] = {cls.name: cls for cls in (RK45, DOP853, LSODA, DPRKN6, DPRKN8, DPRKN12)}

__all__ = [
    "Integrator", "Problem", "State", "LinearChain", "INTEGRATORS", "ADAPTIVE",
    "VelocityVerlet", "CompensatedVerlet", "Yoshida4", "BlanesMoan4", "BlanesMoan6", "KahanLi8", "RK4",
    "MatrixExponential", "ChebyshevPropagator", "AdaptiveMethod", "AdaptiveResult",
    "RK45", "DOP853", "LSODA", "DPRKN6", "DPRKN8", "DPRKN12", "NewmarkAverage", "NewmarkLinear", "HHTAlpha",
]
