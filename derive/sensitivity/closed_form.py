"""∂ω²/∂p in closed form, where the modes are closed-form.

A closed-form ω² (a root of a factor of the characteristic polynomial, valid for every parameter
value) is an analytic branch, so its derivative is ``sp.diff(ω², p)``; a repeated closed-form root
stays repeated for every value (both branches share the derivative). Values are evaluated like
the printed ω²: in mpmath with the parameters as exact binary fractions, correctly rounded
(:func:`derive.accurate.value`). Uniform ``[chain]`` scenes differentiate their family ω²_j(j, n).
Expressions longer than :data:`MAX_OPS` operations are not kept (the numeric value stands).
"""

from __future__ import annotations

from dataclasses import dataclass

import sympy as sp

from ..caps import CAPS
from ..accurate import NotAccurate, exact_values, value
from ..expr import as_sympy

#: Largest derivative (SymPy operation count) kept as a closed form.
MAX_OPS = CAPS.sensitivity_ops
#: Largest derivative SymPy is asked to simplify (``cancel``/``factor``; a size cap, never a time).
MAX_SIMPLIFY_OPS = CAPS.sensitivity_simplify_ops
#: Largest shape component (operations) whose derivative is sought in closed form.
MAX_SHAPE_OPS = CAPS.sensitivity_shape_ops


@dataclass(frozen=True)
class ClosedForm:
    """∂ω²/∂p of each closed-form mode.

    Attributes
    ----------
    modes : list of (dict, dict) or None
        Per mode in ascending order (repeated modes listed once per independent shape):
        ``({p: expression}, {p: value})``, or None for a mode without a closed form.
    shapes : list of dict or None
        Per mode: ``{p: [∂φ_i/∂p expression, ...]}`` of the mass-normalised closed-form shape
        ``φ = ±s/√(sᵀMs)`` (sign: the largest mass-weighted component positive at the scene's values),
        for simple modes whose derivatives stay below :data:`MAX_OPS` operations; None otherwise.
    family : dict or None
        A uniform chain's ``{p: ∂ω²_j/∂p}`` in ``j`` and ``n``.
    """

    modes: list
    family: dict | None = None
    shapes: list | None = None


def _simplify(expr: sp.Expr) -> sp.Expr | None:
    """A readable form of a derivative, or None when it is longer than :data:`MAX_OPS` operations.

    Only small rational expressions go through ``cancel``/``factor`` (:data:`MAX_SIMPLIFY_OPS`): the work is
    bounded by size, so the same scene costs the same on any machine."""
    ops = sp.count_ops(expr)
    if ops > MAX_OPS:
        return None
    if ops <= MAX_SIMPLIFY_OPS and not expr.has(sp.cos, sp.acos, sp.sin):
        out = sp.factor(sp.cancel(expr))
        return out if sp.count_ops(out) <= ops else expr
    return expr


def closed_form_derivatives(model, modes, parameters: tuple[str, ...]) -> ClosedForm:
    """Closed-form ∂ω²/∂p of a scene's modes (see the module docstring).

    Parameters
    ----------
    model : Model or ChainModel
    modes : ModeSet or ChainModes
    parameters : tuple of str
    """
    syms = model.params
    if model.scene.chain is not None:
        if getattr(modes, "omega2", None) is None:
            return ClosedForm([], None)
        return ClosedForm([], {p: _simplify(sp.diff(modes.omega2, syms[p])) for p in parameters})
    subs = exact_values(syms, model.scene.parameters)
    out, shapes = [], []
    for mode in modes.modes:
        d_shape = _shape_derivatives(model, mode, parameters, subs) if mode.multiplicity == 1 else None
        shapes.extend([d_shape] * mode.multiplicity)
        if not mode.exact or mode.rigid:
            entry = None if not mode.rigid else ({p: sp.Integer(0) for p in parameters}, {p: 0.0 for p in parameters})
        else:
            exprs, values = {}, {}
            for p in parameters:
                d = _simplify(sp.diff(mode.omega2, syms[p]))
                exprs[p] = d
                try:
                    values[p] = None if d is None else value(d, subs)
                except NotAccurate:
                    values[p] = None
            entry = (exprs, values)
        out.extend([entry] * mode.multiplicity)
    return ClosedForm(out, None, shapes)


def _shape_derivatives(model, mode, parameters: tuple[str, ...], subs: dict) -> dict | None:
    """``{p: [∂φ_i/∂p]}`` of a simple closed-form mode's mass-normalised shape, or None (too long, numeric)."""
    if not mode.exact or not mode.shapes:
        return None
    shape = [as_sympy(c) for c in mode.shapes[0]]
    if any(c.is_Float for c in shape) or any(sp.count_ops(c) > MAX_SHAPE_OPS for c in shape):
        return None
    norm2 = sp.Add(*[m * c**2 for m, c in zip(model.masses, shape)])
    try:
        weighted = [value(sp.sqrt(m) * c, subs) for m, c in zip(model.masses, shape)]
    except NotAccurate:
        return None
    big = max(range(len(shape)), key=lambda i: abs(weighted[i]))
    sign = -1 if weighted[big] < 0 else 1
    phi = [sign * c / sp.sqrt(norm2) for c in shape]
    out = {}
    for p in parameters:
        comps = []
        for c in phi:
            d = _simplify(sp.diff(c, model.params[p]))
            if d is None:
                return None
            comps.append(d)
        out[p] = comps
    return out


__all__ = ["ClosedForm", "closed_form_derivatives", "MAX_OPS"]
