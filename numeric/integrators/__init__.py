"""Integrators, one module each, behind :class:`~numeric.integrators.base.Integrator`.

Fixed-step methods take a step ``h``; the adaptive methods (SciPy's peers and the
embedded Runge–Kutta–Nyström pairs of :mod:`~numeric.integrators.nystrom`) take
tolerances and have their own small interface
(:class:`~numeric.integrators.ivp.AdaptiveMethod`). Their names are registered once,
in :mod:`numeric.run.registry`.
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
from .rk4 import RK4
from .verlet import VelocityVerlet
from .verlet_compensated import CompensatedVerlet
from .yoshida import Yoshida4

__all__ = [
    "Integrator", "Problem", "State", "LinearChain",
    "VelocityVerlet", "CompensatedVerlet", "Yoshida4", "BlanesMoan4", "BlanesMoan6", "KahanLi8", "RK4",
    "MatrixExponential", "ChebyshevPropagator", "AdaptiveMethod", "AdaptiveResult",
    "RK45", "DOP853", "LSODA", "DPRKN6", "DPRKN8", "DPRKN12",
]
