"""Springs given by their energy: ``potential = "EXPR"`` of the extension d (the scene's spring laws).

A spring law is V(d) with d = x_b − x_a for ``between = [a, b]`` (a wall end counts 0), or, in a
``[chain]``, d = x_{i+1} − x_i for the spring i (the left wall spring i = −1 has d = x_0, the right
one d = −x_{n−1}, a ring's closing spring d = x_0 − x_{n−1}). The force the spring pulls its ends
together with is the tension V'(d): +V'(d) on mass a, −V'(d) on mass b. Its stiffness V''(d) at the
equilibrium is the spring's entry in K (the modes are those of the linearisation about the
equilibrium, :mod:`springchain.derive.equilibrium`).

Linear and cubic springs are laws too (``k d²/2 + k3 d⁴/4``), so the equilibrium solver sees every
spring the same way.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property

import sympy as sp

from .scene import EXTENSION

#: The extension symbol of every spring law (real).
D = sp.Symbol(EXTENSION, real=True)


@dataclass(frozen=True)
class SpringLaw:
    """One spring's energy V(d) and what follows from it (derivatives, stable forms).

    Attributes
    ----------
    key : str
        The scene entry (``springs[2]``, ``chain``); the potential's key is ``key + ".potential"``.
    energy : sympy.Expr
        V(d) in the parameters (and ``i`` in a chain), as written.
    given : bool
        Whether it enters the equations as a law (a potential; False for k/k3 springs taken as k and k3).
    cubic : bool
        A k/k3 spring taken as its law ``k d²/2 + k3 d⁴/4`` (given): its equilibrium is away from d = 0.
    """

    key: str
    energy: sp.Expr
    given: bool = True
    cubic: bool = False
    d: sp.Symbol = field(default=D, repr=False)

    @cached_property
    def force(self) -> sp.Expr:
        """The tension V'(d)."""
        return sp.diff(self.energy, self.d)

    @cached_property
    def stiffness(self) -> sp.Expr:
        """V''(d)."""
        return sp.diff(self.force, self.d)

    @cached_property
    def stable_force(self) -> sp.Expr:
        """V'(d) in a form without cancellation near d = 0 (:func:`stable_laws.stable_force`)."""
        from .stable_laws import stable_force

        return stable_force(self.force, self.d)

    @cached_property
    def stable_energy(self) -> sp.Expr:
        """V(d) − V(0) in a form without cancellation near d = 0 (:func:`stable_laws.stable_energy`)."""
        from .stable_laws import stable_energy

        return stable_energy(self.energy, self.d)

    @property
    def where(self) -> str:
        """The key error messages name."""
        if self.cubic:
            return f"{self.key}.k3"
        return f"{self.key}.potential" if self.given else f"{self.key}.k"

    def polynomial_degree(self) -> int | None:
        """The degree of V in d if V is a polynomial in d, else None."""
        try:
            return sp.Poly(self.energy, self.d).degree()
        except sp.PolynomialError:
            return None


def linear_law(key: str, k: sp.Expr, k3: sp.Expr | None) -> SpringLaw:
    """``k d²/2 (+ k3 d⁴/4)``: a k/k3 spring as a law."""
    return SpringLaw(key, k * D**2 / 2 + (k3 * D**4 / 4 if k3 is not None else 0), given=False)


__all__ = ["D", "SpringLaw", "linear_law"]
