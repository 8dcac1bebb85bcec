"""∂/∂p and ∂²/∂p² of every mass and spring constant of a linear scene, symbolically.

The element expressions of the scene (``masses.m1 = "3*m"``, ``k = "k*(1 + i)"``) are
differentiated by SymPy once (:class:`ElementLaw`); :meth:`ElementLaw.at` evaluates the
derivatives at any parameter values:

* ``[masses]`` scenes: each derivative in mpmath with the values as exact binary fractions,
  correctly rounded (:func:`derive.accurate.value`); constants directly;
* ``[chain]`` scenes: expressions of the index ``i`` as NumPy functions over ``i`` (float64, vectorised:
  10⁵ masses in milliseconds), derivatives free of ``i`` exactly as above.

The springs come in the generated module's order (``spring_ends``): for a chain the spring between
masses i and i+1 is k(i), a left wall spring k(−1), a right wall or the ring closure k(n−1).
"""

from __future__ import annotations

import functools
from dataclasses import dataclass, field

import numpy as np
import sympy as sp

from ..accurate import exact_values, value
from ..errors import SceneError


@functools.lru_cache(maxsize=256)
def _numpy_function(expr: sp.Expr, symbols: tuple):
    """``expr`` as a NumPy function of ``symbols`` (an index-dependent chain derivative), built once."""
    return sp.lambdify(list(symbols), expr, modules="numpy")


def _value(expr: sp.Expr, subs: dict) -> float:
    if expr.is_Number:
        return float(expr)
    return value(expr, subs)


@dataclass(frozen=True)
class ElementLaw:
    """Symbolic first and second derivatives of the element values.

    Attributes
    ----------
    parameters : tuple of str
    symbols : dict
        Parameter name -> SymPy symbol (every parameter of the scene).
    masses, springs : list of list of (Expr, Expr)
        Per parameter, per element: (∂e/∂p, ∂²e/∂p²). For a chain one entry each (in ``i``).
    chain : bool
    index : sympy.Symbol or None
        The chain index ``i``.
    """

    parameters: tuple[str, ...]
    symbols: dict = field(repr=False)
    masses: list = field(repr=False)
    springs: list = field(repr=False)
    chain: bool = False
    index: object = field(default=None, repr=False)

    def _chain_values(self, expr: sp.Expr, at: np.ndarray, subs: dict, values: dict) -> np.ndarray:
        if not expr.has(self.index):
            return np.full(at.shape[0], _value(expr, subs))
        names = tuple(sorted(values))
        f = _numpy_function(expr, (self.index,) + tuple(self.symbols[k] for k in names))
        out = f(at.astype(float), *[float(values[k]) for k in names])
        return np.broadcast_to(np.asarray(out, dtype=float), at.shape).copy()

    def at(self, values: dict[str, float], spring_ends: np.ndarray, n: int):
        """``(dm, dk, d2m, d2k)`` at ``values``, shapes (P, N), (P, S), (P, N), (P, S).

        Parameters
        ----------
        values : dict
            Every parameter's value.
        spring_ends : ndarray of int, shape (S, 2)
            The generated module's spring order (mass indices, -1 for a wall).
        n : int
            Masses.
        """
        subs = exact_values(self.symbols, values)
        ends = np.asarray(spring_ends, dtype=np.intp).reshape(-1, 2)
        P, S = len(self.parameters), ends.shape[0]
        dm, d2m, dk, d2k = np.zeros((P, n)), np.zeros((P, n)), np.zeros((P, S)), np.zeros((P, S))
        if self.chain:
            a, b = ends[:, 0], ends[:, 1]
            ks = np.where(a < 0, -1, np.where(b < 0, a, np.where((a == n - 1) & (b == 0), n - 1, np.minimum(a, b))))
            ms = np.arange(n)
            for p in range(P):
                (m1, m2), (k1, k2) = self.masses[p][0], self.springs[p][0]
                dm[p], d2m[p] = self._chain_values(m1, ms, subs, values), self._chain_values(m2, ms, subs, values)
                dk[p], d2k[p] = self._chain_values(k1, ks, subs, values), self._chain_values(k2, ks, subs, values)
            return dm, dk, d2m, d2k
        for p in range(P):
            for i, (e1, e2) in enumerate(self.masses[p]):
                dm[p, i], d2m[p, i] = _value(e1, subs), _value(e2, subs)
            for s, (e1, e2) in enumerate(self.springs[p]):
                dk[p, s], d2k[p, s] = _value(e1, subs), _value(e2, subs)
        return dm, dk, d2m, d2k


def _pair(expr: sp.Expr, sym: sp.Symbol) -> tuple[sp.Expr, sp.Expr]:
    d1 = sp.diff(expr, sym)
    return d1, sp.diff(d1, sym)


def element_law(model, parameters: tuple[str, ...]) -> ElementLaw:
    """The symbolic derivatives of a linear model's masses and spring constants.

    Parameters
    ----------
    model : derive.model.Model or derive.chain.ChainModel
    parameters : tuple of str
        Names of scene parameters (checked by the caller).

    Raises
    ------
    SceneError
        A scene with spring potentials (its stiffness is that of an equilibrium), one line.
    """
    scene = model.scene
    if scene.has_potential:
        raise SceneError(scene.file, "springs", "sensitivities need springs given by k (linear, or cubic: the "
                                                "linear part is what the modes see); this scene has spring "
                                                "potentials; accepted: k (and k3) springs")
    if getattr(model, "equilibrium", None) is not None:  # cubic springs under constant loads: K = K_t at x_eq
        raise SceneError(scene.file, "springs", "sensitivities need the modes' stiffness as a function of the "
                                                "parameters; this scene's cubic (k3) springs are linearised about "
                                                "a static equilibrium solved numerically (k + 3 k3 d^2 there); "
                                                "accepted: k (and k3) springs without constant loads")
    syms = model.params
    if scene.chain is not None:
        masses = [[_pair(model.mass, syms[p])] for p in parameters]
        springs = [[_pair(model.k, syms[p])] for p in parameters]
        return ElementLaw(tuple(parameters), syms, masses, springs, True, model.i)
    masses = [[_pair(m, syms[p]) for m in model.masses] for p in parameters]
    springs = [[_pair(k, syms[p]) for _, _, k, _, _ in model.springs] for p in parameters]
    return ElementLaw(tuple(parameters), syms, masses, springs)


def relevant(model) -> tuple[str, ...]:
    """The parameters the masses or spring constants depend on (sorted)."""
    if model.scene.chain is not None:
        exprs = [model.mass, model.k]
    else:
        exprs = list(model.masses) + [k for _, _, k, _, _ in model.springs]
    used = set().union(*(e.free_symbols for e in exprs)) if exprs else set()
    return tuple(name for name, sym in sorted(model.params.items()) if sym in used)


__all__ = ["ElementLaw", "element_law", "relevant"]
