"""The shared part of the exact propagators (``expm``, ``chebyshev``): what they accept."""

from __future__ import annotations

import math

from .base import Integrator, Problem


class LinearPropagator(Integrator):
    """Base of propagators that apply the exact flow of an undamped, unforced linear chain.

    They need ``Problem.linear`` and take any step (``stability_limit = inf``).
    """

    order = math.inf
    symplectic = True  # the exact flow, to roundoff
    init_evals = 0
    stability_limit = math.inf

    def refusal(self, problem: Problem) -> str | None:
        if problem.linear is None:
            return (f"method {self.name!r} needs a linear chain of springs only (no cubic springs, "
                    f"dampers, gravity or external forces); use the exact method 'modal' for the exact solution "
                    f"of a linear scene with effects, or a step method such as blanes-moan6")
        if problem.damping is not None or problem.external is not None:
            return (f"method {self.name!r} propagates free oscillations only; this scene has "
                    f"dampers or external forces: use rk4 or dop853")
        return None
