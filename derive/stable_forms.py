"""Which closed forms evaluate stably in float64 (no cancellation), so generated code may keep them."""

from __future__ import annotations

import sympy as sp

from .modes import ModeSet


def _sign_coherent(expr: sp.Expr) -> bool:
    """No sum of terms of both signs, no function: evaluates in float64 to a few ulps anywhere."""
    if expr.atoms(sp.Function):
        return False
    for node in sp.preorder_traversal(expr):
        if node.is_Add:
            signs = {t.could_extract_minus_sign() for t in node.args}
            if len(signs) > 1:
                return False
    return True


def _stable(expr) -> sp.Expr | None:
    """A float64-stable form of ``expr`` (itself, or numerator/denominator expanded), or None."""
    if isinstance(expr, int):
        expr = sp.Integer(expr)
    elif isinstance(expr, float):
        expr = sp.Float(expr)
    if expr.is_Number or _sign_coherent(expr):
        return expr
    n, d = sp.fraction(sp.together(expr))
    alt = sp.expand(n) / sp.expand(d)
    return alt if _sign_coherent(alt) else None


def stable_closed_forms(modes: ModeSet):
    """ω² and shape expressions of every mode if all of them evaluate stably in float64, else None.

    Returns
    -------
    (list of Expr, list of tuple of Expr) or None
        One ω² and one shape per independent mode, in the ModeSet's order.
    """
    if not modes.closed_form:
        return None
    w2, shapes = [], []
    for mode in modes.modes:
        for s in mode.shapes:
            e = _stable(mode.omega2)
            cs = [_stable(c) for c in s]
            if e is None or any(c is None for c in cs):
                return None
            w2.append(e)
            shapes.append(tuple(cs))
    return w2, shapes
